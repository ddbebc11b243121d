"""Measurement-to-track association in static shapes: Gaussian likelihoods, a χ² gate and the greedy
"highest likelihood wins" assignment (each track takes at most one measurement, each measurement goes
to at most one track).  Jit- and vmap-able: absent measurements are masked, not removed.

Greedy assignment is not the optimal (Hungarian) one in general; it is the rule of trackers that
assign pairs in order of likelihood, and it needs only ``min(N, M)`` rounds of an argmax.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp


class Scores(NamedTuple):
    """``log_lik (N, M)``: ``log N(z_m; ẑ_n, S_n + R_m)``; ``nis (N, M)``: the normalised squared distance."""

    log_lik: jax.Array
    nis: jax.Array


def gaussian_scores(z_hat: jax.Array, S: jax.Array, z: jax.Array, R: jax.Array) -> Scores:
    """Scores of every (track, measurement) pair: predicted measurements ``z_hat (N, p)`` with
    covariances ``S (N, p, p)`` (``H P Hᵀ``), measurements ``z (M, p)`` with noise ``R (M, p, p)``."""
    if z_hat.ndim != 2 or S.shape != z_hat.shape + z_hat.shape[-1:]:
        raise ValueError(f"z_hat, S: expected shapes (N, p), (N, p, p), got {z_hat.shape}, {S.shape}")
    if z.ndim != 2 or R.shape != z.shape + z.shape[-1:] or z.shape[1] != z_hat.shape[1]:
        raise ValueError(f"z, R: expected shapes (M, {z_hat.shape[1]}), (M, p, p), got {z.shape}, {R.shape}")
    cov = S[:, None] + R[None, :]  # (N, M, p, p)
    d = z[None, :, :] - z_hat[:, None, :]
    chol = jnp.linalg.cholesky(cov)
    w = jax.scipy.linalg.solve_triangular(chol, d[..., None], lower=True)[..., 0]
    nis = jnp.sum(w * w, axis=-1)
    log_det = 2.0 * jnp.sum(jnp.log(jnp.diagonal(chol, axis1=-2, axis2=-1)), axis=-1)
    p = z.shape[1]
    return Scores(-0.5 * (nis + log_det + p * jnp.log(2.0 * jnp.pi)), nis)


def greedy_assignment(score: jax.Array, valid: jax.Array) -> jax.Array:
    """``(N,)`` int: for each row (track) the column (measurement) it takes, ``−1`` for none.

    Repeatedly takes the highest ``score`` among the ``valid (N, M)`` pairs whose row and column are
    both still free.  Ties go to the lowest flat index (row-major)."""
    n, m = score.shape
    if valid.shape != (n, m):
        raise ValueError(f"valid: expected shape {(n, m)} like score, got {valid.shape}")
    neg = jnp.asarray(-jnp.inf, score.dtype)

    def round_(_, carry):
        free, out = carry
        s = jnp.where(free, score, neg)
        k = jnp.argmax(s)
        i, j = k // m, k % m
        ok = free[i, j]
        out = out.at[i].set(jnp.where(ok, j, out[i]).astype(out.dtype))
        free = jnp.where(ok, free.at[i, :].set(False).at[:, j].set(False), free)
        return free, out

    init = (valid & jnp.isfinite(score), jnp.full(n, -1, dtype=jnp.int32))
    return jax.lax.fori_loop(0, min(n, m), round_, init)[1]


__all__ = ["Scores", "gaussian_scores", "greedy_assignment"]
