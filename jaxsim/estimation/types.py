"""States and results shared by the estimation kernels (NamedTuples: pytrees that vmap and scan).

Shapes: ``n`` state dimension, ``p`` measurement dimension, ``T`` number of time steps.
"""

from __future__ import annotations

from typing import NamedTuple

import jax


class GaussianState(NamedTuple):
    """A Gaussian belief ``N(mean, cov)``: mean ``(n,)``, covariance ``(n, n)``."""

    mean: jax.Array
    cov: jax.Array


class SqrtGaussianState(NamedTuple):
    """A Gaussian belief in square-root form: mean ``(n,)``, lower Cholesky factor ``chol``
    ``(n, n)`` with ``cov = chol @ chol.T``."""

    mean: jax.Array
    chol: jax.Array


class Innovation(NamedTuple):
    """What one measurement update saw.

    residual: ``(p,)`` innovation ``y − ŷ`` (0 on masked components);
    cov: ``(p, p)`` innovation covariance ``S`` (identity rows/columns on masked components);
    log_likelihood: ``log N(y; ŷ, S)`` over the available components only;
    nis: normalised innovation squared ``rᵀ S⁻¹ r`` (χ² with ``dof`` degrees of freedom);
    dof: number of available components.
    """

    residual: jax.Array
    cov: jax.Array
    log_likelihood: jax.Array
    nis: jax.Array
    dof: jax.Array


class FilterResult(NamedTuple):
    """A filter run over ``T`` steps (time on the leading axis).

    means, covs: ``(T, n)``, ``(T, n, n)`` filtered ``p(x_t | y_0..y_t)``;
    predicted_means, predicted_covs: the prior ``p(x_t | y_0..y_{t−1})`` each update started from
    (``[0]`` is the model's initial belief);
    log_likelihood: ``()`` total ``log p(y_0..y_{T−1})``; log_likelihoods: ``(T,)`` per step;
    innovations, innovation_covs, nis, dof: per-step :class:`Innovation` fields;
    accepted: ``(T,)`` whether the step updated with at least one component (masking or gating).
    """

    means: jax.Array
    covs: jax.Array
    predicted_means: jax.Array
    predicted_covs: jax.Array
    log_likelihood: jax.Array
    log_likelihoods: jax.Array
    innovations: jax.Array
    innovation_covs: jax.Array
    nis: jax.Array
    dof: jax.Array
    accepted: jax.Array


class SmootherResult(NamedTuple):
    """A smoother run: smoothed ``p(x_t | y_0..y_{T−1})`` means ``(T, n)`` and covs ``(T, n, n)``,
    the smoother gains ``(T−1, n, n)`` and the forward :class:`FilterResult`."""

    means: jax.Array
    covs: jax.Array
    gains: jax.Array
    filtered: FilterResult
