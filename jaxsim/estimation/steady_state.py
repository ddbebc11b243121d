"""Steady-state (stationary) Kalman filter of a time-invariant model.

The prediction covariance solves the filter DARE
``P = F P Fᵀ − F P Hᵀ (H P Hᵀ + R)⁻¹ H P Fᵀ + Q`` — solved by the toolkit's DARE
(:func:`jaxsim.control.kalman_gain.discrete_kalman`: doubling + Hewer polish, implicit derivatives).
Requires ``(F, H)`` detectable and ``(F, Q^{1/2})`` without uncontrollable modes on the unit circle.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from jaxsim.control.kalman_gain import discrete_kalman
from jaxsim.core.validation import check_covariance, check_finite, check_square
from jaxsim.estimation.kalman import symmetrize


class SteadyStateKalman(NamedTuple):
    """``predicted_cov`` P⁻ ``(n, n)``, ``filtered_cov`` P⁺ ``(n, n)``, ``gain`` K ``(n, p)`` of the update
    ``x⁺ = x⁻ + K (y − H x⁻)``, ``innovation_cov`` S ``(p, p)``."""

    predicted_cov: jax.Array
    filtered_cov: jax.Array
    gain: jax.Array
    innovation_cov: jax.Array


def steady_state_kalman(F: Any, Q: Any, H: Any, R: Any) -> SteadyStateKalman:
    """Stationary covariances and gain of the filter for ``(F (n, n), Q (n, n), H (p, n), R (p, p))``."""
    F, Q, H, R = (jnp.asarray(v) for v in (F, Q, H, R))
    check_square("F", F)
    n = F.shape[0]
    if H.ndim != 2 or H.shape[1] != n:
        raise ValueError(f"H: expected shape (p, {n}), got {tuple(H.shape)}")
    check_finite("F", F)
    check_finite("H", H)
    check_covariance("Q", Q, n)
    check_covariance("R", R, H.shape[0])
    gain = discrete_kalman(F, H, Q, R, names=("F", "H", "Q", "R"))
    s = symmetrize(H @ gain.p_prior @ H.T + R)
    return SteadyStateKalman(gain.p_prior, gain.p_post, gain.k, s)
