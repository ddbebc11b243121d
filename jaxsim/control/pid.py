"""Discrete PID controller in parallel form with derivative filter, saturation and anti-windup.

``u = sat(kp·e + z + kd·D)``, ``e = r − y``, where

* ``z`` is the integral term in output units, integrated by forward Euler at the controller period
  ``Ts`` (``u_k`` uses the errors up to ``k−1``), so the sampled loop keeps the continuous loop's
  steady-state errors exactly;
* ``D`` is ``s/(tf·s + 1)`` applied to ``e`` (or to ``−y`` with ``derivative_on="measurement"``),
  discretised by backward Euler; ``tf = 0`` gives the plain backward difference; the first tick
  sees no derivative kick (the previous error is initialised to the first one);
* ``sat`` clips to ``[u_min, u_max]``;
* anti-windup: ``"none"``; ``"clamping"`` (conditional integration: the integral freezes while the
  output is saturated and the error pushes further into saturation); ``"back_calculation"``
  (``ż = ki·e + (u − v)/tt``, tracking time constant ``tt``, default ``kp/ki``).

Gains may be scalars or ``(k,)`` arrays (one loop per channel).  Units: ``kp`` output unit per error
unit, ``ki`` per second, ``kd`` times seconds; ``tf``, ``tt`` in seconds.
"""

from __future__ import annotations

from typing import Any, Literal, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.pytree import pytree_dataclass, static_field
from jaxsim.core.system import Controller
from jaxsim.core.validation import check_finite, check_positive

AntiWindup = Literal["none", "clamping", "back_calculation"]


@pytree_dataclass
class PIDParams:
    """Gains and limits of :func:`pid` (see module docstring for units)."""

    kp: Any = 1.0
    ki: Any = 0.0
    kd: Any = 0.0
    tf: Any = 0.0
    u_min: Any = -jnp.inf
    u_max: Any = jnp.inf
    tt: Any = None
    anti_windup: AntiWindup = static_field(default="clamping")
    derivative_on: Literal["error", "measurement"] = static_field(default="error")


class PIDState(NamedTuple):
    integral: jax.Array
    deriv: jax.Array
    prev: jax.Array


def _deriv_signal(p: PIDParams, r: jax.Array, y: jax.Array) -> jax.Array:
    return r - y if p.derivative_on == "error" else -y


def pid_init(p: PIDParams, r0: jax.Array, y0: jax.Array) -> PIDState:
    e0 = jnp.broadcast_to(r0 - y0, jnp.broadcast_shapes(jnp.shape(r0 - y0), jnp.shape(p.kp)))
    zero = jnp.zeros_like(e0 * 1.0)
    return PIDState(integral=zero, deriv=zero, prev=zero + _deriv_signal(p, r0, y0))


def pid_step(
    p: PIDParams, s: PIDState, r: jax.Array, y: jax.Array, ts: jax.Array, t: Any = None
) -> tuple[PIDState, jax.Array]:
    """One controller tick of period ``ts`` (s) at tick time ``t`` (s; unused: the law is
    time-invariant); returns the new state and the saturated output."""
    e = r - y
    sig = _deriv_signal(p, r, y)
    deriv = (p.tf * s.deriv + (sig - s.prev)) / (p.tf + ts)
    v = p.kp * e + s.integral + p.kd * deriv
    u = jnp.clip(v, p.u_min, p.u_max)
    if p.anti_windup == "none":
        dz = p.ki * e
    elif p.anti_windup == "clamping":
        pushing = (v != u) & (jnp.sign(p.ki * e) == jnp.sign(v - u))
        dz = jnp.where(pushing, 0.0, p.ki * e)
    elif p.anti_windup == "back_calculation":
        tt = jnp.where(p.ki != 0, p.kp / jnp.where(p.ki != 0, p.ki, 1.0), 1.0) if p.tt is None else p.tt
        dz = p.ki * e + (u - v) / tt
    else:
        raise ValueError(f"anti_windup: unknown mode {p.anti_windup!r}")
    new = PIDState(integral=s.integral + ts * dz, deriv=deriv, prev=sig)
    return new, u


def validate_pid(p: PIDParams) -> None:
    for name in ("kp", "ki", "kd"):
        check_finite(name, getattr(p, name))
    check_positive("tf", p.tf, allow_zero=True)
    if p.tt is not None:
        check_positive("tt", p.tt)
    if p.anti_windup not in ("none", "clamping", "back_calculation"):
        raise ValueError(f"anti_windup: must be 'none', 'clamping' or 'back_calculation', got {p.anti_windup!r}")
    if p.derivative_on not in ("error", "measurement"):
        raise ValueError(f"derivative_on: must be 'error' or 'measurement', got {p.derivative_on!r}")
    lo, hi = np.asarray(p.u_min, float), np.asarray(p.u_max, float)
    if np.any(np.isnan(lo)) or np.any(np.isnan(hi)) or np.any(lo >= hi):
        raise ValueError(f"u_min/u_max: need u_min < u_max, got u_min={p.u_min!r}, u_max={p.u_max!r}")


def pid(params: PIDParams | None = None, **kwargs: Any) -> Controller:
    """A PID :class:`~jaxsim.core.system.Controller`; gains as ``PIDParams`` or keyword arguments."""
    p = params if params is not None else PIDParams(**kwargs)
    validate_pid(p)
    return Controller(p, pid_init, pid_step, name="pid")


def pid_transfer_function(kp: float, ki: float, kd: float, tf: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Continuous ``C(s) = kp + ki/s + kd s/(tf s + 1)`` as ``(num, den)``, descending powers.

    Terms whose gain is exactly zero are dropped from the structure (a P controller is ``[kp]/[1]``).
    """
    if ki == 0 and kd == 0:
        return np.array([kp], float), np.array([1.0])
    if kd == 0:
        return np.array([kp, ki], float), np.array([1.0, 0.0])
    if ki == 0:
        return np.array([kp * tf + kd, kp], float), np.array([tf, 1.0])
    return np.array([kp * tf + kd, kp + ki * tf, ki], float), np.array([tf, 1.0, 0.0])
