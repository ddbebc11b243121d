"""Steady-state (stationary) Kalman filter of a time-invariant model.

The prediction covariance solves the filter DARE
``P = F P Fᵀ − F P Hᵀ (H P Hᵀ + R)⁻¹ H P Fᵀ + Q``, here by the structure-preserving doubling
algorithm (Chu, Fan, Lin & Wang 2004) on the dual pair ``(Fᵀ, Hᵀ)``::

    W = I + G_k H_k,  A_{k+1} = A_k W⁻¹ A_k,  G_{k+1} = G_k + A_k W⁻¹ G_k A_kᵀ,
    H_{k+1} = H_k + A_kᵀ H_k W⁻¹ A_k,     A₀ = Fᵀ, G₀ = Hᵀ R⁻¹ H, H₀ = Q,   H_k → P

(quadratic convergence; a fixed number of iterations keeps it jittable and differentiable).
Requires ``(F, H)`` detectable and ``(F, Q^{1/2})`` stabilisable.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from jaxsim.core.validation import check_covariance, check_finite, check_square
from jaxsim.estimation.kalman import symmetrize


class SteadyStateKalman(NamedTuple):
    """``predicted_cov`` P⁻ ``(n, n)``, ``filtered_cov`` P⁺ ``(n, n)``, ``gain`` K ``(n, p)`` of the update
    ``x⁺ = x⁻ + K (y − H x⁻)``, ``innovation_cov`` S ``(p, p)``."""

    predicted_cov: jax.Array
    filtered_cov: jax.Array
    gain: jax.Array
    innovation_cov: jax.Array


def solve_dare_doubling(A: jax.Array, G: jax.Array, Hq: jax.Array, iterations: int = 60) -> jax.Array:
    """Stabilising ``X = Aᵀ X (I + G X)⁻¹ A + Hq`` by doubling (``G = B R⁻¹ Bᵀ``): the control DARE."""
    eye = jnp.eye(A.shape[0], dtype=A.dtype)

    def body(_, c):
        a, g, h = c
        w = eye + g @ h
        wa = jnp.linalg.solve(w, a)
        wg = jnp.linalg.solve(w, g)
        return a @ wa, symmetrize(g + a @ wg @ a.T), symmetrize(h + a.T @ h @ wa)

    _, _, x = jax.lax.fori_loop(0, iterations, body, (A, G, Hq))
    return x


def steady_state_kalman(F: Any, Q: Any, H: Any, R: Any, *, iterations: int = 60) -> SteadyStateKalman:
    """Stationary covariances and gain of the filter for ``(F (n, n), Q, H (p, n), R)``."""
    F, Q, H, R = (jnp.asarray(v) for v in (F, Q, H, R))
    check_square("F", F)
    n = F.shape[0]
    if H.ndim != 2 or H.shape[1] != n:
        raise ValueError(f"H: expected shape (p, {n}), got {tuple(H.shape)}")
    check_finite("F", F)
    check_finite("H", H)
    check_covariance("Q", Q, n)
    check_covariance("R", R, H.shape[0])
    g = H.T @ jnp.linalg.solve(R, H)
    p_pred = solve_dare_doubling(F.T, symmetrize(g), Q, iterations)
    s = symmetrize(H @ p_pred @ H.T + R)
    k = jnp.linalg.solve(s, H @ p_pred).T
    ikh = jnp.eye(n, dtype=F.dtype) - k @ H
    p_filt = symmetrize(ikh @ p_pred @ ikh.T + k @ R @ k.T)
    return SteadyStateKalman(p_pred, p_filt, k, s)
