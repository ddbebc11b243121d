"""Periodic Riccati equation and Floquet multipliers of a linear periodic system (differentiable).

For ``ẋ = A(t) x + B(t) v`` with period ``T`` the periodic stabilising solution of

    −Ṗ = Aᵀ P + P A + Q − P B R⁻¹ Bᵀ P

is the limit of the backward integration from ``P(T) = Q_f`` over several periods; the gain is
``K(t) = −R⁻¹ Bᵀ P(t)`` and the closed loop ``A + B K``.  Both :func:`periodic_riccati` and
:func:`monodromy` take ``A``, ``B`` sampled at ``t_j = j·T/(2N)``, ``j = 0 … 2N`` (first = last), and
integrate by RK4 with step ``h = T/N`` (the odd samples are the stage midpoints), in ``lax.scan``:
everything is differentiable by ``jax.grad``.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.validation import check_positive_int


def _check_samples(a: jax.Array, b: jax.Array) -> None:
    if a.ndim != 3 or a.shape[1] != a.shape[2]:
        raise ValueError(f"a must have shape (2N+1, n, n), got {a.shape}")
    if b.ndim != 3 or b.shape[:2] != a.shape[:2]:
        raise ValueError(f"b must have shape (2N+1, n, m) matching a {a.shape}, got {b.shape}")
    if a.shape[0] < 3 or a.shape[0] % 2 == 0:
        raise ValueError(f"a must hold an odd number (2N+1 ≥ 3) of samples, got {a.shape[0]}")


def periodic_riccati(
    a: jax.Array, b: jax.Array, q: jax.Array, r: jax.Array, period: Any, periods: int, p_final: jax.Array | None = None
) -> tuple[jax.Array, jax.Array]:
    """Backward RK4 integration of the Riccati equation over ``periods`` periods.

    ``a (2N+1, n, n)``, ``b (2N+1, n, m)``, ``q (n, n)``, ``r (m, m)``; returns ``(P (N+1, n, n)`` on the
    grid ``t = j·T/N`` of the last period integrated (``P[0]`` at ``t = 0``), ``residual``: max
    ``|P(0)−P(T)|/max|P|`` over that period — small when the solution has become periodic).
    """
    a, b = jnp.asarray(a), jnp.asarray(b)
    _check_samples(a, b)
    check_positive_int("periods", periods)
    n_steps = (a.shape[0] - 1) // 2
    h = period / n_steps
    r_inv = jnp.linalg.inv(r)
    p0 = q if p_final is None else p_final

    def rhs(j2, p):  # dP/dt at sample index j2 (half-steps)
        aj, bj = a[j2], b[j2]
        return -(aj.T @ p + p @ aj + q - p @ bj @ r_inv @ bj.T @ p)

    def step(p, j):  # from t_{j+1} back to t_j (sample indices 2j+2, 2j+1, 2j)
        hi, mid, lo = 2 * j + 2, 2 * j + 1, 2 * j
        k1 = rhs(hi, p)
        k2 = rhs(mid, p - 0.5 * h * k1)
        k3 = rhs(mid, p - 0.5 * h * k2)
        k4 = rhs(lo, p - h * k3)
        p1 = p - h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        p1 = 0.5 * (p1 + p1.T)
        return p1, p1

    idx = jnp.arange(n_steps)[::-1]

    def one_period(p, _):
        p_start, ps = jax.lax.scan(step, p, idx)
        return p_start, ps

    p_last_end = jax.lax.fori_loop(0, periods - 1, lambda _, p: one_period(p, None)[0], p0)
    p_start, ps = one_period(p_last_end, None)
    grid = jnp.concatenate([ps[::-1], p_last_end[None]])  # t = 0 … T
    residual = jnp.max(jnp.abs(p_start - p_last_end)) / jnp.max(jnp.abs(p_start))
    return grid, residual


def gains(b: jax.Array, r: jax.Array, p: jax.Array) -> jax.Array:
    """``K_j = −R⁻¹ B_jᵀ P_j`` for ``b (N+1, n, m)`` and ``p (N+1, n, n)`` on the same grid → ``(N+1, m, n)``."""
    return -jnp.einsum("mk,jnk,jnl->jml", jnp.linalg.inv(r), b, p)


def monodromy(a: jax.Array, period: Any) -> jax.Array:
    """Monodromy matrix ``Φ(T)`` of ``ẋ = A(t) x`` (``a (2N+1, n, n)`` sampled as above), forward RK4."""
    a = jnp.asarray(a)
    _check_samples(a, a)
    n_steps = (a.shape[0] - 1) // 2
    h = period / n_steps

    def step(phi, j):
        lo, mid, hi = 2 * j, 2 * j + 1, 2 * j + 2
        k1 = a[lo] @ phi
        k2 = a[mid] @ (phi + 0.5 * h * k1)
        k3 = a[mid] @ (phi + 0.5 * h * k2)
        k4 = a[hi] @ (phi + h * k3)
        return phi + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4), None

    out, _ = jax.lax.scan(step, jnp.eye(a.shape[1]), jnp.arange(n_steps))
    return out


def floquet_multipliers(a: jax.Array, period: Any) -> jax.Array:
    """Eigenvalues of :func:`monodromy`, sorted by decreasing modulus (complex)."""
    mu = jnp.linalg.eigvals(monodromy(a, period))
    return mu[jnp.argsort(-jnp.abs(mu))]
