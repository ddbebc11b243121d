"""Nonlinear capacitive MEMS accelerometer under vibration (seed 004 #35; spec seed004_part2 §2.7).

Nondimensional equation (1) of the paper (reconstructed in the spec)::

    ẍ + 2εμ ẋ + x + εκ x³ − β [1/(1−x)² − 1/(1+x)²] = F sin Ωt

``x = u/d`` (displacement over the electrode gap, |x| < 1), time in units of ``1/ω_m`` (the
suspension's mechanical natural frequency), ``β = ε_r ε0 S V²/(2 c d³)`` (electrostatic over
elastic force), ``κ`` the cubic suspension stiffness, ``ε`` a small parameter, ``F, Ω`` the vibration
amplitude (acceleration over ``ω_m² d``) and frequency (over ``ω_m``).

The paper prints no numbers (curves only); the defaults below are assumed and named.  Expanding the
symmetric electrostatic term, ``β[…] = 4βx + 8βx³ + 12βx⁵ + …``: the linear frequency is
``ω0 = √(1−4β)`` and the effective cubic coefficient ``εκ − 8β`` (softening when ``8β > εκ``).

Kernels (pure JAX, jit/vmap/grad-able):

* :func:`dynamics` — ``ẋ`` of the state ``[x, ẋ]`` with an input acceleration ``u``;
* :func:`static_force` / :func:`static_stiffness` — ``g(x) = x + εκx³ − β[…]`` and ``g'(x)``: the
  static equilibrium under a constant acceleration ``a`` is ``g(x) = a``;
* :func:`pull_in` — static pull-in point ``g'(x*) = 0`` by bisection on ``x`` and the pull-in
  acceleration ``a* = g(x*)`` (differentiable by the envelope theorem, ``∂a*/∂θ = ∂g/∂θ`` at ``x*``);
* :func:`sweep` — a stepped-sine frequency sweep with state carry-over (jumps, hysteresis), the
  response's Fourier components at ``Ω``, ``3Ω`` and ``Ω/3``; collapse (|x| ≥ ``x_collapse``) freezes
  the state and is flagged;
* :func:`ms_backbone`, :func:`ms_response_branches`, :func:`ms_jump_frequencies` — the first-order
  multiple-scales primary resonance (cubic and quintic terms of the expansion), the self-check.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.pytree import pytree_dataclass
from jaxsim.core.validation import check_int, is_concrete

EPS0 = 8.854e-12  # F/m, vacuum permittivity (paper)


@pytree_dataclass
class Params:
    """Nondimensional parameters of equation (1).  All values assumed (the paper prints none):
    ``eps = 0.1`` (small parameter), ``mu = 0.5`` (damping 2εμ = 0.1, Q = 10, the spec's lower
    range), ``kappa = 1`` (cubic suspension), ``beta = 0.05`` (ω0 = √0.8), ``F = 0.01``, ``Omega = 1``."""

    eps: Any = 0.1
    mu: Any = 0.1
    kappa: Any = 1.0
    beta: Any = 0.1
    F: Any = 0.004
    Omega: Any = 1.0


def validate(p: Params) -> None:
    """ValueError naming the field when a concrete parameter is out of range."""
    for name in ("eps", "mu", "kappa", "F", "Omega"):
        v = getattr(p, name)
        if is_concrete(v) and not np.all(np.isfinite(np.asarray(v))):
            raise ValueError(f"{name}: must be finite, got {v!r}")
    for name in ("eps", "mu", "Omega"):
        v = getattr(p, name)
        if is_concrete(v) and np.any(np.asarray(v) <= 0):
            raise ValueError(f"{name}: must be positive, got {v!r}")
    b = p.beta
    if is_concrete(b) and not (np.all(np.asarray(b) >= 0) and np.all(np.asarray(b) < 0.25)):
        raise ValueError(f"beta: must lie in [0, 0.25) (the origin pulls in at β = 1/4), got {b!r}")


def beta_from_voltage(voltage: Any, area: float, gap: float, stiffness: float, eps_r: float = 1.0) -> Any:
    """``β = ε_r ε0 S V²/(2 c d³)``; ``voltage`` in V, ``area`` S in m², ``gap`` d in m, ``stiffness`` c in N/m."""
    return eps_r * EPS0 * area * jnp.asarray(voltage) ** 2 / (2.0 * stiffness * gap**3)


def voltage_from_beta(beta: Any, area: float, gap: float, stiffness: float, eps_r: float = 1.0) -> Any:
    """Inverse of :func:`beta_from_voltage` (V)."""
    return jnp.sqrt(2.0 * stiffness * gap**3 * jnp.asarray(beta) / (eps_r * EPS0 * area))


def electrostatic(beta: Any, x: Any) -> Any:
    """``β [1/(1−x)² − 1/(1+x)²]`` (the net attraction towards the nearer electrode)."""
    return beta * (1.0 / (1.0 - x) ** 2 - 1.0 / (1.0 + x) ** 2)


def static_force(p: Params, x: Any) -> Any:
    """``g(x) = x + εκx³ − β[…]``: the restoring force; equilibrium under acceleration ``a`` is ``g = a``."""
    return x + p.eps * p.kappa * x**3 - electrostatic(p.beta, x)


def static_stiffness(p: Params, x: Any) -> Any:
    """``g'(x) = 1 + 3εκx² − 2β[1/(1−x)³ + 1/(1+x)³]``."""
    return 1.0 + 3.0 * p.eps * p.kappa * x**2 - 2.0 * p.beta * (1.0 / (1.0 - x) ** 3 + 1.0 / (1.0 + x) ** 3)


def linear_frequency(p: Params) -> Any:
    """``ω0 = √(1 − 4β)`` (small oscillations about x = 0)."""
    return jnp.sqrt(1.0 - 4.0 * p.beta)


def dynamics(p: Params, x: jax.Array, u: jax.Array, t: jax.Array) -> jax.Array:
    """``[ẋ, ẍ]`` of state ``x = [x, ẋ]`` (shape (2,)) under input acceleration ``u`` (shape (1,))."""
    pos, vel = x[0], x[1]
    acc = u[0] - 2.0 * p.eps * p.mu * vel - static_force(p, pos)
    return jnp.stack([vel, acc])


def forced_dynamics(p: Params, t: jax.Array, x: jax.Array) -> jax.Array:
    """Equation (1) with its vibration input ``F sin Ωt`` (vector field ``f(t, x)``)."""
    return dynamics(p, x, jnp.atleast_1d(p.F * jnp.sin(p.Omega * t)), t)


class PullIn(NamedTuple):
    x: jax.Array  # displacement at pull-in (g'(x) = 0), over the gap
    a: jax.Array  # pull-in acceleration a* = g(x*), nondimensional


def pull_in(p: Params, n_iter: int = 60) -> PullIn:
    """Static pull-in ``g'(x*) = 0`` on ``(0, 1)`` by bisection (``n_iter`` halvings), ``a* = g(x*)``.

    ``g'(0) = 1 − 4β > 0`` and ``g' → −∞`` as ``x → 1``; the first sign change is found when ``g'``
    has one root (true for κ ≥ 0 in the range of this study).  ``a*`` is differentiable in the
    parameters: ``x*`` is held (stop_gradient) and ``∂g/∂x = 0`` there (envelope theorem)."""
    n_iter = check_int("n_iter", n_iter)

    def body(_: int, lohi: tuple[jax.Array, jax.Array]) -> tuple[jax.Array, jax.Array]:
        lo, hi = lohi
        mid = 0.5 * (lo + hi)
        pos = static_stiffness(p, mid) > 0
        return jnp.where(pos, mid, lo), jnp.where(pos, hi, mid)

    beta = jnp.asarray(p.beta, dtype=float)
    lo0, hi0 = jnp.zeros_like(beta), jnp.full_like(beta, 1.0 - 1e-9)
    lo, hi = jax.lax.fori_loop(0, n_iter, body, (lo0, hi0))
    xs = jax.lax.stop_gradient(0.5 * (lo + hi))
    return PullIn(xs, static_force(p, xs))


class Sweep(NamedTuple):
    omega: jax.Array  # (n,) sweep frequencies, in sweep order
    amp: jax.Array  # (n,) max |x| over the measured periods
    c1: jax.Array  # (n,) amplitude of the Ω component of x
    c3: jax.Array  # (n,) amplitude of the 3Ω component
    c13: jax.Array  # (n,) amplitude of the Ω/3 component
    collapsed: jax.Array  # (n,) bool: |x| reached x_collapse (state frozen from then on)
    x_end: jax.Array  # (2,) state at the end of the sweep


def sweep(
    p: Params,
    omegas: jax.Array,
    x0: jax.Array,
    n_periods: int = 30,
    n_measure: int = 6,
    steps_per_period: int = 64,
    x_collapse: float = 0.95,
) -> Sweep:
    """Stepped-sine sweep of equation (1) over ``omegas`` (in the order given; reverse it for a down
    sweep), the state carried from one frequency to the next (the forcing phase restarts at 0).

    At each frequency ``n_periods`` periods of ``2π/Ω`` are integrated by RK4 with
    ``steps_per_period`` steps; the last ``n_measure`` (a multiple of 3, for the ``Ω/3`` component)
    are measured.  ``p.Omega`` is ignored.  vmap over ``p`` fields, ``omegas`` or ``x0`` to batch."""
    n_periods = check_int("n_periods", n_periods)
    n_measure = check_int("n_measure", n_measure, high=n_periods)
    steps_per_period = check_int("steps_per_period", steps_per_period, low=8)
    if n_measure % 3:
        raise ValueError(f"n_measure: must be a multiple of 3 (Ω/3 component), got {n_measure}")
    n_tr = (n_periods - n_measure) * steps_per_period
    n_me = n_measure * steps_per_period

    def rk4(f: Any, t: jax.Array, x: jax.Array, h: jax.Array) -> jax.Array:
        k1 = f(t, x)
        k2 = f(t + h / 2, x + h / 2 * k1)
        k3 = f(t + h / 2, x + h / 2 * k2)
        k4 = f(t + h, x + h * k3)
        return x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)

    def one_frequency(carry: tuple[jax.Array, jax.Array], om: jax.Array) -> tuple[Any, Any]:
        x, dead = carry
        h = 2 * jnp.pi / om / steps_per_period

        def f(t: jax.Array, s: jax.Array) -> jax.Array:
            return dynamics(p, s, jnp.atleast_1d(p.F * jnp.sin(om * t)), t)

        def step(c: tuple[jax.Array, jax.Array], k: jax.Array) -> tuple[Any, jax.Array]:
            s, d = c
            s_new = rk4(f, k * h, s, h)
            d_new = d | (jnp.abs(s_new[0]) >= x_collapse) | ~jnp.all(jnp.isfinite(s_new))
            s_new = jnp.where(d_new, s, s_new)  # frozen after collapse
            return (s_new, d_new), s_new[0]

        (x, dead), _ = jax.lax.scan(step, (x, dead), jnp.arange(n_tr, dtype=float))
        (x, dead), xs = jax.lax.scan(step, (x, dead), jnp.arange(n_tr, n_tr + n_me, dtype=float))
        t = (jnp.arange(n_tr, n_tr + n_me, dtype=float) + 1.0) * h

        def comp(w: jax.Array) -> jax.Array:
            return 2.0 * jnp.abs(jnp.mean(xs * jnp.exp(-1j * w * t)))

        out = (jnp.max(jnp.abs(xs)), comp(om), comp(3 * om), comp(om / 3), dead)
        return (x, dead), out

    x0 = jnp.asarray(x0, dtype=float)
    (x_end, _), (amp, c1, c3, c13, dead) = jax.lax.scan(one_frequency, (x0, jnp.array(False)), omegas)
    return Sweep(jnp.asarray(omegas), amp, c1, c3, c13, dead, x_end)


def ms_coefficients(p: Params) -> tuple[Any, Any, Any, Any]:
    """``(ω0, α3, α5, c)``: ``ẍ + cẋ + ω0²x + α3x³ + α5x⁵ = F sin Ωt`` from the expansion of (1)."""
    return linear_frequency(p), p.eps * p.kappa - 8.0 * p.beta, -12.0 * p.beta, 2.0 * p.eps * p.mu


def ms_backbone(p: Params, a: Any) -> Any:
    """First-order multiple-scales backbone ``ω(a) = ω0 + (3α3a²/8 + 5α5a⁴/16)/ω0``."""
    w0, a3, a5, _ = ms_coefficients(p)
    return w0 + (3.0 * a3 * a**2 / 8.0 + 5.0 * a5 * a**4 / 16.0) / w0


def ms_peak_amplitude(p: Params) -> Any:
    """Top of the multiple-scales frequency response ``F/(c ω0)``."""
    w0, _, _, c = ms_coefficients(p)
    return p.F / (c * w0)


def ms_response_branches(p: Params, a: Any) -> tuple[Any, Any]:
    """The two branches ``Ω±(a) = ω(a) ± √((F/(2ω0a))² − (c/2)²)`` of the primary resonance
    (``a`` ≤ :func:`ms_peak_amplitude`); NaN above it."""
    w0, _, _, c = ms_coefficients(p)
    root = jnp.sqrt((p.F / (2.0 * w0 * a)) ** 2 - (c / 2.0) ** 2)
    bb = ms_backbone(p, a)
    return bb - root, bb + root


def ms_jump_frequencies(p: Params, n_grid: int = 20001) -> tuple[float, float]:
    """``(Ω_down, Ω_up)``: the saddle-node frequencies of the multiple-scales response (the down
    sweep jumps at the lower, the up sweep at the upper); ``(nan, nan)`` when the response is single
    valued.  Concrete (NumPy) evaluation on a fine amplitude grid."""
    a_max = float(ms_peak_amplitude(p))
    a = np.linspace(a_max * 1e-3, a_max * (1 - 1e-12), n_grid)
    folds = []
    for br in ms_response_branches(p, jnp.asarray(a)):
        s = np.asarray(br)
        d = np.diff(s)
        k = np.nonzero(np.sign(d[1:]) != np.sign(d[:-1]))[0] + 1
        folds.extend(s[k].tolist())
    if not folds:
        return float("nan"), float("nan")
    return float(min(folds)), float(max(folds))
