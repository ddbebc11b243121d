"""The twin-rotor stand (TRMS) as an MJCF rigid body driven by our motor models.

The rigid body — inertia, gravity, viscous friction — is MuJoCo's; the motor lags, rotor moments,
the rotor's gyroscopic moment, dry friction and the cross-reaction torque stay in
:mod:`jaxsim.plants.trms` (:func:`~jaxsim.plants.trms.motor_derivatives`,
:func:`~jaxsim.plants.trms.applied_moments`) and reach MJX as the two actuator torques.

Geometry (one body on two hinges through a common pivot: yaw about the world ``z`` axis, then
pitch about the yawed ``y`` axis).  The ODE model has *constant* inertias ``I1`` (pitch) and ``I2``
(yaw) and no centrifugal coupling; a rigid body has exactly that when its inertia about the pivot
is isotropic, ``I_s·𝟙``.  So the body carries a mass ``m`` whose centre lies ``l`` below the pivot
(gravity moment ``m g l sin ψ = Mg sin ψ``) with a centroidal inertia ``diag(I_s − m l², I_s − m l², I_s)``,
and the rest of each axis's inertia is joint armature: ``I1 − I_s`` on pitch, ``I2 − I_s`` on yaw.
``I_s = ½ min(I1, I2)`` and ``m l² = I_s/4`` (assumed split: only ``Mg``, ``I1``, ``I2`` are known;
the dynamics do not depend on the split).  A body whose yaw inertia varied with pitch would add
``(I_zz − I_xx) sin ψ cos ψ φ̇²`` terms that the manufacturer's model does not have.

State ordering: MJX ``(yaw, pitch, yaw_rate, pitch_rate, τ1, τ2, M_R)`` — qpos follows the joint
order — versus the ODE's ``(pitch, yaw, pitch_rate, yaw_rate, τ1, τ2, M_R)``; :data:`TO_ODE` maps
one to the other (it is its own inverse).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.system import Plant
from jaxsim.mjx.actuated import actuated_plant
from jaxsim.mjx.plant import mjcf_params
from jaxsim.plants import trms
from jaxsim.plants.trms import TRMSParams

GRAVITY = 9.81  # m/s², used only to split Mg into a mass and a lever arm
TO_ODE = np.array([1, 0, 3, 2, 4, 5, 6])  # x_ode = x_mjx[TO_ODE] and x_mjx = x_ode[TO_ODE]
STATE_NAMES = tuple(trms.STATE_NAMES[i] for i in TO_ODE)


def trms_mjcf(params: TRMSParams | None = None, timestep: float = 1e-3) -> str:
    """MJCF XML of the TRMS rigid body for the (concrete) ``params`` (module docstring)."""
    p = trms.FEEDBACK_MANUFACTURER if params is None else params
    trms.validate_params(p)
    i1, i2, mg = float(p.I1), float(p.I2), float(p.Mg)
    if mg <= 0:
        raise ValueError(f"params.Mg: the MJCF model needs a positive gravity moment, got {mg!r}")
    i_s = 0.5 * min(i1, i2)
    m = 4.0 * mg**2 / (i_s * GRAVITY**2)  # so that m l² = I_s / 4
    lever = mg / (m * GRAVITY)
    ixx = i_s - m * lever**2
    return f"""<mujoco model="trms">
  <compiler angle="radian" autolimits="true"/>
  <option timestep="{timestep!r}" gravity="0 0 {-GRAVITY!r}" integrator="Euler"/>
  <worldbody>
    <body name="beam">
      <joint name="yaw" type="hinge" axis="0 0 1" damping="{float(p.B1phi)!r}" armature="{i2 - i_s!r}"/>
      <joint name="pitch" type="hinge" axis="0 1 0" damping="{float(p.B1psi)!r}" armature="{i1 - i_s!r}"/>
      <inertial pos="0 0 {-lever!r}" mass="{m!r}" diaginertia="{ixx!r} {ixx!r} {i_s!r}"/>
    </body>
  </worldbody>
  <actuator>
    <motor name="yaw_moment" joint="yaw"/>
    <motor name="pitch_moment" joint="pitch"/>
  </actuator>
</mujoco>
"""


def ode_state(x_mjx: jax.Array) -> jax.Array:
    """MJX state ordering → ODE state ordering (also the inverse map)."""
    return x_mjx[..., TO_ODE]


def _actuator_states(p: TRMSParams, x_rigid: jax.Array, z: jax.Array, u: jax.Array) -> jax.Array:
    return trms.motor_derivatives(p, ode_state(jnp.concatenate([x_rigid, z])), u)


def _actuator_torques(p: TRMSParams, x_rigid: jax.Array, z: jax.Array, u: jax.Array) -> jax.Array:
    pitch_moment, yaw_moment = trms.applied_moments(p, ode_state(jnp.concatenate([x_rigid, z])))
    return jnp.stack([yaw_moment, pitch_moment])  # actuator order: yaw_moment, pitch_moment


def trms_mjx_plant(params: TRMSParams | None = None, field: str = "forward", timestep: float = 1e-3) -> Plant:
    """The TRMS with MJX rigid-body physics: 7 states (MJX ordering), inputs ``(u1, u2)`` in volts,
    outputs ``(pitch, yaw)`` as in the ODE plant."""
    p = trms.FEEDBACK_MANUFACTURER if params is None else params
    rigid = mjcf_params(trms_mjcf(p, timestep), outputs=("pitch", "yaw"))
    return actuated_plant(
        rigid, p, _actuator_states, _actuator_torques, n_actuator_states=3, n_inputs=2, field=field, name="trms_mjx"
    )
