"""Quantiles from a fixed log-bucket histogram: mergeable exactly, with a stated error bound.

The real line is cut into fixed buckets (the layout of DDSketch, Masson et al. 2019, with a fixed
range instead of a collapsing one):

* ``|x| ≤ min_abs`` — one "zero" bucket, represented by 0;
* ``min_abs·γ^k < |x| ≤ min_abs·γ^(k+1)``, ``k = 0 … K−1``, one bucket per sign, represented by
  ``±min_abs·γ^k · 2γ/(1+γ)``, where ``γ = (1+α)/(1−α)`` and ``K = ⌈log_γ(max_abs/min_abs)⌉``;
* beyond ``min_abs·γ^K ≥ max_abs`` — one overflow bucket per sign.

Counts are integers, so merging sketches (adding counts) is exact and order-free.  The quantile at
level ``p`` of ``N`` values is defined as the order statistic ``x₍ᵣ₎`` with ``r = max(1, ⌈p·N⌉)``
(NumPy's ``method="inverted_cdf"``); the estimate is the representative of the bucket holding
``x₍ᵣ₎``, clipped to the exact ``[min, max]`` of the data.

**Error bound.**  If ``min_abs < |x₍ᵣ₎| ≤ max_abs``: ``|q̂ − x₍ᵣ₎| ≤ α·|x₍ᵣ₎|`` (relative accuracy
α; up to rounding of ``log`` at a bucket edge, ~1e-15 relative).  If ``|x₍ᵣ₎| ≤ min_abs``:
``|q̂ − x₍ᵣ₎| ≤ min_abs``.  Beyond ``max_abs`` there is no bound other than the exact extremes (the
estimate is then the data's min or max).  Memory: ``2K + 3`` counts per metric element
(41,449 for the defaults α = 1e-3, range 1e-9 … 1e9).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import jax.numpy as jnp
import numpy as np


@dataclass(frozen=True)
class QuantileSketch:
    """Bucket layout: relative accuracy ``rel_accuracy`` (α) for ``min_abs < |x| ≤ max_abs``."""

    rel_accuracy: float = 1e-3
    min_abs: float = 1e-9
    max_abs: float = 1e9

    def __post_init__(self) -> None:
        if not (0.0 < float(self.rel_accuracy) < 1.0):
            raise ValueError(f"rel_accuracy: must be in (0, 1), got {self.rel_accuracy!r}")
        if not (math.isfinite(self.min_abs) and self.min_abs > 0):
            raise ValueError(f"min_abs: must be finite and positive, got {self.min_abs!r}")
        if not (math.isfinite(self.max_abs) and self.max_abs > self.min_abs):
            raise ValueError(f"max_abs: must be finite and greater than min_abs={self.min_abs!r}, got {self.max_abs!r}")

    @property
    def gamma(self) -> float:
        a = float(self.rel_accuracy)
        return (1.0 + a) / (1.0 - a)

    @property
    def buckets_per_sign(self) -> int:
        return int(math.ceil(math.log(self.max_abs / self.min_abs) / math.log(self.gamma)))

    @property
    def n_bins(self) -> int:
        return 2 * self.buckets_per_sign + 3

    def bucket(self, x: jnp.ndarray) -> jnp.ndarray:
        """Bucket index of each value (device side, int32; monotone non-decreasing in ``x``)."""
        k_max = self.buckets_per_sign
        ax = jnp.abs(x)
        k = jnp.ceil(jnp.log(ax / self.min_abs) / math.log(self.gamma)) - 1.0
        k = jnp.clip(jnp.where(ax > self.min_abs, k, 0.0), 0.0, k_max).astype(jnp.int32)
        # k == k_max marks the overflow bucket of either sign.
        positive = (k_max + 2) + k
        negative = k_max - k
        zero = k_max + 1
        return jnp.where(ax <= self.min_abs, zero, jnp.where(x > 0, positive, negative)).astype(jnp.int32)

    def representatives(self) -> np.ndarray:
        """Value reported for each bucket (``±inf`` for the overflow buckets)."""
        k_max, g = self.buckets_per_sign, self.gamma
        mags = self.min_abs * g ** np.arange(k_max, dtype=np.float64) * (2.0 * g / (1.0 + g))
        return np.concatenate([[-np.inf], -mags[::-1], [0.0], mags, [np.inf]])

    def describe(self) -> dict[str, float]:
        return {
            "rel_accuracy": float(self.rel_accuracy),
            "min_abs": float(self.min_abs),
            "max_abs": float(self.max_abs),
        }


def sketch_quantile(
    sketch: QuantileSketch,
    counts: np.ndarray,
    q: float | np.ndarray,
    minimum: np.ndarray,
    maximum: np.ndarray,
) -> np.ndarray:
    """Quantile(s) ``q ∈ [0, 1]`` from bucket ``counts`` (shape ``(n_bins, *shape)``).

    Returns shape ``q.shape + shape``; ``nan`` where there are no values.  ``minimum``/``maximum``
    are the exact extremes (the estimate is clipped to them).
    """
    qs = np.asarray(q, np.float64)
    if np.any(~np.isfinite(qs)) or np.any((qs < 0) | (qs > 1)):
        raise ValueError(f"q: quantile levels must lie in [0, 1], got {q!r}")
    counts = np.asarray(counts, np.int64)
    flat = counts.reshape(counts.shape[0], -1)
    total = flat.sum(axis=0)
    cum = np.cumsum(flat, axis=0)
    reps = sketch.representatives()
    lo = np.asarray(minimum, np.float64).reshape(-1)
    hi = np.asarray(maximum, np.float64).reshape(-1)
    out = np.empty(qs.shape + (flat.shape[1],), np.float64)
    for j in range(flat.shape[1]):
        if total[j] == 0:
            out[..., j] = np.nan
            continue
        rank = np.maximum(1, np.ceil(qs * total[j])).astype(np.int64)
        idx = np.searchsorted(cum[:, j], rank, side="left")
        out[..., j] = np.clip(reps[idx], lo[j], hi[j])
    return out.reshape(qs.shape + counts.shape[1:])


def quantile_error_bound(sketch: QuantileSketch, estimate: np.ndarray) -> np.ndarray:
    """Bound on ``|q̂ − x₍ᵣ₎|`` given the estimate (see module docstring; ``inf`` beyond ``max_abs``).

    Expressed through the estimate: ``α|x| ≤ α|q̂|/(1−α)`` inside the range, ``min_abs`` near 0.
    """
    a = float(sketch.rel_accuracy)
    est = np.abs(np.asarray(estimate, np.float64))
    bound = np.where(est <= sketch.min_abs, sketch.min_abs, a * est / (1.0 - a))
    return np.where(est > sketch.max_abs, np.inf, bound)
