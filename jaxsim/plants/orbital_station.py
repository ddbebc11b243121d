"""Rigid orbital station: attitude relative to the orbital frame, gravity-gradient torque, reaction jets
(seed 004 #5, Prutko & Atroshenkov; spec seed004_part2.md §2.6).

Frames: orbital (LVLH) frame ``O`` — x along track, y opposite the orbit normal, z to nadir; it rotates
at the orbit rate ``n`` about its −y axis, so its inertial rate in ``O`` axes is ``ω_O = [0, −n, 0]``.
State ``x = [q (4), ω (3)]`` (shape ``(7,)``): ``q = [w, x, y, z]`` the unit quaternion of the body
attitude in ``O`` (body → orbital), ``ω`` the body's *inertial* angular rate in body axes (rad/s).
Dynamics (circular orbit)::

    q̇ = ½ q ⊗ [0, ω − C ω_O],        C = C_bo = R(q)ᵀ (orbital → body)
    J ω̇ = −ω × Jω + 3n² c × Jc + u,  c = C·[0, 0, 1] (nadir in body axes)

``u`` (N·m, shape ``(3,)``) is the jets' torque.  The paper gives no mass data ("as required"): the
defaults are public order-of-magnitude ISS values (assumed, named below).  Fuel of a torque history is
``∫ Σ_i |u_i| dt / (arm · Isp · g0)`` (one jet couple per axis acting at ``arm``).

Time is also used nondimensionally by the optimal-control problems: ``τ = t/T``, ``Ω = ω T``,
``ũ = u T²/J_ref`` (:func:`scaled_rhs`).
"""

from __future__ import annotations

from dataclasses import dataclass

import jax
import jax.numpy as jnp

from jaxsim.core.rotations import quat_mul

__all__ = [
    "StationParams",
    "dcm",
    "fuel_kg",
    "nadir_body",
    "orbit_rate_body",
    "quat_mul",
    "rhs",
    "scaled_rhs",
    "rest_state",
]

G0 = 9.80665  # m/s²


@dataclass(frozen=True)
class StationParams:
    """Station parameters (SI).  All assumed: the paper omits them."""

    inertia: tuple[float, float, float] = (1.02e8, 0.91e8, 1.63e8)  # kg·m², principal; ISS order (assumed)
    orbit_rate: float = 2.0 * jnp.pi / 5556.0  # rad/s; ≈ 400 km circular orbit, 92.6 min (assumed)
    arm: float = 15.0  # m, jet moment arm (Service-module size, assumed)
    isp: float = 280.0  # s, bipropellant jets (assumed)


def dcm(q: jax.Array) -> jax.Array:
    """``R(q)`` (3, 3): body → orbital rotation matrix of a unit quaternion ``[w, x, y, z]`` — the
    polynomial form without normalisation (unlike :func:`jaxsim.core.rotations.rotation_from_quat`), as
    the CasADi model writes it, so both agree to rounding off the unit sphere (inside RK4 stages)."""
    w, x, y, z = q[0], q[1], q[2], q[3]
    return jnp.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def nadir_body(q: jax.Array) -> jax.Array:
    """Nadir unit vector in body axes, ``(3,)``."""
    return dcm(q).T @ jnp.array([0.0, 0.0, 1.0])


def orbit_rate_body(q: jax.Array, n: float) -> jax.Array:
    """The orbital frame's inertial rate ``[0, −n, 0]`` in body axes (rad/s), ``(3,)``."""
    return dcm(q).T @ jnp.array([0.0, -n, 0.0])


def _rhs(x: jax.Array, u: jax.Array, inertia: jax.Array, n: float) -> jax.Array:
    q, w = x[:4], x[4:]
    rel = w - orbit_rate_body(q, n)
    qdot = 0.5 * quat_mul(q, jnp.concatenate([jnp.zeros(1), rel]))
    c = nadir_body(q)
    jw = inertia * w
    wdot = (-jnp.cross(w, jw) + 3.0 * n * n * jnp.cross(c, inertia * c) + u) / inertia
    return jnp.concatenate([qdot, wdot])


def rhs(x: jax.Array, u: jax.Array, p: StationParams = StationParams()) -> jax.Array:
    """``ẋ`` (7,) of state ``x`` (7,) under torque ``u`` (3,) N·m, SI time."""
    return _rhs(x, u, jnp.asarray(p.inertia), p.orbit_rate)


def scaled_rhs(x: jax.Array, u: jax.Array, p: StationParams, horizon: float) -> jax.Array:
    """``dx/dτ`` of the scaled state ``[q, Ω = ωT]`` under scaled torque ``ũ = u T²/J_ref``, ``τ = t/T``;
    ``J_ref = J_z`` (so ``J̃ = J/J_z``), ``T = horizon`` s."""
    inertia = jnp.asarray(p.inertia)
    return _rhs(x, u, inertia / inertia[2], p.orbit_rate * horizon)


def rest_state(q: jax.Array, p: StationParams = StationParams()) -> jax.Array:
    """State (7,) at attitude ``q`` held fixed in the orbital frame (relative rate zero)."""
    q = jnp.asarray(q, float)
    return jnp.concatenate([q, orbit_rate_body(q, p.orbit_rate)])


def fuel_kg(torque_impulse: jax.Array, p: StationParams = StationParams()) -> jax.Array:
    """Propellant (kg) for ``∫ Σ|u_i| dt`` (N·m·s): one jet couple per axis at ``arm``, ``Isp``."""
    return torque_impulse / (p.arm * p.isp * G0)
