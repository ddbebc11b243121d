"""Cubature Kalman filter (Arasaratnam & Haykin, third-degree spherical–radial rule).

``2n`` points ``m ± √n Lᵢ`` with equal weights ``1/(2n)`` — the unscented rule with ``α = 1``,
``β = 0``, ``κ = 0`` minus its zero-weight centre point.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.pytree import pytree_dataclass
from jaxsim.estimation import kalman
from jaxsim.estimation.nonlinear import NonlinearSSM
from jaxsim.estimation.types import FilterResult
from jaxsim.estimation.ukf import sigma_point_filter


@pytree_dataclass
class CubaturePoints:
    """Third-degree spherical–radial cubature points (no parameters)."""

    def points(self, mean: jax.Array, cov: jax.Array) -> jax.Array:
        """Points ``(2n, n)``: ``[m + √n Lᵢ…, m − √n Lᵢ…]``."""
        n = mean.shape[0]
        scaled = jnp.sqrt(n) * jnp.linalg.cholesky(kalman.symmetrize(cov))
        return jnp.concatenate([mean[None] + scaled.T, mean[None] - scaled.T], axis=0)

    def weights(self, n: int) -> tuple[jax.Array, jax.Array]:
        w = jnp.full((2 * n,), 0.5 / n)
        return w, w


def cubature_kalman_filter(
    model: NonlinearSSM,
    y: Any,
    u: Any = None,
    *,
    mask: Any = None,
    missing: str = "error",
    gate: float | None = None,
) -> FilterResult:
    """Scanned cubature Kalman filter (arguments as :func:`~jaxsim.estimation.ukf.unscented_kalman_filter`)."""
    return sigma_point_filter(model, y, u, scheme=CubaturePoints(), mask=mask, missing=missing, gate=gate)
