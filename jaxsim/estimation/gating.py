"""Consistency and gating: NIS, NEES, χ² gates and the χ² confidence bounds of Monte-Carlo averages.

* ``nis = νᵀ S⁻¹ ν`` of an innovation ``ν`` with covariance ``S`` is χ²(p) for a consistent filter;
* ``nees = eᵀ P⁻¹ e`` of an estimation error ``e = x − x̂`` is χ²(n);
* over ``N`` independent runs the average is ``χ²(N·dof)/N``, so its two-sided ``prob`` bounds are
  ``χ²⁻¹((1 ∓ prob)/2; N·dof)/N`` (Bar-Shalom, Li & Kirubarajan, §5.4).

Thresholds come from SciPy's χ² quantiles (design-time numbers, computed before tracing).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import scipy.stats

from jaxsim.core.validation import check_positive


def _check_prob(prob: float) -> None:
    if not 0.0 < float(prob) < 1.0:
        raise ValueError(f"prob: must lie in (0, 1), got {prob!r}")


def chi2_threshold(dof: int, prob: float = 0.99) -> float:
    """The ``prob`` quantile of χ²(dof): a gate that passes ``prob`` of consistent innovations."""
    check_positive("dof", dof)
    _check_prob(prob)
    return float(scipy.stats.chi2.ppf(prob, dof))


def chi2_bounds(dof: int, n_runs: int = 1, prob: float = 0.95) -> tuple[float, float]:
    """Two-sided ``prob`` interval of the average of ``n_runs`` independent χ²(dof) statistics."""
    check_positive("dof", dof)
    check_positive("n_runs", n_runs)
    _check_prob(prob)
    k = int(n_runs) * dof
    lo, hi = scipy.stats.chi2.ppf([(1.0 - prob) / 2.0, (1.0 + prob) / 2.0], k)
    return float(lo) / n_runs, float(hi) / n_runs


def mahalanobis_squared(e: jax.Array, cov: jax.Array) -> jax.Array:
    """``eᵀ cov⁻¹ e`` by Cholesky (broadcasts over leading axes of ``e (…, k)`` and ``cov (…, k, k)``)."""
    chol = jnp.linalg.cholesky(cov)
    z = jax.scipy.linalg.solve_triangular(chol, e[..., None], lower=True)[..., 0]
    return jnp.sum(z * z, axis=-1)


def nis(innovation: jax.Array, S: jax.Array) -> jax.Array:
    """Normalised innovation squared ``νᵀ S⁻¹ ν``."""
    return mahalanobis_squared(innovation, S)


def nees(x_true: jax.Array, mean: jax.Array, cov: jax.Array) -> jax.Array:
    """Normalised estimation error squared ``(x − x̂)ᵀ P⁻¹ (x − x̂)``."""
    return mahalanobis_squared(x_true - mean, cov)


def chi2_gate(innovation: jax.Array, S: jax.Array, threshold: float | jax.Array) -> jax.Array:
    """``True`` where the innovation passes the gate ``NIS ≤ threshold``."""
    return nis(innovation, S) <= threshold


def fraction_inside(stat: jax.Array, bounds: tuple[float, float]) -> jax.Array:
    """Fraction of ``stat`` values inside ``[lo, hi]`` (e.g. per-step averages against :func:`chi2_bounds`)."""
    lo, hi = bounds
    return jnp.mean((stat >= lo) & (stat <= hi))


__all__ = ["chi2_threshold", "chi2_bounds", "mahalanobis_squared", "nis", "nees", "chi2_gate", "fraction_inside"]
