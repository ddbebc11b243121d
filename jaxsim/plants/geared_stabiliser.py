"""Geared two-mass stabiliser of an optical unit on a rolling ship, with gear backlash.

Bondarev, Semenov, Antonov (seed 004, #17, lines 3732–3876; spec seed004_part1.md B7): the motor
drives mass 1 (rotor, reduced to the output shaft) through a geared, elastic shaft to mass 2 (the
optical unit); the unit must hold its angle to the horizon while the ship rolls.

State ``x = [θ2, ω2, δ, ω1]``: optical-unit angle to the horizon (rad), its rate (rad/s), the shaft
twist ``δ = θ1 − θ2`` (rad) and the reduced rotor speed in inertial space (rad/s).  Input ``u``:
motor torque reduced to the output shaft (N·m).  The shaft torque is ``M_e = c·DZ(δ)``, ``DZ`` the
dead zone of half-width ``backlash/2`` (the gear's free play; exact), or its smooth surrogate
:func:`smooth_dead_zone` (gradients).  The paper's state holds the elastic torque ``M_e = c·δ``
itself; the twist is the same state for the linear model and keeps the backlash exact.

Disturbance ``d`` (N·m) acts on mass 1 beside ``u``: the constant friction torque (the paper's internal
model: "a constant (dry friction)") plus the gear-rolling torque of the ship's roll ``φ(t)``: the
rotor turns relative to the ship by ``N·(θ1 − φ)``, so its inertial angle is ``N·θ1 − (N − 1)·φ`` and
the reduced equation carries ``J1·(1 − 1/N)·φ̈`` (:func:`roll_torque`).

Defaults: the paper gives only the 1′ backlash; inertias, stiffness and gear ratio are assumed
(``J1 = J2 = 0.05 kg·m²``, ``c`` for a two-mass natural frequency of 5 Hz, ``N = 100``).
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.pytree import pytree_dataclass
from jaxsim.core.validation import check_finite, check_positive

ARCMIN = jnp.pi / (180.0 * 60.0)  # rad
ARCSEC = ARCMIN / 60.0  # rad


@pytree_dataclass
class StabiliserParams:
    """Two-mass geared drive.  ``J1``, ``J2`` kg·m² (rotor reduced to the output, optical unit);
    ``stiffness`` N·m/rad (gear + shaft); ``gear_ratio`` (rotor turns per output turn); ``backlash``
    rad, the total free play (paper: 1′, B7 §1); ``friction`` N·m, constant friction torque on mass 1."""

    J1: Any = 0.05  # assumed (B7 §4 "Assume: J1, J2, stiffness, gear ratio")
    J2: Any = 0.05  # assumed, a small optical unit
    stiffness: Any = 0.05 / 2.0 * (2.0 * jnp.pi * 5.0) ** 2  # assumed: ω0 = √(c(1/J1 + 1/J2)) = 2π·5 rad/s
    gear_ratio: Any = 100.0  # assumed
    backlash: Any = ARCMIN  # paper: 1 arcmin (B7 §1)
    friction: Any = 0.02  # N·m, assumed


def check_params(p: StabiliserParams) -> None:
    """``ValueError`` naming the field for non-positive inertias/stiffness, gear ratio < 1, negative backlash."""
    for name in ("J1", "J2", "stiffness"):
        check_positive(name, getattr(p, name))
    check_finite("friction", p.friction)
    if float(p.gear_ratio) < 1.0:
        raise ValueError(f"gear_ratio: must be ≥ 1, got {p.gear_ratio!r}")
    if not float(p.backlash) >= 0.0:
        raise ValueError(f"backlash: must be ≥ 0 rad, got {p.backlash!r}")


def natural_frequency(p: StabiliserParams) -> jax.Array:
    """``ω0 = √(c·(1/J1 + 1/J2))`` rad/s, the two-mass resonance (the paper's loop bandwidth)."""
    return jnp.sqrt(p.stiffness * (1.0 / p.J1 + 1.0 / p.J2))


def dead_zone(z: jax.Array, half_width: jax.Array) -> jax.Array:
    """Exact dead zone ``z − clip(z, −h, h)``."""
    return z - jnp.clip(z, -half_width, half_width)


def smooth_dead_zone(z: jax.Array, half_width: jax.Array, eps: jax.Array) -> jax.Array:
    """``ε·softplus((z − h)/ε) − ε·softplus((−z − h)/ε)``: smooth, odd, → :func:`dead_zone` as ``ε → 0``
    (error ≤ ``ε·ln 2``, at ``|z| = h``)."""
    return eps * (jax.nn.softplus((z - half_width) / eps) - jax.nn.softplus((-z - half_width) / eps))


def shaft_torque(p: StabiliserParams, twist: jax.Array, eps: jax.Array | None = None) -> jax.Array:
    """``M_e = c·DZ(δ)`` N·m; exact dead zone when ``eps`` is ``None`` or ``0`` (a traced ``eps`` selects at
    run time, so one compiled loop serves both), else the smooth one (``eps`` rad)."""
    h = 0.5 * p.backlash
    if eps is None:
        return p.stiffness * dead_zone(twist, h)
    smooth = smooth_dead_zone(twist, h, jnp.maximum(eps, 1e-12))
    return p.stiffness * jnp.where(eps > 0, smooth, dead_zone(twist, h))


def dynamics(p: StabiliserParams, x: jax.Array, u: jax.Array, d: jax.Array, eps: jax.Array | None = None) -> jax.Array:
    """``θ̇2 = ω2``, ``J2·ω̇2 = M_e``, ``δ̇ = ω1 − ω2``, ``J1·ω̇1 = u − M_e + d`` (``u``, ``d`` scalars, N·m)."""
    m_e = shaft_torque(p, x[2], eps)
    return jnp.stack([x[1], m_e / p.J2, x[3] - x[1], (u - m_e + d) / p.J1])


def linear_model(p: StabiliserParams) -> tuple[jax.Array, jax.Array, jax.Array]:
    """``(A (4,4), B (4,1), C (1,4))`` of the backlash-free plant (``M_e = c·δ``); ``d`` enters through ``B``;
    the measured output is ``θ2``."""
    c = p.stiffness
    a = jnp.array(
        [
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, c / p.J2, 0.0],
            [0.0, -1.0, 0.0, 1.0],
            [0.0, 0.0, -c / p.J1, 0.0],
        ]
    )
    b = jnp.array([[0.0], [0.0], [0.0], [1.0 / p.J1]])
    return a, b, jnp.array([[1.0, 0.0, 0.0, 0.0]])


def roll_torque(p: StabiliserParams, amplitude: jax.Array, omega: jax.Array, t: jax.Array) -> jax.Array:
    """Gear-rolling torque ``J1·(1 − 1/N)·φ̈`` N·m of the roll ``φ = amplitude·sin(ω t)`` (rad, rad/s)."""
    return -p.J1 * (1.0 - 1.0 / p.gear_ratio) * amplitude * omega**2 * jnp.sin(omega * t)


def disturbance(p: StabiliserParams, amplitude: jax.Array, omega: jax.Array, t: jax.Array) -> jax.Array:
    """Total disturbance torque on mass 1: the constant friction torque plus :func:`roll_torque`."""
    return p.friction + roll_torque(p, amplitude, omega, t)
