"""The 3-DOF helicopter stand as an MJCF rigid body, thrust from our motor models.

Same geometry as :mod:`jaxsim.plants.helicopter_3dof` (whose equations come from Euler–Lagrange by
autodiff; MuJoCo's come from its recursive Newton–Euler, so the two cross-check each other): an
``arm`` body on the travel (``z``) and elevation (``−y``) hinges carrying the counterweight, and a
``helicopter`` body on the pitch (``x``) hinge at ``(la, 0, 0)``.  Two site actuators push along the
body's ``z`` axis at ``(0, ±lh, 0)``; their controls are the thrusts ``(F_f, F_b)``, which are motor-lag
states of our code.  State ordering is the ODE's: ``(φ, θ, ψ, φ̇, θ̇, ψ̇, F_f, F_b)``.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxsim.core.system import Plant
from jaxsim.mjx.actuated import actuated_plant
from jaxsim.mjx.plant import mjcf_params
from jaxsim.plants import helicopter_3dof as heli
from jaxsim.plants.helicopter_3dof import HelicopterParams


def helicopter_mjcf(params: HelicopterParams | None = None, timestep: float = 1e-3) -> str:
    """MJCF XML of the stand for the (concrete) ``params``."""
    p = HelicopterParams() if params is None else params
    with jax.ensure_compile_time_eval():  # concrete numbers even when built inside a jit
        heli.validate_params(p)
        d = {k: float(v) if jnp.ndim(v) == 0 else [float(e) for e in v] for k, v in heli.derived(p).items()}
    eps, lh, la = heli.EPS_INERTIA, float(p.lh), float(p.la)
    b_travel, b_elev, b_pitch = d["b"]
    body_i = d["m_h"] * lh**2
    return f"""<mujoco model="helicopter_3dof">
  <compiler angle="radian" autolimits="true"/>
  <option timestep="{timestep!r}" gravity="0 0 {-heli.GRAVITY!r}" integrator="Euler"/>
  <worldbody>
    <body name="arm">
      <joint name="travel" type="hinge" axis="0 0 1" damping="{b_travel!r}"/>
      <joint name="elevation" type="hinge" axis="0 -1 0" damping="{b_elev!r}"/>
      <inertial pos="{-d["lw"]!r} 0 0" mass="{float(p.m_w)!r}" diaginertia="{eps!r} {d["j_arm"]!r} {d["j_arm"]!r}"/>
      <body name="helicopter" pos="{la!r} 0 0">
        <joint name="pitch" type="hinge" axis="1 0 0" damping="{b_pitch!r}"/>
        <inertial pos="0 0 {-float(p.hp)!r}" mass="{d["m_h"]!r}" diaginertia="{body_i!r} {eps!r} {body_i!r}"/>
        <site name="rotor_front" pos="0 {lh!r} 0"/>
        <site name="rotor_back" pos="0 {-lh!r} 0"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <general name="thrust_front" site="rotor_front" gear="0 0 1 0 0 0"/>
    <general name="thrust_back" site="rotor_back" gear="0 0 1 0 0 0"/>
  </actuator>
</mujoco>
"""


def _motor_states(p: HelicopterParams, x_rigid: jax.Array, thrust: jax.Array, u: jax.Array) -> jax.Array:
    return heli.motor_derivatives(p, thrust, u)


def _thrusts(p: HelicopterParams, x_rigid: jax.Array, thrust: jax.Array, u: jax.Array) -> jax.Array:
    return thrust


def helicopter_mjx_plant(
    params: HelicopterParams | None = None, field: str = "forward", timestep: float = 1e-3
) -> Plant:
    """The 3-DOF helicopter with MJX rigid-body physics (8 states in the ODE's order, 2 voltages in,
    outputs ``(travel, elevation, pitch)``)."""
    p = HelicopterParams() if params is None else params
    rigid = mjcf_params(helicopter_mjcf(p, timestep), outputs=heli.OUTPUT_NAMES)
    return actuated_plant(
        rigid, p, _motor_states, _thrusts, n_actuator_states=2, n_inputs=2, field=field, name="helicopter_3dof_mjx"
    )
