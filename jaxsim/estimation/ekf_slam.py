"""EKF-SLAM with state augmentation, in static shapes: a vehicle pose and up to ``N`` point landmarks.

The state is ``[pose (3: x, y, θ), landmark 0 (2), …, landmark N−1 (2)]`` with a boolean ``active (N,)``:
a landmark's slot holds zeros (mean, covariance rows and columns) until its first observation
*augments* the state — the landmark is placed by the sensor's inverse model and its covariance and
cross-covariances are those of that placement (``P_ll = Gx P_pp Gxᵀ + Gz R Gzᵀ``, ``P_l· = Gx P_p·``) —
so the state never changes shape under ``jit``/``vmap`` and an inactive slot takes no part in any
update (its ``H`` columns and covariance are zero).  This is the textbook growing-state filter with the
landmarks stored in slot order rather than in order of discovery (the test compares the two).

Data association is by landmark index (the measurement array's row ``j`` belongs to landmark ``j``);
``seen (N,)`` says which rows are present.  A landmark seen for the first time initialises its slot and
is not used for an update at that step (its placement carries no information on the pose).

The sensor is a :class:`LandmarkSensor` of plain functions (``observe``, its inverse ``place``, and the
residual with angle wrapping); :data:`RANGE_BEARING` is the usual range–bearing one.  The motion model is
any ``motion(pose (3,), u) -> pose (3,)`` with process noise on ``u`` (odometry), covariance ``Q_u``;
:func:`unicycle` is the Euler-discretised one.  Jacobians are taken by ``jax.jacfwd``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, NamedTuple

import jax
import jax.numpy as jnp

from jaxsim.core.rotations import wrap_angle
from jaxsim.estimation import kalman
from jaxsim.estimation.types import GaussianState

POSE = 3  # x (m), y (m), heading θ (rad)
LANDMARK = 2  # x, y (m)


class SlamState(NamedTuple):
    """``mean (3 + 2N,)``, ``cov (3 + 2N, 3 + 2N)``, ``active (N,)`` bool: which landmark slots are in the map."""

    mean: jax.Array
    cov: jax.Array
    active: jax.Array


@dataclass(frozen=True)
class LandmarkSensor:
    """``observe(pose (3,), landmark (2,)) -> z (p,)``; ``place(pose, z) -> landmark (2,)`` (the inverse);
    ``residual(z, ẑ) -> (p,)`` (``z − ẑ`` with any angle wrapped to (−π, π])."""

    observe: Callable[[jax.Array, jax.Array], jax.Array]
    place: Callable[[jax.Array, jax.Array], jax.Array]
    residual: Callable[[jax.Array, jax.Array], jax.Array]


def _range_bearing(pose: jax.Array, landmark: jax.Array) -> jax.Array:
    d = landmark - pose[:2]
    return jnp.stack([jnp.sqrt(d @ d), wrap_angle(jnp.arctan2(d[1], d[0]) - pose[2])])


def _place_range_bearing(pose: jax.Array, z: jax.Array) -> jax.Array:
    a = pose[2] + z[1]
    return pose[:2] + z[0] * jnp.stack([jnp.cos(a), jnp.sin(a)])


def _residual_range_bearing(z: jax.Array, z_hat: jax.Array) -> jax.Array:
    return jnp.stack([z[0] - z_hat[0], wrap_angle(z[1] - z_hat[1])])


RANGE_BEARING = LandmarkSensor(_range_bearing, _place_range_bearing, _residual_range_bearing)
"""Range (m) and bearing relative to the heading (rad) to a point landmark."""


def unicycle(pose: jax.Array, u: jax.Array, dt: float) -> jax.Array:
    """One Euler step of the unicycle: ``u = (v m/s, ω rad/s)``, ``dt`` s; heading wrapped."""
    x, y, th = pose
    v, w = u
    return jnp.stack([x + v * dt * jnp.cos(th), y + v * dt * jnp.sin(th), wrap_angle(th + w * dt)])


def slam_init(pose_mean: jax.Array, pose_cov: jax.Array, n_landmarks: int) -> SlamState:
    """An empty map of ``n_landmarks`` slots around a pose ``N(pose_mean (3,), pose_cov (3, 3))``."""
    pose_mean = jnp.asarray(pose_mean, dtype=float)
    pose_cov = jnp.asarray(pose_cov, dtype=float)
    if pose_mean.shape != (POSE,) or pose_cov.shape != (POSE, POSE):
        raise ValueError(f"pose_mean, pose_cov: expected shapes (3,), (3, 3), got {pose_mean.shape}, {pose_cov.shape}")
    if int(n_landmarks) < 1:
        raise ValueError(f"n_landmarks: expected a positive count, got {n_landmarks!r}")
    n = POSE + LANDMARK * int(n_landmarks)
    mean = jnp.zeros(n).at[:POSE].set(pose_mean)
    cov = jnp.zeros((n, n)).at[:POSE, :POSE].set(pose_cov)
    return SlamState(mean, cov, jnp.zeros(int(n_landmarks), dtype=bool))


def slam_predict(
    state: SlamState, motion: Callable[[jax.Array, jax.Array], jax.Array], u: jax.Array, Q_u: jax.Array
) -> SlamState:
    """Move the pose by ``motion(pose, u)`` with noise ``Q_u`` on ``u``; landmarks are static.

    Only the pose rows and columns change (``P_pp ← Fx P_pp Fxᵀ + Gu Q_u Guᵀ``, ``P_p· ← Fx P_p·``): O(N)
    work, not O(N³)."""
    pose = state.mean[:POSE]
    Fx = jax.jacfwd(motion, argnums=0)(pose, u)
    Gu = jax.jacfwd(motion, argnums=1)(pose, u)
    P = state.cov
    rows = Fx @ P[:POSE, :]
    P = P.at[:POSE, :].set(rows).at[:, :POSE].set(rows.T)
    P = P.at[:POSE, :POSE].set(kalman.symmetrize(Fx @ state.cov[:POSE, :POSE] @ Fx.T + Gu @ Q_u @ Gu.T))
    return SlamState(state.mean.at[:POSE].set(motion(pose, u)), P, state.active)


def _slot(j: jax.Array) -> jax.Array:
    return POSE + LANDMARK * j


def slam_augment(state: SlamState, sensor: LandmarkSensor, j: jax.Array, z: jax.Array, R: jax.Array) -> SlamState:
    """Put landmark ``j`` (an inactive slot) into the map from its first observation ``z (p,)``, noise ``R``."""
    pose = state.mean[:POSE]
    lm = sensor.place(pose, z)
    Gx = jax.jacfwd(sensor.place, argnums=0)(pose, z)
    Gz = jax.jacfwd(sensor.place, argnums=1)(pose, z)
    P = state.cov
    cross = Gx @ P[:POSE, :]  # (2, n): the new landmark against the pose and the mapped landmarks
    block = kalman.symmetrize(Gx @ P[:POSE, :POSE] @ Gx.T + Gz @ R @ Gz.T)
    s = _slot(j)
    P = jax.lax.dynamic_update_slice(P, cross, (s, 0))
    P = jax.lax.dynamic_update_slice(P, cross.T, (0, s))
    P = jax.lax.dynamic_update_slice(P, block, (s, s))
    mean = jax.lax.dynamic_update_slice(state.mean, lm, (s,))
    return SlamState(mean, P, state.active.at[j].set(True))


def slam_update(
    state: SlamState, sensor: LandmarkSensor, j: jax.Array, z: jax.Array, R: jax.Array, *, use: jax.Array | bool = True
) -> tuple[SlamState, kalman.Innovation]:
    """EKF update (Joseph form) with observation ``z (p,)`` of mapped landmark ``j``; ``use=False`` leaves
    the state unchanged (a masked update), so it may be traced for every slot."""

    def h(x):
        return sensor.observe(x[:POSE], jax.lax.dynamic_slice(x, (_slot(j),), (LANDMARK,)))

    H = jax.jacfwd(h)(state.mean)
    residual = sensor.residual(z, h(state.mean))
    mask = jnp.broadcast_to(jnp.asarray(use), residual.shape)
    post, innov = kalman.condition(GaussianState(state.mean, state.cov), residual, H, R, mask=mask, form="joseph")
    mean = post.mean.at[2].set(wrap_angle(post.mean[2]))
    return SlamState(mean, post.cov, state.active), innov


def slam_observe(
    state: SlamState, sensor: LandmarkSensor, z: jax.Array, seen: jax.Array, R: jax.Array
) -> tuple[SlamState, jax.Array]:
    """Process one scan ``z (N, p)`` with ``seen (N,)`` bool, landmark by landmark in index order: a seen
    inactive landmark augments the state, a seen active one updates it.  Returns the state and the
    NIS of each landmark's update ``(N,)`` (NaN where there was none)."""

    def one(j, carry):
        st, nis = carry
        zj = jnp.where(seen[j], z[j], jnp.ones_like(z[j]))  # an absent row may hold NaN
        update = seen[j] & st.active[j]
        augment = seen[j] & ~st.active[j]
        upd, innov = slam_update(st, sensor, j, zj, R, use=update)
        aug = slam_augment(st, sensor, j, zj, R)
        st = jax.tree_util.tree_map(lambda a, b: jnp.where(augment, a, b), aug, upd)
        return st, nis.at[j].set(jnp.where(update, innov.nis, jnp.nan))

    n = state.active.shape[0]
    return jax.lax.fori_loop(0, n, one, (state, jnp.full(n, jnp.nan, dtype=state.mean.dtype)))


def pose_nees(state: SlamState, true_pose: jax.Array) -> jax.Array:
    """``eᵀ P_pp⁻¹ e`` of the pose, heading error wrapped (χ²(3) for a consistent filter)."""
    e = true_pose - state.mean[:POSE]
    e = e.at[2].set(wrap_angle(e[2]))
    return e @ jnp.linalg.solve(state.cov[:POSE, :POSE], e)


__all__ = [
    "SlamState",
    "LandmarkSensor",
    "RANGE_BEARING",
    "unicycle",
    "slam_init",
    "slam_predict",
    "slam_augment",
    "slam_update",
    "slam_observe",
    "pose_nees",
]
