"""Building blocks of Fossen's 6-DOF marine-vehicle model, shared by every vessel plant.

Conventions (Fossen, *Handbook of Marine Craft Hydrodynamics and Motion Control*, 2011):

* absolute frame NED (x north, y east, z **down**); body frame x forward, y starboard, z down;
* generalised position ``η = [x, y, z, φ, θ, ψ]`` (m, rad), body velocity
  ``ν = [u, v, w, p, q, r]`` (m/s, rad/s), generalised force ``τ = [X, Y, Z, K, M, N]`` (N, N·m);
* attitude by zyx Euler angles: ``R(Θ) = R_z(ψ) R_y(θ) R_x(φ)`` maps body vectors to the absolute
  frame (the rotations live in :mod:`jaxsim.core.rotations`, re-exported here), ``ṗ = R ν₁``, ``Θ̇ = T(Θ) ν₂``
  (singular at ``θ = ±90°``); ``η̇ = J(η) ν``;
* dynamics ``M ν̇ + C(ν) ν + D(ν) ν + g(η) = τ`` with ``M = M_RB + M_A`` symmetric positive
  definite, ``C`` from ``M`` by Kirchhoff's equations (:func:`coriolis_from_mass`), ``D`` diagonal
  linear + quadratic damping and ``g`` the restoring forces of weight and buoyancy.

``C(ν)`` built from any symmetric ``M`` is skew-symmetric, so ``νᵀ C(ν) ν = 0``: the Coriolis and
centripetal terms do no work and the kinetic energy ``½ νᵀ M ν`` changes only through ``τ``,
damping and the restoring forces (``g`` derives from the potential :func:`potential_energy`).
All functions are pure, take single (un-batched) arrays and compose with jit/vmap/grad.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.rotations import (  # noqa: F401  (re-exported: marine.rotation_z, marine.skew, ...)
    euler_from_rotation,
    rotation_x,
    rotation_y,
    rotation_z,
    rotation_zyx,
    skew,
)
from jaxsim.core.validation import check_covariance


def course_attitude(velocity: jax.Array, min_speed: Any = 0.0) -> jax.Array:
    """``[0, θ, ψ]`` (rad) of a body with no roll whose x axis points along ``velocity (3,)`` (m/s,
    NED: pitch up > 0).  Where the horizontal speed is at most ``min_speed`` (m/s) the direction is
    ill-defined: ``[0, 0, 0]`` with zero derivatives (finite under ``jvp``/``grad``)."""
    h2 = velocity[0] ** 2 + velocity[1] ** 2
    ok = h2 > jnp.asarray(min_speed) ** 2
    vh = jnp.sqrt(jnp.where(ok, h2, 1.0))
    psi = jnp.where(ok, jnp.arctan2(jnp.where(ok, velocity[1], 0.0), jnp.where(ok, velocity[0], 1.0)), 0.0)
    theta = jnp.where(ok, jnp.arctan2(jnp.where(ok, -velocity[2], 0.0), vh), 0.0)
    return jnp.stack([jnp.zeros_like(psi), theta, psi])


def euler_rate_matrix(euler: jax.Array) -> jax.Array:
    """``T(Θ)`` with ``Θ̇ = T ω`` (body angular velocity ``ω``); singular at ``θ = ±90°``."""
    sphi, cphi = jnp.sin(euler[0]), jnp.cos(euler[0])
    ctheta, ttheta = jnp.cos(euler[1]), jnp.tan(euler[1])
    one, zero = jnp.ones_like(sphi), jnp.zeros_like(sphi)
    return jnp.stack(
        [
            jnp.stack([one, sphi * ttheta, cphi * ttheta]),
            jnp.stack([zero, cphi, -sphi]),
            jnp.stack([zero, sphi / ctheta, cphi / ctheta]),
        ]
    )


def euler_rate_matrix_inverse(euler: jax.Array) -> jax.Array:
    """``T(Θ)⁻¹`` with ``ω = T⁻¹ Θ̇`` (defined everywhere)."""
    sphi, cphi = jnp.sin(euler[0]), jnp.cos(euler[0])
    stheta, ctheta = jnp.sin(euler[1]), jnp.cos(euler[1])
    one, zero = jnp.ones_like(sphi), jnp.zeros_like(sphi)
    return jnp.stack(
        [
            jnp.stack([one, zero, -stheta]),
            jnp.stack([zero, cphi, ctheta * sphi]),
            jnp.stack([zero, -sphi, ctheta * cphi]),
        ]
    )


def kinematics_jacobian(eta: jax.Array) -> jax.Array:
    """``J(η) = blockdiag(R(Θ), T(Θ))`` with ``η̇ = J ν``; ``(6, 6)``."""
    euler = eta[3:6]
    zero = jnp.zeros((3, 3), dtype=jnp.result_type(eta, float))
    return jnp.block([[rotation_zyx(euler), zero], [zero, euler_rate_matrix(euler)]])


def kinematics_jacobian_inverse(eta: jax.Array) -> jax.Array:
    """``J(η)⁻¹ = blockdiag(Rᵀ, T⁻¹)``; ``(6, 6)``."""
    euler = eta[3:6]
    zero = jnp.zeros((3, 3), dtype=jnp.result_type(eta, float))
    return jnp.block([[rotation_zyx(euler).T, zero], [zero, euler_rate_matrix_inverse(euler)]])


def coriolis_from_mass(mass: jax.Array, nu: jax.Array) -> jax.Array:
    """Coriolis–centripetal matrix of a body with (rigid + added) mass matrix ``M (6, 6)``.

    Fossen's velocity-dependent parametrisation (his Theorem 3.2 applied to ``M``)::

        C(ν) = [[ 0₃,        −S(M₁₁ν₁ + M₁₂ν₂)],
                [−S(M₁₁ν₁ + M₁₂ν₂), −S(M₂₁ν₁ + M₂₂ν₂)]]

    Linear in ``M``, so ``C(M_RB + M_A) = C_RB + C_A``; skew-symmetric for every symmetric ``M``.
    """
    m = 0.5 * (mass + mass.T)
    a = m[:3, :3] @ nu[:3] + m[:3, 3:] @ nu[3:]
    b = m[3:, :3] @ nu[:3] + m[3:, 3:] @ nu[3:]
    sa, sb = skew(a), skew(b)
    return jnp.block([[jnp.zeros((3, 3), dtype=sa.dtype), -sa], [-sa, -sb]])


def damping_matrix(d_linear: jax.Array, d_quadratic: jax.Array, nu: jax.Array) -> jax.Array:
    """Diagonal ``D(ν) = diag(d₁ + d₂ |ν|)`` (the paper's ``D_ii = d1_i + d2_i |υ_i|``)."""
    return jnp.diag(d_linear + d_quadratic * jnp.abs(nu))


def restoring_forces(euler: jax.Array, weight: Any, buoyancy: Any, r_g: jax.Array, r_b: jax.Array) -> jax.Array:
    """Restoring forces ``g(η)`` (Fossen eq. 4.6) of weight ``W`` at ``r_g`` and buoyancy ``B`` at
    ``r_b`` (body frame, m, relative to the body origin); ``(6,)`` in N and N·m."""
    rot = rotation_zyx(euler)
    down = jnp.asarray([0.0, 0.0, 1.0], dtype=rot.dtype)
    f_g = rot.T @ (weight * down)  # weight in body axes
    f_b = rot.T @ (-buoyancy * down)  # buoyancy in body axes
    force = f_g + f_b
    moment = jnp.cross(r_g, f_g) + jnp.cross(r_b, f_b)
    return -jnp.concatenate([force, moment])


def potential_energy(eta: jax.Array, weight: Any, buoyancy: Any, r_g: jax.Array, r_b: jax.Array) -> jax.Array:
    """Gravitational + buoyancy potential (J) whose generalised force is :func:`restoring_forces`.

    NED: the height of a point is ``−z``; ``V = −W·z_G + B·z_B`` with ``z_G``, ``z_B`` the depths of
    the centres of gravity and buoyancy.
    """
    rot = rotation_zyx(eta[3:6])
    z_g = eta[2] + (rot @ r_g)[2]
    z_b = eta[2] + (rot @ r_b)[2]
    return -weight * z_g + buoyancy * z_b


def kinetic_energy(mass: jax.Array, nu: jax.Array) -> jax.Array:
    """``½ νᵀ M ν`` (J)."""
    return 0.5 * nu @ mass @ nu


def check_mass_matrix(name: str, mass: Any, *, rtol: float = 1e-10) -> None:
    """Require a symmetric positive-definite ``(6, 6)`` mass matrix; ``ValueError`` naming ``name``.

    Only the shape is checked on tracers (values are unknown under jit/vmap).
    """
    check_covariance(name, mass, 6, rtol=rtol, definite=True)


def unbalanced_forces(
    mass: jax.Array, nu: jax.Array, tau: jax.Array, d_linear: jax.Array, d_quadratic: jax.Array, g: jax.Array
) -> jax.Array:
    """``τ − C(ν)ν − D(ν)ν − g`` ``(6,)``: what accelerates the body, ``M ν̇ = unbalanced_forces``."""
    return tau - coriolis_from_mass(mass, nu) @ nu - damping_matrix(d_linear, d_quadratic, nu) @ nu - g


def inverse_dynamics(
    mass: jax.Array,
    d_linear: jax.Array,
    d_quadratic: jax.Array,
    g: jax.Array,
    nu: jax.Array,
    nu_r: jax.Array,
    nu_r_dot: jax.Array,
) -> jax.Array:
    """Computed-torque force ``M ν̇_r + C(ν) ν_r + D(ν) ν_r + g`` (Slotine–Li form); ``(6,)``."""
    return mass @ nu_r_dot + coriolis_from_mass(mass, nu) @ nu_r + damping_matrix(d_linear, d_quadratic, nu) @ nu_r + g
