"""The AUV's rigid body (seed 002, :mod:`jaxsim.plants.auv`) as an MJCF free body.

MuJoCo does the rigid-body part ``M_R ν̇ + C_R(ν) ν = τ`` and the kinematics (quaternion) only:
added mass, damping and restoring forces are hydrodynamics MuJoCo does not model, so the
comparison is with the ODE AUV with ``M_A = 0``, ``d1 = d2 = 0`` and no restoring moment
(:func:`rigid_body_params`).  The body has ``mass = M_R[0, 0]``, its centre of mass at the body origin
and ``diaginertia = diag(M_R[3:, 3:])`` (the paper's ``M_R`` is diagonal); gravity is off (neutral
buoyancy).  Six site actuators at the body origin apply the body-frame ``τ = (X, Y, Z, K, M, N)``.

MuJoCo's world frame is taken as the AUV's NED frame.  States: the ODE's ``(η, ν)`` =
``(x, y, z, φ, θ, ψ, u, v, w, p, q, r)`` and MJX's ``(pos, quat, R ν_lin, ν_ang)`` (free-joint linear
velocity is in world axes, angular velocity in body axes); :func:`to_mjx_state` and
:func:`from_mjx_state` convert (zyx Euler angles, ``|θ| < 90°``).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.pytree import replace
from jaxsim.core.system import Plant
from jaxsim.mjx.plant import mjcf_plant
from jaxsim.plants import auv, marine
from jaxsim.plants.auv import AUVParams

FORCE_NAMES = ("X", "Y", "Z", "K", "M", "N")


def rigid_body_params(params: AUVParams | None = None) -> AUVParams:
    """``params`` with added mass, damping and restoring forces switched off."""
    p = AUVParams() if params is None else params
    return replace(
        p, M_A=np.zeros((6, 6)), d1=np.zeros(6), d2=np.zeros(6), r_g=np.zeros(3), r_b=np.zeros(3), buoyancy=p.weight
    )


def auv_mjcf(params: AUVParams | None = None, timestep: float = 1e-3) -> str:
    """MJCF XML of the AUV's rigid body (module docstring)."""
    p = AUVParams() if params is None else params
    m_r = np.asarray(p.M_R, dtype=float)
    if not np.allclose(m_r, np.diag(np.diag(m_r))) or not np.allclose(m_r[0, 0], m_r[1:3, 1:3].diagonal()):
        raise ValueError("params.M_R: the MJCF body needs a diagonal M_R with equal translational masses")
    mass, inertia = float(m_r[0, 0]), [float(v) for v in m_r.diagonal()[3:]]
    actuators = "\n".join(
        f'    <general name="{n}" site="origin" gear="{" ".join("1" if j == i else "0" for j in range(6))}"/>'
        for i, n in enumerate(FORCE_NAMES)
    )
    return f"""<mujoco model="auv_rigid_body">
  <option timestep="{timestep!r}" gravity="0 0 0" integrator="Euler"/>
  <worldbody>
    <body name="hull">
      <joint name="hull" type="free"/>
      <inertial pos="0 0 0" mass="{mass!r}" diaginertia="{inertia[0]!r} {inertia[1]!r} {inertia[2]!r}"/>
      <site name="origin"/>
    </body>
  </worldbody>
  <actuator>
{actuators}
  </actuator>
</mujoco>
"""


def auv_mjx_plant(params: AUVParams | None = None, field: str = "forward", timestep: float = 1e-3) -> Plant:
    """The AUV rigid body as an MJCF plant: 13 states (MJX ordering), 6 body-frame forces in."""
    return mjcf_plant(auv_mjcf(params, timestep), outputs=("qpos:hull",), field=field, name="auv_rigid_mjx")


def _quat_from_rotation(rot: jax.Array) -> jax.Array:
    """(w, x, y, z) of a rotation matrix (Shepperd's method, branch on the largest component)."""
    tr = jnp.trace(rot)
    cands = jnp.stack(
        [
            jnp.stack([1 + tr, rot[2, 1] - rot[1, 2], rot[0, 2] - rot[2, 0], rot[1, 0] - rot[0, 1]]),
            jnp.stack([rot[2, 1] - rot[1, 2], 1 + 2 * rot[0, 0] - tr, rot[0, 1] + rot[1, 0], rot[0, 2] + rot[2, 0]]),
            jnp.stack([rot[0, 2] - rot[2, 0], rot[0, 1] + rot[1, 0], 1 + 2 * rot[1, 1] - tr, rot[1, 2] + rot[2, 1]]),
            jnp.stack([rot[1, 0] - rot[0, 1], rot[0, 2] + rot[2, 0], rot[1, 2] + rot[2, 1], 1 + 2 * rot[2, 2] - tr]),
        ]
    )
    best = jnp.argmax(jnp.stack([tr, rot[0, 0], rot[1, 1], rot[2, 2]]))
    q = cands[best]
    return q / jnp.linalg.norm(q) * jnp.sign(jnp.where(q[0] == 0, 1.0, q[0]))


def _rotation_from_quat(q: jax.Array) -> jax.Array:
    w, x, y, z = q / jnp.linalg.norm(q)
    return jnp.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def to_mjx_state(x: jax.Array) -> jax.Array:
    """ODE state ``(η, ν)`` ``(12,)`` → MJX state ``(pos, quat, R ν_lin, ν_ang)`` ``(13,)``."""
    rot = marine.rotation_zyx(x[3:6])
    return jnp.concatenate([x[:3], _quat_from_rotation(rot), rot @ x[6:9], x[9:12]])


def from_mjx_state(x: jax.Array) -> jax.Array:
    """MJX state ``(13,)`` → ODE state ``(η, ν)`` ``(12,)``."""
    rot = _rotation_from_quat(x[3:7])
    return jnp.concatenate([x[:3], marine.euler_from_rotation(rot), rot.T @ x[7:10], x[10:13]])


def ode_rigid_body_plant(params: AUVParams | None = None) -> Plant:
    """The ODE AUV of :mod:`jaxsim.plants.auv` reduced to its rigid body (the comparison partner)."""
    return auv.auv_plant(rigid_body_params(params))
