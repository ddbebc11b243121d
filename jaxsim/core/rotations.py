"""Rotation matrices of 3-D rigid-body kinematics (zyx Euler angles), shared by plants and estimators.

``R(Θ) = R_z(ψ) R_y(θ) R_x(φ)`` for ``Θ = [φ, θ, ψ]`` (roll, pitch, yaw; rad) maps body-frame vectors
to the absolute frame (Fossen's convention, used by :mod:`jaxsim.plants.marine`).  All functions
are pure, take single (un-batched) arrays and compose with jit/vmap/grad.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp


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
