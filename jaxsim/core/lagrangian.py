"""Equations of motion of rigid-body chains from their energies (Euler–Lagrange by autodiff).

For generalised coordinates ``q (n,)`` and rates ``q̇ (n,)`` with kinetic energy ``T(q, q̇)``,
potential ``V(q)`` and generalised forces ``Q``:

    M(q) q̈ = Q + ∂T/∂q − ∂V/∂q − (∂²T/∂q̇∂q) q̇,        M = ∂²T/∂q̇²

Energies are written from poses: a body's pose ``(R(q), o(q))`` (rotation to world, origin in world)
gives its centre-of-mass velocity and body-frame angular velocity ``ω = vee(Rᵀ Ṙ)`` by one ``jvp``.
This is an independent route to the dynamics a recursive Newton–Euler engine (MuJoCo) computes,
so the two cross-check each other.  Units: SI; gravity along world ``−z``.
"""

from __future__ import annotations

from typing import Callable

import jax
import jax.numpy as jnp

Pose = Callable[[jax.Array], tuple[jax.Array, jax.Array]]  # q -> (R (3, 3), origin (3,))


def rotation(axis, angle: jax.Array) -> jax.Array:
    """Rotation matrix ``(3, 3)`` about the unit ``axis`` by ``angle`` (rad), Rodrigues' formula."""
    k = jnp.asarray(axis, dtype=float)
    k = k / jnp.linalg.norm(k)
    skew = jnp.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return jnp.eye(3) + jnp.sin(angle) * skew + (1.0 - jnp.cos(angle)) * skew @ skew


def body_energy(pose: Pose, mass, com, inertia, gravity: float = 9.81):
    """``(T(q, q̇), V(q))`` of one rigid body.

    ``com (3,)``: centre of mass in the body frame; ``inertia (3,)``: principal moments about the
    centre of mass along the body axes (kg·m²).
    """
    com = jnp.asarray(com, dtype=float)
    inertia = jnp.asarray(inertia, dtype=float)

    def com_world(q):
        rot, origin = pose(q)
        return origin + rot @ com

    def kinetic(q, qd):
        v = jax.jvp(com_world, (q,), (qd,))[1]
        rot, rot_dot = jax.jvp(lambda z: pose(z)[0], (q,), (qd,))
        w = rot.T @ rot_dot  # skew(ω) in the body frame
        omega = jnp.stack([w[2, 1], w[0, 2], w[1, 0]])
        return 0.5 * mass * v @ v + 0.5 * omega @ (inertia * omega)

    def potential(q):
        return mass * gravity * com_world(q)[2]

    return kinetic, potential


def point_force(pose: Pose, point, force_body: jax.Array, q: jax.Array) -> jax.Array:
    """Generalised force ``Jᵀ F`` of a force given in the body frame applied at body ``point``."""
    point = jnp.asarray(point, dtype=float)

    def position(z):
        rot, origin = pose(z)
        return origin + rot @ point

    jac = jax.jacfwd(position)(q)
    return jac.T @ (pose(q)[0] @ force_body)


def euler_lagrange(
    kinetic: Callable[[jax.Array, jax.Array], jax.Array],
    potential: Callable[[jax.Array], jax.Array],
    q: jax.Array,
    qd: jax.Array,
    force: jax.Array,
) -> jax.Array:
    """``q̈`` from the energies and generalised forces (module docstring); shapes ``(n,)``."""
    # forward mode throughout: n is small (a few joints) and it compiles faster than reverse mode
    momentum = jax.jacfwd(kinetic, argnums=1)  # ∂T/∂q̇ (n,)
    mass = jax.jacfwd(momentum, argnums=1)(q, qd)
    mixed = jax.jacfwd(momentum, argnums=0)(q, qd)
    rhs = force + jax.jacfwd(kinetic, argnums=0)(q, qd) - jax.jacfwd(potential)(q) - mixed @ qd
    return jnp.linalg.solve(mass, rhs)
