"""One channel of a gravimeter gimbal stabilised in the horizon plane from INS roll data — indirect
stabilisation, no gyro on the platform (seed 004 #22, Elektropribor; spec part 2 §2.4).

The paper's equations (its ref. [4]) are lost; from its variable list::

    J ω̇ = M_DV − M_TR · sign(ω − θ̇),      φ̇ = ω,      M_DV = k_DV U

``φ`` is the ring's absolute angle (the stabilisation error δ: the horizon is 0), ``ω`` its rate, ``θ``
the ship's roll, ``M_TR`` the dry-friction torque in the gimbal bearing (relative velocity ``ω − θ̇``),
``M_DV`` the motor torque.  Units: rad, rad/s, N·m, kg·m², s.

Dry friction is stepped exactly and event-free by the implicit catch-up scheme of
:mod:`jaxsim.core.dry_friction`: with the friction impulse bound ``b = dt·M_TR/J`` and the free relative
velocity ``s* = ω + dt·M/J − θ̇_next``, the new relative velocity is ``s* − clip(s*, −b, b)`` — zero
(stick) when ``|s*| ≤ b``, else slip with the full friction.  :func:`step` with ``exact=False`` replaces
``clip(s, −b, b)`` by ``b·tanh(s/b)`` (smooth, for gradients; the same scale, no extra parameter).
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.dry_friction import catch_up
from jaxsim.core.dry_friction import friction_impulse as _friction_impulse
from jaxsim.core.pytree import pytree_dataclass
from jaxsim.core.validation import check_positive


@pytree_dataclass
class Params:
    """Ring inertia ``J`` (kg·m²), bearing friction ``M_TR`` (N·m), motor torque limit ``M_max`` (N·m).
    Defaults: the 5 kg relative-gravimeter element (assumed: J = 0.02 kg·m², M_TR = 0.02 N·m,
    M_max = 0.2 N·m); :data:`ABSOLUTE_60KG` for the 60 kg absolute gravimeter."""

    J: Any = 0.02
    M_TR: Any = 0.02
    M_max: Any = 0.2


RELATIVE_5KG = Params()
ABSOLUTE_60KG = Params(J=0.6, M_TR=0.15, M_max=1.5)


def soft_clip(s: jax.Array, b: jax.Array) -> jax.Array:
    """``b·tanh(s/b)``: smooth stand-in for ``clip(s, −b, b)``."""
    return _friction_impulse(s, b, exact=False)


def step(
    p: Params, x: jax.Array, torque: jax.Array, roll_rate_next: jax.Array, dt: float, exact: bool = True
) -> jax.Array:
    """``x = [φ, ω]`` → next state under the motor torque (N·m, held over ``dt``) with the frame turning at
    ``roll_rate_next`` (rad/s) at the end of the step; semi-implicit Euler for ``φ``."""
    check_positive("dt", dt)
    b = dt * p.M_TR / p.J
    s_free = x[1] + dt * torque / p.J - roll_rate_next
    omega = roll_rate_next + catch_up(s_free, b, exact)
    return jnp.stack([x[0] + dt * omega, omega])


def motor_torque(p: Params, demand: jax.Array) -> jax.Array:
    """The demanded torque through the motor's smooth limit ``M_max·tanh(M/M_max)``."""
    return p.M_max * jnp.tanh(demand / p.M_max)


__all__ = ["Params", "RELATIVE_5KG", "ABSOLUTE_60KG", "soft_clip", "step", "motor_torque"]
