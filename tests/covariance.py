"""Comparing covariance matrices the way their numbers mean something.

An off-diagonal entry that should be zero comes out of two correct computations as rounding noise
(1e-27 against a 1e-10 diagonal, with either sign), and a correlation near ±1 loses digits to
cancellation; a plain ``rtol`` on each entry then fails on some CPUs and not others.  Each entry is
compared instead against the scale of its row and column, σᵢσⱼ: ``|Δ_ij| ≤ rtol·σᵢσⱼ``, i.e. the
correlation coefficients agree to ``rtol`` and the variances to ``rtol`` relatively.
"""

from __future__ import annotations

import numpy as np


def assert_covariance_close(actual, desired, rtol: float) -> None:
    """Raise ``AssertionError`` unless ``|actual − desired| ≤ rtol·σᵢσⱼ`` entrywise, with σ from
    ``desired``'s diagonal; ``actual`` and ``desired`` are ``(n, n)`` covariances."""
    actual, desired = np.asarray(actual, float), np.asarray(desired, float)
    assert actual.shape == desired.shape, f"shapes differ: {actual.shape} vs {desired.shape}"
    sigma = np.sqrt(np.clip(np.diag(desired), 0.0, None))
    scale = np.outer(sigma, sigma)
    excess = np.abs(actual - desired) - rtol * scale
    if np.any(excess > 0):
        i, j = np.unravel_index(np.argmax(excess / np.where(scale > 0, scale, 1.0)), excess.shape)
        raise AssertionError(
            f"covariances differ beyond rtol={rtol:g} of σᵢσⱼ at [{i}, {j}]: "
            f"{actual[i, j]:.6e} vs {desired[i, j]:.6e} (σᵢσⱼ = {scale[i, j]:.3e})"
        )
