"""Constant-speed unicycle in a scalar field with disc obstacles (seed 004, #18, Nikolaev/Matveev; spec
seed004_part1.md B8).

Kinematics ``ẋ = v cos ψ``, ``ẏ = v sin ψ``, ``ψ̇ = u``, ``|u| ≤ ū``; :func:`step` advances a pose
``[x, y, ψ]`` (m, m, rad) exactly along the arc of a turn rate held over ``τ``.  The field (spec B8, an
uncertain reconstruction): ``F(r) = (a + b·cos φ)/ρ`` in polar coordinates ``(ρ, φ)``, ``a = 2``,
``b = 0.5``; its isoline ``F = f0 = 1`` is the limaçon ``ρ = a + b cos φ`` (1.5–2.5 m).  Obstacles
(assumed; the paper gives none): discs ``(cx, cy, R)``; :func:`distance` is the distance to the nearest
boundary (negative inside).
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp


def step(pose: jax.Array, u: jax.Array, v: Any, tau: Any) -> jax.Array:
    """Exact pose after ``tau`` s at speed ``v`` m/s and turn rate ``u`` rad/s held (the straight line for
    ``|u·τ| < 1e-9``)."""
    x, y, psi = pose
    dpsi = u * tau
    small = jnp.abs(dpsi) < 1e-9
    safe = jnp.where(small, 1.0, dpsi)
    # chord factors: sin(ψ+Δ) − sin ψ = 2 cos(ψ + Δ/2) sin(Δ/2), etc.
    k = jnp.where(small, v * tau, v * tau * jnp.sin(safe / 2) / (safe / 2))
    mid = psi + dpsi / 2
    return jnp.stack([x + k * jnp.cos(mid), y + k * jnp.sin(mid), psi + dpsi])


def field(r: jax.Array, a: Any = 2.0, b: Any = 0.5) -> jax.Array:
    """``F = (a + b cos φ)/ρ`` at ``r = [x, y, …]`` (``ρ > 0``)."""
    rho = jnp.hypot(r[0], r[1])
    return (a + b * r[0] / rho) / rho


def isoline_radius(phi: jax.Array, f0: Any = 1.0, a: Any = 2.0, b: Any = 0.5) -> jax.Array:
    """``ρ(φ)`` of the isoline ``F = f0``: ``(a + b cos φ)/f0``."""
    return (a + b * jnp.cos(phi)) / f0


def distance(r: jax.Array, discs: jax.Array) -> jax.Array:
    """Distance from ``r`` to the nearest disc boundary (m); ``discs (K, 3)`` rows ``(cx, cy, R)``; ``+inf``
    for ``K = 0``."""
    if discs.shape[0] == 0:
        return jnp.asarray(jnp.inf)
    return jnp.min(jnp.hypot(r[0] - discs[:, 0], r[1] - discs[:, 1]) - discs[:, 2])
