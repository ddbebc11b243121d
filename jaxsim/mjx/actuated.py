"""An MJCF rigid body driven by actuator models written in the toolkit (motor lags, rotor thrust).

MuJoCo does the rigid body; our code keeps the actuator states ``z`` and computes the controls
(generalised forces) that MJX applies.  State ``x = (qpos, qvel, z)``, input ``u`` = whatever the
actuator models take (voltages, ...):

    ż    = actuator_dynamics(actuator_params, x_rigid, z, u)        (k,)
    ctrl = actuator_controls(actuator_params, x_rigid, z, u)        (nu,)  → MJX actuators
    ẋ_rigid = forward_field / step_field of the MJCF model with that ctrl

With ``field="step"`` the rigid part advances by ``mjx.step`` and ``z`` by explicit Euler when the
plant is simulated with ``solver=EULER, dt=opt.timestep``.
"""

from __future__ import annotations

from typing import Any, Callable

import jax
import jax.numpy as jnp

from jaxsim.core.pytree import pytree_dataclass, static_field
from jaxsim.core.system import Plant
from jaxsim.mjx.plant import MJCFParams, check_control, rigid_field
from jaxsim.mjx.plant import output as rigid_output

ActuatorFn = Callable[[Any, jax.Array, jax.Array, jax.Array], jax.Array]


@pytree_dataclass
class ActuatedParams:
    """The MJCF part, the actuator models' params (leaves) and their functions (static)."""

    rigid: MJCFParams
    actuator: Any
    actuator_dynamics: ActuatorFn = static_field()
    actuator_controls: ActuatorFn = static_field()
    n_actuator_states: int = static_field()
    n_inputs: int = static_field()
    field: str = static_field(default="forward")


def split(p: ActuatedParams, x: jax.Array) -> tuple[jax.Array, jax.Array]:
    """``x → (x_rigid (nq + nv,), z (k,))``."""
    n = p.rigid.layout.n_states
    return x[:n], x[n:]


def _check_input(p: ActuatedParams, x: jax.Array, u: jax.Array) -> None:
    n = p.rigid.layout.n_states + p.n_actuator_states
    if jnp.shape(x) != (n,):
        raise ValueError(
            f"x: expected shape ({n},) = rigid (qpos, qvel) + {p.n_actuator_states} actuator "
            f"states, got {tuple(jnp.shape(x))}"
        )
    if jnp.shape(u) != (p.n_inputs,):
        raise ValueError(f"u: expected shape ({p.n_inputs},), got {tuple(jnp.shape(u))}")


def dynamics(p: ActuatedParams, x: jax.Array, u: jax.Array, t: jax.Array) -> jax.Array:
    """``ẋ = (ẋ_rigid, ż)`` (see the module docstring)."""
    _check_input(p, x, u)
    xr, z = split(p, x)
    ctrl = p.actuator_controls(p.actuator, xr, z, u)
    check_control(p.rigid.layout, ctrl)
    dz = p.actuator_dynamics(p.actuator, xr, z, u)
    return jnp.concatenate([rigid_field(p.field)(p.rigid, xr, ctrl, t), dz])


def output(p: ActuatedParams, x: jax.Array) -> jax.Array:
    """The MJCF model's selected outputs."""
    return rigid_output(p.rigid, split(p, x)[0])


def actuated_plant(
    rigid: MJCFParams,
    actuator_params: Any,
    actuator_dynamics: ActuatorFn,
    actuator_controls: ActuatorFn,
    n_actuator_states: int,
    n_inputs: int,
    field: str = "forward",
    name: str = "mjcf_actuated",
) -> Plant:
    """A :class:`Plant` of an MJCF rigid body plus actuator models (module docstring).

    ``actuator_dynamics`` and ``actuator_controls`` should be module-level functions (they are part
    of the jit cache key).
    """
    rigid_field(field)  # validates the name
    if int(n_actuator_states) < 0:
        raise ValueError(f"n_actuator_states: must be >= 0, got {n_actuator_states!r}")
    if int(n_inputs) < 1:
        raise ValueError(f"n_inputs: must be >= 1, got {n_inputs!r}")
    p = ActuatedParams(
        rigid, actuator_params, actuator_dynamics, actuator_controls, int(n_actuator_states), int(n_inputs), field
    )
    lay = rigid.layout
    return Plant(
        p,
        dynamics,
        output,
        n_states=lay.n_states + int(n_actuator_states),
        n_inputs=int(n_inputs),
        n_outputs=lay.n_outputs,
        name=name,
    )
