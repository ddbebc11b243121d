"""Event probabilities with Wilson score confidence intervals.

For ``k`` occurrences in ``n`` runs, ``p̂ = k/n`` and, with ``z`` the two-sided normal quantile of
the confidence level,

    centre = (p̂ + z²/(2n)) / (1 + z²/n),   half = z/(1 + z²/n) · √(p̂(1−p̂)/n + z²/(4n²)).

Unlike the Wald interval ``p̂ ± z√(p̂(1−p̂)/n)`` it stays inside [0, 1] and keeps its coverage when
``k`` is 0 or ``n`` (rare events such as track loss).  Same formula as
``scipy.stats.binomtest(k, n).proportion_ci(method="wilson")``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.stats import norm


def wilson_interval(k: Any, n: Any, confidence: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
    """``(low, high)`` Wilson score interval for ``k`` successes in ``n`` trials (element-wise)."""
    if not 0.0 < float(confidence) < 1.0:
        raise ValueError(f"confidence: must be in (0, 1), got {confidence!r}")
    k = np.asarray(k, np.float64)
    n = np.asarray(n, np.float64)
    if np.any(n < 0) or np.any(k < 0) or np.any(k > n):
        raise ValueError(f"k, n: need 0 ≤ k ≤ n, got k={k!r}, n={n!r}")
    z = float(norm.ppf(0.5 + float(confidence) / 2.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        p = k / n
        denom = 1.0 + z * z / n
        centre = (p + z * z / (2.0 * n)) / denom
        half = z / denom * np.sqrt(p * (1.0 - p) / n + z * z / (4.0 * n * n))
    low = np.where((n > 0) & (k > 0), np.maximum(centre - half, 0.0), 0.0)  # exact 0 at k = 0
    high = np.where((n > 0) & (k < n), np.minimum(centre + half, 1.0), 1.0)  # exact 1 at k = n
    return low, high
