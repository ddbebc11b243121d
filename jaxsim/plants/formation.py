"""Leader–follower formation of seed 002: the leader's trajectory, the follower's target point and
the follower's camera.

**Leader** (paper lines 1013–1030): a prescribed kinematic trajectory (no dynamics)::

    t < t_c:  x = x0 + V t,  y = 0,                              z = z0
    t ≥ t_c:  x = x0 + V t,  y = A_y (cos ω_y (t − t_c) − 1),    z = z0 + A_z (1 − cos ω_z (t − t_c))

with ``x0 = 3 m, V = 1.2 m/s, z0 = 1.2 m, t_c = 32 s, A_y = 7.5 m, ω_y = 0.1 rad/s, A_z = 5 m,
ω_z = 0.05 rad/s``; position and velocity are continuous at ``t_c``, the acceleration jumps.  The
leader's longitudinal axis points along the tangent: ``ψ_L = atan2(ẏ, ẋ)``, pitch from the climb
angle, roll 0 (assumed).  Frames are NED (z down, :mod:`jaxsim.plants.marine`).

**Target point** (paper eq. 6): ``X* = p_L + R_z(ψ_L) X_L*`` with the offset ``X_L* = [−1.5, −6, 0]``
given in the leader's *level* frame (origin at the leader, z parallel to the absolute z, rotated
by the leader's yaw only).

**Camera** (10 Hz, paper line 1006): the follower measures the leader's position and yaw relative
to its own level frame FR (origin at the follower, z vertical, x along its heading) and forms the
target point in FR by eq. (6).  Noise model: *pose noise* — white Gaussian noise on the leader's
relative position (``pos_std`` per axis, m) and on its relative yaw (``yaw_std``, rad).  Why not
beacon-pixel noise: the paper gives no intrinsics, resolution, beacon layout or pixel noise, so a
pixel model would rest on half a dozen invented numbers, whereas pose noise needs two, and it is
what a Levenberg–Marquardt PnP solution delivers to the rest of the system (its covariance is
approximately Gaussian for small pixel noise).  The yaw noise matters through the 6.18 m lever arm
of the offset; the leader's roll and pitch do not enter the target point.

The camera sensor (:func:`camera_sensor`) runs every controller tick and returns
``[x_F (12), z_FR (3), frame (1)]``: the follower's inertial state (exact), the camera's target point
and a flag that is 1 on camera frames (every ``camera_period``) and 0 in between.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.pytree import pytree_dataclass, static_field
from jaxsim.core.system import Sensor
from jaxsim.core.validation import check_finite, check_period_multiple, check_positive
from jaxsim.plants.marine import course_attitude, rotation_z

CAMERA_OUTPUTS = 16  # [x_F (12), z_FR (3), frame flag (1)]


@pytree_dataclass
class LeaderParams:
    """The leader's trajectory and the follower's offset (paper lines 1013–1030, 1027)."""

    x0: Any = 3.0  # m
    speed: Any = 1.2  # m/s
    z0: Any = 1.2  # m
    t_curve: Any = 32.0  # s
    y_amp: Any = 7.5  # m
    y_omega: Any = 0.1  # rad/s
    z_amp: Any = 5.0  # m
    z_omega: Any = 0.05  # rad/s
    offset: Any = dataclasses.field(default_factory=lambda: np.array([-1.5, -6.0, 0.0]))  # X_L*, m


def leader_position(p: LeaderParams, t: jax.Array) -> jax.Array:
    """Leader position ``(3,)`` at time ``t`` (s), absolute frame."""
    t = jnp.asarray(t, dtype=float)
    tau = t - p.t_curve  # only used where t ≥ t_c (no kink inside a derivative)
    curved = t >= p.t_curve
    y = jnp.where(curved, p.y_amp * (jnp.cos(p.y_omega * tau) - 1.0), 0.0)
    z = p.z0 + jnp.where(curved, p.z_amp * (1.0 - jnp.cos(p.z_omega * tau)), 0.0)
    return jnp.stack([p.x0 + p.speed * t, y, z])


def leader_velocity(p: LeaderParams, t: jax.Array) -> jax.Array:
    """``ṗ_L`` ``(3,)`` (exact derivative of the active branch)."""
    t = jnp.asarray(t, dtype=float)
    return jax.jvp(lambda s: leader_position(p, s), (t,), (jnp.ones_like(t),))[1]


def leader_euler(p: LeaderParams, t: jax.Array) -> jax.Array:
    """``[φ_L, θ_L, ψ_L]`` with the x axis along the trajectory tangent and no roll."""
    return course_attitude(leader_velocity(p, t))


def target_point(p: LeaderParams, t: jax.Array) -> jax.Array:
    """The follower's target point ``X* = p_L + R_z(ψ_L) X_L*`` ``(3,)`` (paper eq. 6)."""
    psi = leader_euler(p, t)[2]
    return leader_position(p, t) + rotation_z(psi) @ jnp.asarray(p.offset)


def target_motion(p: LeaderParams, t: jax.Array) -> tuple[jax.Array, jax.Array, jax.Array]:
    """Position, velocity and acceleration ``(3,)`` each of the target point at ``t``."""
    t = jnp.asarray(t, dtype=float)
    one = jnp.ones_like(t)

    def pos_vel(s):
        return jax.jvp(lambda r: target_point(p, r), (s,), (jnp.ones_like(s),))

    (x, v), (_, a) = jax.jvp(pos_vel, (t,), (one,))
    return x, v, a


def level_frame_error(target: jax.Array, follower_state: jax.Array) -> jax.Array:
    """Target point relative to the follower in its level frame FR: ``R_z(ψ_F)ᵀ (X* − p_F)``."""
    return rotation_z(follower_state[5]).T @ (target - follower_state[:3])


@pytree_dataclass
class CameraParams:
    """Camera pose noise and the leader it watches."""

    leader: LeaderParams = dataclasses.field(default_factory=LeaderParams)
    pos_std: Any = 0.0  # m, per axis, leader's relative position
    yaw_std: Any = 0.0  # rad, leader's relative yaw
    camera_period: float = static_field(default=0.1)  # s, paper line 1006
    control_period: float = static_field(default=1e-3)  # s, paper line 1007 (prediction period)


def camera_target(params: CameraParams, key: jax.Array, follower_state: jax.Array, t: jax.Array) -> jax.Array:
    """One camera measurement of the target point in the follower's level frame ``(3,)``."""
    lead = params.leader
    k_pos, k_yaw = jax.random.split(key)
    p_l = leader_position(lead, t)
    psi_l = leader_euler(lead, t)[2]
    rel_pos = level_frame_error(p_l, follower_state) + params.pos_std * jax.random.normal(k_pos, (3,))
    rel_yaw = psi_l - follower_state[5] + params.yaw_std * jax.random.normal(k_yaw, ())
    return rotation_z(rel_yaw) @ jnp.asarray(lead.offset) + rel_pos


def camera_measure(params: CameraParams, key: jax.Array, y: jax.Array, t: jax.Array) -> jax.Array:
    """``[x_F (12), z_FR (3), frame]`` for the rollout (``y`` is the follower's state)."""
    every = round(params.camera_period / params.control_period)
    tick = jnp.round(t / params.control_period).astype(jnp.int64)
    frame = (tick % every == 0).astype(y.dtype)
    return jnp.concatenate([y, camera_target(params, key, y, t), frame[None]])


def camera_sensor(
    leader: LeaderParams | None = None,
    pos_std: Any = 0.0,
    yaw_std: Any = 0.0,
    camera_period: float = 0.1,
    control_period: float = 1e-3,
) -> Sensor:
    """The follower's camera + inertial sensor, sampled every controller tick (see module doc).

    Raises ``ValueError`` when ``camera_period`` is not a positive integer multiple of
    ``control_period`` or a noise level is negative.
    """
    check_period_multiple("camera_period", camera_period, control_period, "control_period")
    check_positive("pos_std", pos_std, allow_zero=True)
    check_positive("yaw_std", yaw_std, allow_zero=True)
    lead = LeaderParams() if leader is None else leader
    check_finite("leader", lead)
    params = CameraParams(
        lead,
        jnp.asarray(pos_std, dtype=float),
        jnp.asarray(yaw_std, dtype=float),
        float(camera_period),
        float(control_period),
    )
    return Sensor(params=params, measure=camera_measure, period=None, name="camera")
