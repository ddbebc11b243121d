"""Allan variance of a sampled signal, overlapping and non-overlapping (IEEE Std 952, annex C).

For samples ``y_k`` at period ``dt`` and a cluster of ``m`` samples (``τ = m·dt``), with cluster
averages ``ȳ_k(m) = (1/m) Σ_{l<m} y_{k+l}``::

    non-overlapping:  σ²(τ) = 1/(2(L − 1)) Σ_{i<L−1} (ȳ_{(i+1)m} − ȳ_{im})²,     L = ⌊N/m⌋
    overlapping:      σ²(τ) = 1/(2(N − 2m + 1)) Σ_{k ≤ N−2m} (ȳ_{k+m} − ȳ_k)²

(the non-overlapping form is eq. 3 of seed 004's Allan-variance paper).  Both are unbiased for
white noise (``σ²/m``) and for a random walk, where seed 004 gives
``E σ²(τ) = K² τ/3 + K² dt²/(6τ)`` with ``K² = σ_V² dt`` the intensity of the increments.
Cluster sizes are static (Python ints); the signal may be traced (jit, vmap over runs).

The signal is centred (its mean subtracted) before the cumulative sum: the Allan variance does not
see a constant offset, and without centring a float32 signal with a large offset loses every digit
of the differences of its cumulative sums.
"""

from __future__ import annotations

import functools
from typing import Any, NamedTuple, Sequence

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.validation import check_finite, check_positive, check_positive_int, check_real


class AllanResult(NamedTuple):
    """``tau (K,)`` averaging times, ``avar (K,)`` Allan variances, ``adev (K,)`` deviations,
    ``n_terms (K,)`` number of squared differences averaged."""

    tau: jax.Array
    avar: jax.Array
    adev: jax.Array
    n_terms: jax.Array


def cluster_sizes(n_samples: int, per_decade: int = 10, max_fraction: float = 0.5) -> tuple[int, ...]:
    """Log-spaced distinct cluster sizes from 1 up to ``max_fraction · n_samples``."""
    top = max(1, int(n_samples * max_fraction))
    grid = np.unique(np.round(np.logspace(0, np.log10(top), per_decade * max(1, int(np.log10(top)) + 1))))
    return tuple(int(m) for m in grid if 1 <= m <= top)


def allan_variance(y: Any, dt: float, m: Sequence[int] | None = None, *, overlapping: bool = True) -> AllanResult:
    """Allan variance of ``y (N,)`` (real) sampled every ``dt`` (s) for cluster sizes ``m`` (positive
    integers; default log-spaced).

    A concrete ``y`` must be finite (``ValueError`` otherwise); a traced ``y`` with NaN gives NaN
    variances.  Integer ``y`` is computed in the default float type.
    """
    y = jnp.asarray(y)
    if y.ndim != 1:
        raise ValueError(f"y: expected shape (N,), got {tuple(y.shape)}")
    check_real("y", y)
    check_finite("y", y)
    check_positive("dt", dt)
    n = y.shape[0]
    sizes = cluster_sizes(n) if m is None else tuple(check_positive_int("m", k) for k in m)
    for k in sizes:
        if (overlapping and 2 * k > n) or (not overlapping and n // k < 2):
            raise ValueError(f"m: cluster size {k} needs at least {2 * k} samples, got N = {n}")
    y = y.astype(jnp.result_type(y, float))
    avar = _avar(y, sizes, overlapping)
    terms = [n + 1 - 2 * k if overlapping else n // k - 1 for k in sizes]
    return AllanResult(jnp.asarray(sizes, dtype=y.dtype) * dt, avar, jnp.sqrt(avar), jnp.asarray(terms))


@functools.partial(jax.jit, static_argnames=("sizes", "overlapping"))
def _avar(y: jax.Array, sizes: tuple[int, ...], overlapping: bool) -> jax.Array:
    n = y.shape[0]
    theta = jnp.concatenate([jnp.zeros((1,), y.dtype), jnp.cumsum(y - jnp.mean(y))])
    avar = []
    for k in sizes:
        if overlapping:
            d = (theta[2 * k :] - 2.0 * theta[k:-k] + theta[: n + 1 - 2 * k]) / k
        else:
            means = (theta[k::k] - theta[:-k:k][: n // k]) / k
            d = jnp.diff(means[: n // k])
        avar.append(0.5 * jnp.mean(d * d))
    return jnp.stack(avar)


def random_walk_avar(tau: Any, k2: Any, dt: Any) -> jax.Array:
    """Seed 004's expectation for a sampled random walk: ``K² τ/3 + K² dt²/(6τ)``."""
    tau = jnp.asarray(tau)
    return k2 * tau / 3.0 + k2 * dt**2 / (6.0 * tau)


def white_noise_avar(tau: Any, sigma2: Any, dt: Any) -> jax.Array:
    """White noise of per-sample variance ``σ²``: ``σ² dt/τ`` (= ``σ²/m``)."""
    return sigma2 * dt / jnp.asarray(tau)
