"""Orbital stabilisation of an underactuated plant along a virtual holonomic constraint (transverse
linearisation feedback, Shiriaev–Perram–Canudas-de-Wit), for the ball on a swing
(:mod:`jaxsim.plants.ball_on_swing`).

The periodic gain ``K(t)`` (from :func:`jaxsim.control.periodic_riccati.periodic_riccati`) is tabulated
along the target orbit; off the orbit the phase is the polar angle of the reduced state,
``ϑ = atan2(−φ̇ T/2π, φ) mod 2π`` (``ϑ = 0`` at ``(φ_a, 0)``), and ``K`` is interpolated in ``ϑ``.
The feedback is ``v = K(ϑ) x⊥`` with ``x⊥ = (I − I*, y, ẏ)`` and the torque ``u = P⁻¹(v − R)`` by
partial feedback linearisation.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.integrators import RK4_ROLLED
from jaxsim.plants import ball_on_swing as bos


def phase(z: jax.Array, period: Any) -> jax.Array:
    """``ϑ ∈ [0, 2π)`` of the reduced state ``z = (φ, φ̇)`` (rad)."""
    return jnp.mod(jnp.arctan2(-z[..., 1] * period / (2.0 * jnp.pi), z[..., 0]), 2.0 * jnp.pi)


def gain_at(theta: jax.Array, phases: jax.Array, k_table: jax.Array) -> jax.Array:
    """``K(ϑ) (n,)`` by periodic linear interpolation of ``k_table (N+1, n)`` given at ``phases (N+1,)``."""
    return jax.vmap(lambda col: jnp.interp(theta, phases[:-1], col[:-1], period=2.0 * jnp.pi), in_axes=1)(k_table)


def closed_loop_field(p: bos.Params, k: Any, i_star: Any, period: Any, phases, k_table, x: jax.Array) -> jax.Array:
    """``ẋ (4,)`` of the plant under ``u = P⁻¹(K(ϑ) x⊥ − R)``."""
    xt = bos.transverse_state(p, k, x, i_star)
    v = gain_at(phase(x[1::2], period), phases, k_table) @ xt
    return bos.dynamics(p, x, bos.pfl_torque(p, k, x, v))


def simulate(p: bos.Params, k: Any, i_star: Any, period: Any, phases, k_table, x0: jax.Array, dt: Any, steps: int):
    """RK4 closed-loop run; returns ``(x (steps+1, 4), x⊥ (steps+1, 3), u (steps+1,))``."""

    def field(t, x):
        return closed_loop_field(p, k, i_star, period, phases, k_table, x)

    def step(x, _):
        x1 = RK4_ROLLED.step(field, 0.0, x, dt)
        return x1, x1

    _, xs = jax.lax.scan(step, x0, None, length=steps)
    xs = jnp.concatenate([x0[None], xs])

    def outputs(x):
        xt = bos.transverse_state(p, k, x, i_star)
        v = gain_at(phase(x[1::2], period), phases, k_table) @ xt
        return xt, bos.pfl_torque(p, k, x, v)

    xts, us = jax.vmap(outputs)(xs)
    return xs, xts, us
