"""Tilt-rotor quadcopter (X layout), 6-DOF rigid body with per-rotor tilted thrust and motor failures
(seed 004 part 3, #8 Shavin & Pritykin; spec ``seed004_part3.md`` §2.8).

Frames: world ``z`` up (origin at the take-off point), body ``x`` forward, ``y`` left, ``z`` up.
Rotor ``i`` sits at ``p_i = L·a_i + h·e_z`` (body frame, from the centre of mass) on an arm of azimuth
``ψ_i`` (:data:`ARM_AZIMUTH_DEG`: 1 front-right, 2 rear-right, 3 rear-left, 4 front-left), ``a_i`` the
arm's unit vector.  A servo tilts rotor ``i`` by ``ϑ_i`` about its arm, so its axis is
``d_i = cos ϑ_i·e_z + sin ϑ_i·n_i`` with ``n_i = e_z × a_i``.  Rotor ``i`` at speed ``ω_i`` (rad/s)
gives the thrust ``k_f ω_i² d_i`` and the reaction torque ``σ_i k_m ω_i² d_i`` (``σ = +1`` for the
left-hand propellers 1 and 3, ``−1`` for 2 and 4, as in the paper's figure 1).  A failed rotor
(``alive_i = 0``) gives neither.  Wind enters through a linear drag ``−c_d (v − w)`` on the
translation.

State ``x (13,)``: position ``r`` (m, world), velocity ``v`` (m/s, world), attitude quaternion ``q``
(``[w, x, y, z]``, body → world, :mod:`jaxsim.core.rotations`), body rate ``Ω`` (rad/s, body).
Input ``u (8,)``: rotor speeds ``ω_1..4`` (rad/s) then tilts ``ϑ_1..4`` (rad); servo and motor
dynamics are taken as instantaneous (the paper does not describe them).

The paper prints no parameter: every value in :class:`TiltRotorParams` is assumed (a 1.5 kg
quadcopter with 0.25 m arms; ``h`` the height of the rotor plane above the centre of mass).
"""

from __future__ import annotations

import math
from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.pytree import pytree_dataclass
from jaxsim.core.rotations import quat_kinematics, rotation_from_quat
from jaxsim.core.system import Plant

ARM_AZIMUTH_DEG = (-45.0, -135.0, 135.0, 45.0)
"""Arm azimuths (deg, from body ``x`` towards ``y``) of rotors 1–4: front-right, rear-right,
rear-left, front-left."""

SPIN = (1.0, -1.0, 1.0, -1.0)
"""``σ_i``: sign of rotor ``i``'s reaction torque along its axis (1, 3 left-hand; 2, 4 right-hand)."""

GRAVITY = 9.81  # m/s²


@pytree_dataclass
class TiltRotorParams:
    """Assumed physical parameters (SI units); ``alive (4,)`` masks failed rotors (1 works, 0 failed)."""

    mass: float = 1.5  # kg
    inertia: Any = (0.025, 0.025, 0.045)  # kg·m², principal moments about body x, y, z
    arm: float = 0.25  # m, L
    rotor_height: float = 0.05  # m, h: rotor plane above the centre of mass
    k_thrust: float = 1.5e-5  # N/(rad/s)², k_f
    k_torque: float = 2.5e-7  # N·m/(rad/s)², k_m
    drag: float = 0.3  # N/(m/s), c_d, linear translational drag against the air
    wind: Any = (0.0, 0.0, 0.0)  # m/s, world frame
    alive: Any = (1.0, 1.0, 1.0, 1.0)


def arm_vectors() -> tuple[jax.Array, jax.Array]:
    """``(a, n) (4, 3)``: arm unit vectors and the tilt directions ``n_i = e_z × a_i`` (body frame)."""
    psi = jnp.deg2rad(jnp.asarray(ARM_AZIMUTH_DEG))
    a = jnp.stack([jnp.cos(psi), jnp.sin(psi), jnp.zeros(4)], axis=1)
    n = jnp.stack([-jnp.sin(psi), jnp.cos(psi), jnp.zeros(4)], axis=1)
    return a, n


def rotor_wrench(p: TiltRotorParams, speeds: jax.Array, tilts: jax.Array) -> tuple[jax.Array, jax.Array]:
    """Body-frame force ``(3,)`` (N) and moment about the centre of mass ``(3,)`` (N·m) of the rotors at
    ``speeds (4,)`` (rad/s) and ``tilts (4,)`` (rad)."""
    a, n = arm_vectors()
    axis = jnp.cos(tilts)[:, None] * jnp.array([0.0, 0.0, 1.0]) + jnp.sin(tilts)[:, None] * n
    w2 = jnp.asarray(p.alive) * speeds**2
    thrust = (p.k_thrust * w2)[:, None] * axis
    arm_pos = p.arm * a + jnp.array([0.0, 0.0, p.rotor_height])
    reaction = (jnp.asarray(SPIN) * p.k_torque * w2)[:, None] * axis
    return jnp.sum(thrust, axis=0), jnp.sum(jnp.cross(arm_pos, thrust) + reaction, axis=0)


def dynamics(p: TiltRotorParams, x: jax.Array, u: jax.Array, t: jax.Array) -> jax.Array:
    """``ẋ (13,)`` of the rigid body (Newton–Euler with quaternion kinematics)."""
    v, q, omega = x[3:6], x[6:10], x[10:13]
    force_b, moment_b = rotor_wrench(p, u[:4], u[4:8])
    rot = rotation_from_quat(q)
    accel = (rot @ force_b - p.drag * (v - jnp.asarray(p.wind))) / p.mass - jnp.array([0.0, 0.0, GRAVITY])
    inertia = jnp.asarray(p.inertia)
    omega_dot = (moment_b - jnp.cross(omega, inertia * omega)) / inertia
    return jnp.concatenate([v, accel, quat_kinematics(q, omega), omega_dot])


def tilt_rotor(p: TiltRotorParams | None = None) -> Plant:
    """The plant: full state out (``y = x``), inputs ``[ω_1..4, ϑ_1..4]``."""
    return Plant(
        params=TiltRotorParams() if p is None else p,
        dynamics=dynamics,
        output=lambda p, x: x,
        n_states=13,
        n_inputs=8,
        n_outputs=13,
        name="tilt_rotor",
    )


def energy(p: TiltRotorParams, x: jax.Array) -> jax.Array:
    """Kinetic + potential energy (J); conserved with the rotors off and no drag."""
    inertia = jnp.asarray(p.inertia)
    return 0.5 * p.mass * jnp.sum(x[3:6] ** 2) + 0.5 * jnp.sum(inertia * x[10:13] ** 2) + p.mass * GRAVITY * x[2]


def hover_speed(p: TiltRotorParams, working: int = 4) -> float:
    """Rotor speed (rad/s) at which ``working`` vertical rotors carry the weight."""
    return math.sqrt(p.mass * GRAVITY / (working * p.k_thrust))
