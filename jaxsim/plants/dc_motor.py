"""DC motor, armature voltage to shaft angle: ``θ(s)/V(s) = K / (s (T s + 1))``.

State ``x = [θ, ω]`` (rad, rad/s), input ``u = [V]`` (volt; a load torque enters as an equivalent
voltage through the loop's disturbance, ``u − d``), output ``y = [θ]`` (rad).  ``K`` is the no-load
speed per volt (rad/s per V), ``T`` the mechanical time constant (s).  Defaults: a small permanent-
magnet motor (≈ 95 rpm/V, 0.1 s), illustrative values, not from a paper.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.pytree import pytree_dataclass
from jaxsim.core.system import Plant
from jaxsim.core.validation import check_finite, check_positive


@pytree_dataclass
class DCMotorParams:
    """``K`` rad/(V·s), ``T`` s."""

    K: Any = 10.0
    T: Any = 0.1


def dynamics(p: DCMotorParams, x: jax.Array, u: jax.Array, t: jax.Array) -> jax.Array:
    """``θ̇ = ω``, ``T ω̇ = K V − ω``."""
    return jnp.stack([x[1], (p.K * u[0] - x[1]) / p.T])


def output(p: DCMotorParams, x: jax.Array) -> jax.Array:
    """Shaft angle ``θ``, shape ``(1,)``."""
    return x[:1]


def dc_motor(params: DCMotorParams | None = None, **kwargs: Any) -> Plant:
    """The motor as a :class:`~jaxsim.core.system.Plant` (``K``, ``T`` as keyword arguments)."""
    p = params if params is not None else DCMotorParams(**kwargs)
    check_finite("K", p.K)
    check_positive("T", p.T)
    return Plant(p, dynamics, output, n_states=2, n_inputs=1, n_outputs=1, name="dc_motor")
