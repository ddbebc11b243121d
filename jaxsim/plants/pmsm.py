"""Surface-mount permanent-magnet synchronous motor in αβ coordinates (seed 004 #29, Sinetova, Vedyakov,
Pyrkin, eq. (1)–(2); spec part 3 §2.9)::

    λ̇ = v − R i,     θ̇ = ω,     j ω̇ = τ_e − f ω − τ_L,     τ_e = n_p iᵀ 𝒥 λ,     𝒥 = [[0, −1], [1, 0]]
    λ = L i + λ_m C(θ),   C(θ) = (cos n_p θ, sin n_p θ)

State ``[λ_α, λ_β, ω, θ]`` (Wb, Wb, rad/s mechanical, rad), input ``[v_α, v_β, τ_L]`` (V, V, N·m); the
current is ``i = (λ − λ_m C(θ))/L``.  Power balance (the test's invariant): ``vᵀi = R|i|² +
d/dt(L|i|²/2) + τ_e ω``.  The paper gives no motor: the defaults are a typical small PMSM (the spec's
ranges: R ≈ 1–9 Ω, L ≈ 1–40 mH, λ_m ≈ 0.1–0.3 Wb, n_p = 2–4).
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.pytree import pytree_dataclass

J2 = jnp.array([[0.0, -1.0], [1.0, 0.0]])


@pytree_dataclass
class Params:
    """``R`` Ω, ``L`` H, ``lam_m`` Wb, ``n_p`` pole pairs, ``j`` kg·m², ``f`` N·m·s/rad (assumed)."""

    R: Any = 2.0
    L: Any = 0.01
    lam_m: Any = 0.15
    n_p: Any = 3.0
    j: Any = 1e-3
    f: Any = 1e-3


def magnet(p: Params, theta: jax.Array) -> jax.Array:
    """``λ_m C(θ)`` (Wb): the magnet's flux vector."""
    a = p.n_p * theta
    return p.lam_m * jnp.stack([jnp.cos(a), jnp.sin(a)])


def current(p: Params, x: jax.Array) -> jax.Array:
    """``i = (λ − λ_m C(θ))/L`` (A)."""
    return (x[:2] - magnet(p, x[3])) / p.L


def torque(p: Params, x: jax.Array) -> jax.Array:
    """``τ_e = n_p iᵀ 𝒥 λ`` (N·m)."""
    return p.n_p * current(p, x) @ (J2 @ x[:2])


def dynamics(p: Params, x: jax.Array, u: jax.Array, t: jax.Array) -> jax.Array:
    """``ẋ`` of ``x = [λ_α, λ_β, ω, θ]`` under ``u = [v_α, v_β, τ_L]``."""
    i = current(p, x)
    return jnp.concatenate([u[:2] - p.R * i, jnp.stack([(torque(p, x) - p.f * x[2] - u[2]) / p.j, x[2]])])


__all__ = ["Params", "J2", "magnet", "current", "torque", "dynamics"]
