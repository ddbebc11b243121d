"""Fuzzy P, PI, PD and PID controllers built as channels of static characteristics.

``u = sat(F_p(e) + z + F_d(D))``, ``e = r − y``, with

* ``F_p``, ``F_i``, ``F_d`` any element-wise characteristics: the paper's
  :class:`~.characteristic.ThreeSection` (exact or smooth), a single-input
  :class:`~.inference.FuzzySystem`, or :class:`~.characteristic.Linear` (then the channel is the
  linear PID's); a channel left ``None`` is absent (fuzzy P: ``p`` only; PI: ``p`` and ``i``; …);
* ``z = ∫F_i(e) dt``, integrated by forward Euler at the controller period ``Ts`` (``u_k`` uses the
  errors up to ``k − 1``, as in :mod:`jaxsim.control.pid`, so the sampled loop has the continuous
  loop's steady states exactly);
* ``D`` the filtered derivative ``s/(tf·s + 1)`` of ``e`` (backward Euler; ``tf = 0``: backward
  difference; no kick on the first tick);
* ``sat`` clipping to ``[u_min, u_max]`` with clamping anti-windup (the integral freezes while
  the output is saturated and ``F_i(e)`` pushes further into saturation), or ``"none"``.

The paper does not show how the channels are combined; this parallel sum is the natural reading
(spec §1.2) and the one its steady-state formulas assume.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.pytree import pytree_dataclass, static_field
from jaxsim.core.system import Controller
from jaxsim.core.validation import check_positive


@pytree_dataclass
class FuzzyPIDParams:
    """Channel characteristics (``None``: channel absent), derivative filter ``tf`` (s) and limits."""

    p: Any = None
    i: Any = None
    d: Any = None
    tf: Any = 0.0
    u_min: Any = -jnp.inf
    u_max: Any = jnp.inf
    anti_windup: str = static_field(default="clamping")


class FuzzyPIDState(NamedTuple):
    integral: jax.Array
    deriv: jax.Array
    prev: jax.Array


def _channel(ch: Any, x: jax.Array) -> jax.Array:
    return jnp.zeros_like(x) if ch is None else jnp.reshape(ch(x), jnp.shape(x))


def fuzzy_pid_init(p: FuzzyPIDParams, r0: jax.Array, y0: jax.Array) -> FuzzyPIDState:
    e0 = jnp.asarray(r0 - y0, float)
    zero = jnp.zeros_like(e0)
    return FuzzyPIDState(integral=zero, deriv=zero, prev=e0)


def fuzzy_pid_step(
    p: FuzzyPIDParams, s: FuzzyPIDState, r: jax.Array, y: jax.Array, ts: jax.Array, t: Any = None
) -> tuple[FuzzyPIDState, jax.Array]:
    """One controller tick of period ``ts`` (s) at tick time ``t`` (s; unused); returns the new
    state and the (saturated) output."""
    e = r - y
    deriv = (p.tf * s.deriv + (e - s.prev)) / (p.tf + ts)
    v = _channel(p.p, e) + s.integral + _channel(p.d, deriv)
    u = jnp.clip(v, p.u_min, p.u_max)
    fi = _channel(p.i, e)
    if p.anti_windup == "clamping":
        fi = jnp.where((v != u) & (jnp.sign(fi) == jnp.sign(v - u)), 0.0, fi)
    return FuzzyPIDState(s.integral + ts * fi, deriv, e), u


def fuzzy_pid(
    p: Any = None,
    i: Any = None,
    d: Any = None,
    *,
    tf: Any = 0.0,
    u_min: Any = -jnp.inf,
    u_max: Any = jnp.inf,
    anti_windup: str = "clamping",
) -> Controller:
    """A fuzzy P/PI/PD/PID :class:`~jaxsim.core.system.Controller` from channel characteristics.

    Raises:
        ValueError: no channel given, a channel that is not callable, negative ``tf``,
            ``u_min ≥ u_max``, unknown ``anti_windup``.
    """
    if p is None and i is None and d is None:
        raise ValueError("p/i/d: give at least one channel characteristic")
    for name, ch in (("p", p), ("i", i), ("d", d)):
        if ch is not None and not callable(ch):
            raise ValueError(f"{name}: a channel must be a characteristic u(e) (callable), got {type(ch).__name__}")
    check_positive("tf", tf, allow_zero=True)
    if anti_windup not in ("none", "clamping"):
        raise ValueError(f"anti_windup: must be 'none' or 'clamping', got {anti_windup!r}")
    lo, hi = np.asarray(u_min, float), np.asarray(u_max, float)
    if np.any(np.isnan(lo)) or np.any(np.isnan(hi)) or np.any(lo >= hi):
        raise ValueError(f"u_min/u_max: need u_min < u_max, got u_min={u_min!r}, u_max={u_max!r}")
    params = FuzzyPIDParams(
        p, i, d, jnp.asarray(tf, float), jnp.asarray(u_min, float), jnp.asarray(u_max, float), anti_windup
    )
    return Controller(params, fuzzy_pid_init, fuzzy_pid_step, name="fuzzy_pid")
