"""Steady-state error of the fuzzy-PID paper's loops with fuzzy (or linear) P/PD and PI/PID control.

Loop (spec §1.1): ``e = g − y``, plant input ``u − f``; reference ``g(t) = g + K_g·t`` and
disturbance ``f(t) = f + K_f·t`` (steps plus ramps from t = 0); the controller
``u = F_p(e) + ∫F_i(e)dt + F_d(ė)`` with odd characteristics (:mod:`jaxsim.control.fuzzy.characteristic`:
the three-section ``ThreeSection`` or ``Linear``).  The derivative channel does not act in a steady
state (``ė = 0``, ``F_d(0) = 0``), so PD behaves as P and PID as PI.

Because superposition fails, the error is found from where the operating point lies on the
characteristic (the paper's approach).  A steady state with constant ``e`` requires:

* **static plant** ``K/((T1 s+1)(T2 s+1))``:
  - P/PD: ``e + K·F_p(e) = g + K·f`` (no ramps; with a ramp the error grows without bound).  With the
    three-section ``F_p`` this is equation (1) ``e = g/(1 + K K1) + K f/(1 + K K1)`` on the small-gain
    section, valid for ``g/K + f ≤ a/K + b``; equation (2)
    ``e = g/(1 + K K2) + K f/(1 + K K2) + K (K2 a − b)/(1 + K K2)`` on the large-gain section, valid for
    ``a/K + b ≤ g/K + f ≤ c/K + d``; and ``e = g + K f − K d`` on the saturated section beyond.
  - PI/PID: ``F_i(e) = K_g/K + K_f`` (so ``e = 0`` without ramps);
* **astatic plant** ``K/(s(T s+1))``:
  - P/PD: ``F_p(e) = f + K_g/K`` (no ramp ``f``): ``e = v/K1`` for ``|v| ≤ b``, ``e = a + (v − b)/K2``
    for ``b < |v| < d``; for ``|v| ≥ d`` the controller cannot balance the demand and there is no
    steady state (the error grows; the paper's "—");
  - PI/PID: ``F_i(e) = K_f``.

``F(e) = v`` is solved on the three sections of ``F`` (odd symmetry for ``v < 0``); a linear
characteristic has only the first section, and the results reduce to the paper's Tables 1–2
(:func:`jaxsim.control.steady_state.paper_table_error`).  These closed forms assume the closed loop
converges to its equilibrium (true for the paper's loops; checked by simulation in the tests and the
``fuzzy_pid_accuracy`` study).
"""

from __future__ import annotations

from typing import Any, Literal, NamedTuple

import numpy as np

from jaxsim.control.fuzzy.characteristic import Linear, ThreeSection

PlantKind = Literal["static", "astatic"]

SMALL_GAIN, LARGE_GAIN, SATURATED, NONE = 1, 2, 3, 0


class OperatingPoint(NamedTuple):
    """Analytic steady state of the loop.

    error: ``e(∞)``; ``±inf`` when the error grows without bound (no steady state).
    exists: whether a steady state exists.
    section: section of the deciding characteristic holding the operating point: 1 small gain
        (``|e| ≤ a``), 2 large gain (``a < |e| ≤ c``), 3 saturated (``|e| > c``), 0 none.
    channel: ``"p"`` or ``"i"``: the channel whose characteristic fixes the error.
    demand: the value the characteristic must match (``g/K + f``, ``f + K_g/K``, ``K_g/K + K_f``…).
    equation: ``"(1)"``, ``"(2)"``, ``"saturated"`` (static plant, P/PD), ``"balance"`` (the
        channel's characteristic equals the demand: astatic P/PD, and PI/PID), or ``"none"``.
    """

    error: float
    exists: bool
    section: int
    channel: str
    demand: float
    equation: str


def _breakpoints(char: Any) -> tuple[float, float, float, float]:
    """``(a, b, c, d)`` as floats; a linear characteristic is ``a = c = ∞`` with ``b/a = gain``."""
    if isinstance(char, ThreeSection):
        return float(char.a), float(char.b), float(char.c), float(char.d)
    if isinstance(char, Linear):
        return np.inf, float(char.gain), np.inf, np.inf
    raise ValueError(f"characteristic: expected ThreeSection or Linear, got {type(char).__name__}")


def _gains(char: Any) -> tuple[float, float]:
    if isinstance(char, Linear):
        return float(char.gain), float(char.gain)
    a, b, c, d = _breakpoints(char)
    return b / a, (d - b) / (c - a)


def section_domains(plant: PlantKind, K: float, char: Any) -> tuple[float, float]:
    """Upper bounds of the demand on the small- and large-gain sections of a P controller.

    Static plant: ``(a/K + b, c/K + d)`` for ``g/K + f``; astatic plant: ``(b, d)`` for
    ``f + K_g/K`` (the paper's validity domains of equations (1) and (2)).
    """
    a, b, c, d = _breakpoints(char)
    if isinstance(char, Linear):
        return np.inf, np.inf
    if plant == "static":
        return a / K + b, c / K + d
    if plant == "astatic":
        return b, d
    raise ValueError(f"plant: must be 'static' or 'astatic', got {plant!r}")


def invert_characteristic(char: Any, v: float, channel: str) -> OperatingPoint:
    """Solve ``F(e) = v`` on the sections of ``F`` (odd): the error where a channel outputs ``v``."""
    sgn, x = np.sign(v), abs(v)
    if isinstance(char, Linear):
        k = float(char.gain)
        if k == 0:
            return OperatingPoint(
                float(sgn * np.inf) if x else 0.0,
                x == 0,
                SMALL_GAIN if x == 0 else NONE,
                channel,
                v,
                "balance" if x == 0 else "none",
            )
        return OperatingPoint(v / k, True, SMALL_GAIN, channel, v, "balance")
    a, b, c, d = _breakpoints(char)
    k1, k2 = _gains(char)
    if x <= b:
        return OperatingPoint(float(sgn * x / k1), True, SMALL_GAIN, channel, v, "balance")
    if x < d and k2 > 0:
        return OperatingPoint(float(sgn * (a + (x - b) / k2)), True, LARGE_GAIN, channel, v, "balance")
    return OperatingPoint(float(sgn * np.inf), False, NONE, channel, v, "none")


def _static_p(K: float, char: Any, g: float, f: float) -> OperatingPoint:
    v = g / K + f  # the demand: e/K + F(e) = g/K + f
    sgn, x = np.sign(v), abs(v)
    k1, k2 = _gains(char)
    lim1, lim2 = section_domains("static", K, char)
    gg, ff = sgn * g, sgn * f  # fold to the positive half (odd symmetry)
    if x <= lim1:
        e = gg / (1 + K * k1) + K * ff / (1 + K * k1)  # equation (1)
        return OperatingPoint(float(sgn * e), True, SMALL_GAIN, "p", v, "(1)")
    a, b, c, d = _breakpoints(char)
    if x <= lim2:
        e = gg / (1 + K * k2) + K * ff / (1 + K * k2) + K * (k2 * a - b) / (1 + K * k2)  # equation (2)
        return OperatingPoint(float(sgn * e), True, LARGE_GAIN, "p", v, "(2)")
    e = gg + K * ff - K * d
    return OperatingPoint(float(sgn * e), True, SATURATED, "p", v, "saturated")


def steady_state_error(
    plant: PlantKind,
    K: float,
    p: Any = None,
    i: Any = None,
    *,
    g: float = 0.0,
    g_slope: float = 0.0,
    f: float = 0.0,
    f_slope: float = 0.0,
) -> OperatingPoint:
    """Analytic steady state of the loop with channels ``p`` (P/PD) and optionally ``i`` (PI/PID).

    Args:
        plant: "static" or "astatic"; K: plant gain.
        p, i: ``ThreeSection`` or ``Linear`` characteristics (``i=None``: P/PD controller).
        g, g_slope: reference step and ramp slope (``K_g``); f, f_slope: disturbance step and slope (``K_f``).

    Raises:
        ValueError: unknown plant, non-positive ``K``, a P/PD controller without ``p``, or (static
            plant, P/PD) reference and disturbance ramps that cancel exactly.
    """
    if plant not in ("static", "astatic"):
        raise ValueError(f"plant: must be 'static' or 'astatic', got {plant!r}")
    if not (np.isfinite(K) and K > 0):
        raise ValueError(f"K: must be finite and positive, got {K!r}")
    if i is not None:
        rate = g_slope / K + f_slope if plant == "static" else f_slope
        if rate == 0:
            return OperatingPoint(0.0, True, SMALL_GAIN, "i", 0.0, "balance")
        return invert_characteristic(i, rate, "i")
    if p is None:
        raise ValueError("p: a P/PD controller needs its proportional characteristic")
    if plant == "static":
        if g_slope or f_slope:
            growth = g_slope + K * f_slope
            if growth == 0:
                raise ValueError("g_slope/f_slope: ramps that cancel (K_g + K·K_f = 0) are not covered")
            return OperatingPoint(float(np.sign(growth) * np.inf), False, NONE, "p", np.inf, "none")
        return _static_p(K, p, g, f)
    if f_slope:
        return OperatingPoint(float(np.sign(f_slope) * np.inf), False, NONE, "p", np.inf, "none")
    return invert_characteristic(p, f + g_slope / K, "p")
