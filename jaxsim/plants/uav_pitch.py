"""Longitudinal short-period dynamics of a small UAV with a rate-limited second-order elevator actuator.

Zaitceva (seed 004, #9, lines 10868–10972; spec seed004_part3.md §2.7): the loop is operator → corrective
device → actuator → pitch dynamics of the UAV "Phastball"; the model's values come from the paper's
ref. [1], lost from the text, so every value below is assumed (typical of a 10 kg UAV).

State ``x = [α, q, θ, δ, v]``: angle of attack (rad), pitch rate (rad/s), pitch angle (rad), elevator
deflection (rad, positive nose-up) and the actuator's commanded rate (rad/s).  Input: the elevator
command ``δ_c`` (rad), clipped to ``±delta_max``.  Equations::

    α̇ = Z_α α + q + Z_δ δ          q̇ = M_α α + M_q q + M_δ δ          θ̇ = q
    δ̇ = sat_R(v)                    v̇ = ω_a² (sat_D(δ_c) − δ) − 2 ζ_a ω_a v

``sat_R`` is the rate limit ``R`` (exact clip, or ``R·tanh(v/R)`` — :func:`saturate` with ``smooth``).
"""

from __future__ import annotations

import math
from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.pytree import pytree_dataclass
from jaxsim.core.validation import check_finite, check_positive


@pytree_dataclass
class PitchParams:
    """Short-period derivatives (1/s, 1/s²), actuator ``omega_a`` rad/s, ``zeta_a``, ``rate_limit`` rad/s,
    ``delta_max`` rad.  All assumed (spec §2.7 "Must be assumed": Phastball model, actuator, rate limit)."""

    Z_alpha: Any = -2.0  # 1/s
    Z_delta: Any = -0.2  # 1/s
    M_alpha: Any = -30.0  # 1/s²  (short period ≈ 6 rad/s, ζ ≈ 0.4)
    M_q: Any = -3.0  # 1/s
    M_delta: Any = 40.0  # 1/s², positive: elevator up → nose up
    omega_a: Any = 30.0  # rad/s, actuator bandwidth
    zeta_a: Any = 0.7
    rate_limit: Any = math.radians(60.0)  # spec §2.7: "e.g. 60 °/s"
    delta_max: Any = math.radians(25.0)  # elevator travel


def check_params(p: PitchParams) -> None:
    """``ValueError`` naming the field for a non-finite derivative or a non-positive actuator value."""
    for name in ("Z_alpha", "Z_delta", "M_alpha", "M_q", "M_delta"):
        check_finite(name, getattr(p, name))
    for name in ("omega_a", "zeta_a", "rate_limit", "delta_max"):
        check_positive(name, getattr(p, name))


def saturate(x: jax.Array, limit: jax.Array, smooth: bool = False) -> jax.Array:
    """``clip(x, −limit, limit)``, or ``limit·tanh(x/limit)`` when ``smooth``."""
    return limit * jnp.tanh(x / limit) if smooth else jnp.clip(x, -limit, limit)


def dynamics(p: PitchParams, x: jax.Array, delta_c: jax.Array, smooth: bool = False) -> jax.Array:
    """``ẋ`` (see the module docstring); ``delta_c`` scalar rad; ``smooth``: tanh saturations."""
    alpha, q, _, d, v = x
    dc = saturate(delta_c, p.delta_max, smooth)
    return jnp.stack(
        [
            p.Z_alpha * alpha + q + p.Z_delta * d,
            p.M_alpha * alpha + p.M_q * q + p.M_delta * d,
            q,
            saturate(v, p.rate_limit, smooth),
            p.omega_a**2 * (dc - d) - 2 * p.zeta_a * p.omega_a * v,
        ]
    )


def linear_model(p: PitchParams) -> tuple[jax.Array, jax.Array]:
    """``(A (5,5), B (5,1))`` without the limits (command → state)."""
    a = jnp.array(
        [
            [p.Z_alpha, 1.0, 0.0, p.Z_delta, 0.0],
            [p.M_alpha, p.M_q, 0.0, p.M_delta, 0.0],
            [0.0, 1.0, 0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, 0.0, 1.0],
            [0.0, 0.0, 0.0, -(p.omega_a**2), -2 * p.zeta_a * p.omega_a],
        ]
    )
    return a, jnp.array([[0.0], [0.0], [0.0], [0.0], [p.omega_a**2]])
