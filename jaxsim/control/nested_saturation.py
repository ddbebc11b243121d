"""Nested saturated feedback (NSF) with disturbance compensation and the dual-mode switch of seed 004
#31 (Ahi, Adelipour, Haeri; spec seed004_part3 §2.10, eqs. (5)–(7), (10)).

* :func:`nsf_control` — ``u = −sat_{u_m}(d̂ + σ_n(x_n + σ_{n−1}(x_{n−1} + … σ_1(x_1))))``, eq. (6),
  with the linear saturations of (5): ``σ_i(s) = k_i·clip(s, −L_i, L_i)`` (bound ``M_i = k_i L_i``).
* :func:`constrained_levels` — the linear zones ``L_i`` from the slopes so that the (reconstructed,
  garbled in the paper) design constraints (7) hold with equality: ``M_n = u_m − d_m`` and
  ``M_i = L_{i+1}/f`` (each inner saturation at most ``1/f`` of the next linear zone).
* :func:`design_residuals` — those constraints as ``g ≤ 0`` plus ``k_i > 0``.
* :func:`lqr_level` — the largest level ``c`` with ``|K x| ≤ u_m − d_m`` on ``{xᵀPx ≤ c}``: the LQR
  level set that stands in for the paper's LMI robust positively invariant set Ω_P (stated
  approximation: with the disturbance cancelled by the ESO the set is invariant for the nominal
  closed loop, P being the Riccati solution, a Lyapunov matrix of ``A − BK``).
* :func:`dual_control` — the switching law (10): linear feedback inside the set, NSF outside.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp


def nsf_inner(k: jax.Array, levels: jax.Array, x: jax.Array) -> jax.Array:
    """``σ_n(x_n + σ_{n−1}(… + σ_1(x_1)))`` for slopes ``k`` and zones ``levels`` (each ``(n,)``)."""
    s = jnp.zeros((), dtype=x.dtype)
    for i in range(x.shape[0]):
        s = k[i] * jnp.clip(x[i] + s, -levels[i], levels[i])
    return s


def nsf_control(k: jax.Array, levels: jax.Array, x: jax.Array, d_hat: jax.Array, u_m: Any) -> jax.Array:
    """Eq. (6): ``−sat_{u_m}(d̂ + nsf_inner(x))`` (scalar)."""
    return -jnp.clip(d_hat + nsf_inner(k, levels, x), -u_m, u_m)


def constrained_levels(k: jax.Array, u_m: Any, d_m: Any, f: float = 2.0) -> jax.Array:
    """``L`` ``(n,)`` with ``k_n L_n = u_m − d_m`` and ``k_i L_i = L_{i+1}/f`` (constraints (7) tight)."""
    n = k.shape[0]
    levels = [None] * n
    levels[n - 1] = (u_m - d_m) / k[n - 1]
    for i in range(n - 2, -1, -1):
        levels[i] = levels[i + 1] / (f * k[i])
    return jnp.stack(levels)


def design_residuals(k: jax.Array, levels: jax.Array, u_m: Any, d_m: Any, f: float = 2.0) -> jax.Array:
    """Constraints (7) as ``g ≤ 0``: ``k_n L_n − (u_m − d_m)``, ``f k_i L_i − L_{i+1}``, ``−k``, ``−L``."""
    m = k * levels
    g = [m[-1] - (u_m - d_m)] + [f * m[i] - levels[i + 1] for i in range(k.shape[0] - 1)]
    return jnp.concatenate([jnp.stack(g), -k, -levels])


def linear_gain(k: jax.Array) -> jax.Array:
    """Row ``(n,)`` of the NSF's unsaturated law ``u = −d̂ − gain·x`` (for pole checks)."""
    n = k.shape[0]
    rows = jnp.zeros(n)
    for i in range(n):  # s_i = k_i (x_i + s_{i−1})  ⇒  coefficients accumulate
        rows = k[i] * (rows + jnp.eye(n)[i])
    return rows


def lqr_level(gain: jax.Array, p: jax.Array, u_m: Any, d_m: Any) -> jax.Array:
    """Largest ``c`` with ``max_{xᵀPx ≤ c} |gain·x| ≤ u_m − d_m``: ``(u_m − d_m)²/(gain P⁻¹ gainᵀ)``."""
    return (u_m - d_m) ** 2 / (gain @ jnp.linalg.solve(p, gain))


def in_set(p: jax.Array, level: jax.Array, x: jax.Array) -> jax.Array:
    """``xᵀPx ≤ level`` (bool)."""
    return x @ p @ x <= level


def dual_control(
    k: jax.Array,
    levels: jax.Array,
    gain: jax.Array,
    p: jax.Array,
    level: jax.Array,
    x: jax.Array,
    d_hat: jax.Array,
    u_m: Any,
) -> tuple[jax.Array, jax.Array]:
    """Switching law (10): ``(u, inside)`` with ``u = −d̂ − gain·x`` inside ``{xᵀPx ≤ level}``,
    the NSF (6) outside; ``u`` saturated at ``u_m`` either way."""
    inside = in_set(p, level, x)
    u_lin = -jnp.clip(d_hat + gain @ x, -u_m, u_m)
    return jnp.where(inside, u_lin, nsf_control(k, levels, x, d_hat, u_m)), inside
