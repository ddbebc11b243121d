"""Rotations of 3-D rigid-body kinematics (zyx Euler angles and quaternions), shared by plants,
estimators and inertial kernels.

``R(Θ) = R_z(ψ) R_y(θ) R_x(φ)`` for ``Θ = [φ, θ, ψ]`` (roll, pitch, yaw; rad) maps body-frame vectors
to the absolute frame (Fossen's convention, used by :mod:`jaxsim.plants.marine`).  All functions
are pure, take single (un-batched) arrays and compose with jit/vmap/grad.

Quaternions are ``[w, x, y, z]`` (Hamilton product), body-to-reference: ``v_ref = R(q) v_body``
with ``R(q)`` from :func:`rotation_from_quat`; the kinematics ``q̇ = ½ q ⊗ [0, ω]`` for the body rate
``ω`` (body frame) is :func:`quat_kinematics`.  The quaternion functions broadcast over leading axes.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp


def wrap_angle(a: jax.Array) -> jax.Array:
    """Angle(s) wrapped to (−π, π] (rad); an angle already in range is returned unchanged (bit for bit)."""
    return jnp.where((a > -jnp.pi) & (a <= jnp.pi), a, jnp.pi - jnp.mod(jnp.pi - a, 2.0 * jnp.pi))


def skew(v: jax.Array) -> jax.Array:
    """Cross-product matrix ``S(v)`` with ``S(v) w = v × w``; ``v`` shape ``(3,)``."""
    x, y, z = v[0], v[1], v[2]
    zero = jnp.zeros_like(x)
    return jnp.stack([jnp.stack([zero, -z, y]), jnp.stack([z, zero, -x]), jnp.stack([-y, x, zero])])


def rotation_x(phi: jax.Array) -> jax.Array:
    """Elementary rotation about x by ``phi`` (rad), ``(3, 3)``."""
    c, s = jnp.cos(phi), jnp.sin(phi)
    one, zero = jnp.ones_like(c), jnp.zeros_like(c)
    return jnp.stack([jnp.stack([one, zero, zero]), jnp.stack([zero, c, -s]), jnp.stack([zero, s, c])])


def rotation_y(theta: jax.Array) -> jax.Array:
    """Elementary rotation about y by ``theta`` (rad), ``(3, 3)``."""
    c, s = jnp.cos(theta), jnp.sin(theta)
    one, zero = jnp.ones_like(c), jnp.zeros_like(c)
    return jnp.stack([jnp.stack([c, zero, s]), jnp.stack([zero, one, zero]), jnp.stack([-s, zero, c])])


def rotation_z(psi: jax.Array) -> jax.Array:
    """Elementary rotation about z by ``psi`` (rad), ``(3, 3)``."""
    c, s = jnp.cos(psi), jnp.sin(psi)
    one, zero = jnp.ones_like(c), jnp.zeros_like(c)
    return jnp.stack([jnp.stack([c, -s, zero]), jnp.stack([s, c, zero]), jnp.stack([zero, zero, one])])


def rotation_zyx(euler: jax.Array) -> jax.Array:
    """Body-to-absolute rotation ``R_z(ψ) R_y(θ) R_x(φ)`` for ``euler = [φ, θ, ψ]`` (rad)."""
    return rotation_z(euler[2]) @ rotation_y(euler[1]) @ rotation_x(euler[0])


def euler_from_rotation(rot: jax.Array) -> jax.Array:
    """``[φ, θ, ψ]`` of a zyx rotation matrix (inverse of :func:`rotation_zyx` for ``|θ| < 90°``)."""
    phi = jnp.arctan2(rot[2, 1], rot[2, 2])
    theta = -jnp.arcsin(jnp.clip(rot[2, 0], -1.0, 1.0))
    psi = jnp.arctan2(rot[1, 0], rot[0, 0])
    return jnp.stack([phi, theta, psi])


def quat_mul(p: jax.Array, q: jax.Array) -> jax.Array:
    """Hamilton product ``p ⊗ q`` of ``[w, x, y, z]`` quaternions."""
    pw, pv = p[..., 0], p[..., 1:]
    qw, qv = q[..., 0], q[..., 1:]
    w = pw * qw - jnp.sum(pv * qv, axis=-1)
    v = pw[..., None] * qv + qw[..., None] * pv + jnp.cross(pv, qv)
    return jnp.concatenate([w[..., None], v], axis=-1)


def quat_exp(phi: jax.Array) -> jax.Array:
    """Unit quaternion of the rotation vector ``phi (..., 3)`` (rad); exact, smooth at 0."""
    angle2 = jnp.sum(phi * phi, axis=-1, keepdims=True)
    angle = jnp.sqrt(jnp.where(angle2 > 0, angle2, 1.0))
    half = 0.5 * angle
    # sin(|φ|/2)/|φ| with its series near 0
    k = jnp.where(angle2 > 1e-8, jnp.sin(half) / angle, 0.5 - angle2 / 48.0)
    w = jnp.where(angle2 > 1e-8, jnp.cos(half), 1.0 - angle2 / 8.0)
    return jnp.concatenate([w, k * phi], axis=-1)


def quat_rotation_vector(q: jax.Array) -> jax.Array:
    """Rotation vector (rad) of a unit quaternion (the shorter rotation)."""
    q = jnp.where(q[..., :1] < 0, -q, q)
    v = q[..., 1:]
    s = jnp.linalg.norm(v, axis=-1, keepdims=True)
    angle = 2.0 * jnp.arctan2(s, q[..., :1])
    return jnp.where(s > 1e-12, angle / jnp.where(s > 1e-12, s, 1.0), 2.0) * v


def rotation_from_quat(q: jax.Array) -> jax.Array:
    """Rotation matrix ``R (3, 3)`` (body → reference) of a quaternion ``q (4,)``; ``q`` is normalised
    first, so a state that drifted off the unit sphere still gives a rotation."""
    w, x, y, z = q / jnp.linalg.norm(q)
    return jnp.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def quat_kinematics(q: jax.Array, omega: jax.Array) -> jax.Array:
    """``q̇ = ½ q ⊗ [0, ω]`` (``(4,)``) for the body rate ``omega (3,)`` (rad/s, body frame)."""
    return 0.5 * quat_mul(q, jnp.concatenate([jnp.zeros(1, omega.dtype), omega]))
