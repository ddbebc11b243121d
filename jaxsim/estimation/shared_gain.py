"""Monte-Carlo runs that share one model: the covariance recursion computed once.

Without gating, the covariances, gains and innovation covariances of a Kalman filter do not depend
on the measured values — only on the model and on *which* measurements are available.  Many runs
that share the model and the availability pattern (a Monte-Carlo sweep over noise draws) can
therefore run :func:`covariance_sequence` once and :func:`mean_filter` per run: per step and run
only ``m ← m + K (y − H m)``, the whitened innovation and ``m ← F m + B u`` remain, which batch over
runs as matrix–matrix products.  Results equal :func:`~jaxsim.estimation.lgssm.kalman_filter`'s.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from jaxsim.estimation.kalman import LOG_2PI
from jaxsim.estimation.lgssm import (
    LinearGaussianSSM,
    at,
    kalman_filter,
    prepare_inputs,
    prepare_measurements,
    step_params,
)
from jaxsim.precision import to_common_float


class CovarianceSequence(NamedTuple):
    """Per step ``t``: ``gains (T, n, p)``, ``whitening (T, p, p)`` = ``L_S⁻¹`` (masked rows zero),
    ``log_norm (T,)`` = ``−½(log det S + dof·log 2π)``, ``covs`` and ``predicted_covs`` ``(T, n, n)``,
    and the availability ``mask (T, p)`` it was computed for."""

    gains: jax.Array
    whitening: jax.Array
    log_norm: jax.Array
    covs: jax.Array
    predicted_covs: jax.Array
    mask: jax.Array


def covariance_sequence(
    model: LinearGaussianSSM, n_steps: int, *, mask: Any = None, form: str = "joseph"
) -> CovarianceSequence:
    """Run the covariance recursion once for ``n_steps`` steps (availability ``mask (T,)``/``(T, p)``)."""
    p = model.n_outputs
    dummy = jnp.zeros((n_steps, p), dtype=jnp.result_type(model.m0, float))
    res = kalman_filter(model, dummy, mask=mask, form=form)
    _, m = prepare_measurements(dummy, p, mask)
    return _sequence(model, res.predicted_covs, res.covs, m)


@jax.jit
def _sequence(model, pred_covs, covs, m) -> CovarianceSequence:
    tv = step_params(model)
    t = pred_covs.shape[0]
    H = at(model, tv, "H") if "H" in tv else jnp.broadcast_to(model.H, (t,) + model.H.shape)
    R = at(model, tv, "R") if "R" in tv else jnp.broadcast_to(model.R, (t,) + model.R.shape)

    def one(P, H_t, R_t, m_t):
        both = m_t[:, None] & m_t[None, :]
        h = jnp.where(m_t[:, None], H_t, 0.0)
        r = jnp.where(both, R_t, jnp.eye(R_t.shape[0], dtype=R_t.dtype))
        s = h @ P @ h.T + r
        chol = jnp.linalg.cholesky(0.5 * (s + s.T))
        k = jax.scipy.linalg.cho_solve((chol, True), h @ P).T
        w = jax.scipy.linalg.solve_triangular(chol, jnp.eye(s.shape[0], dtype=s.dtype), lower=True)
        w = jnp.where(m_t[:, None], w, 0.0)
        log_norm = -0.5 * (2.0 * jnp.sum(jnp.log(jnp.diagonal(chol))) + jnp.sum(m_t) * LOG_2PI)
        return k, w, log_norm

    gains, whitening, log_norm = jax.vmap(one)(pred_covs, H, R, m)
    return CovarianceSequence(gains, whitening, log_norm, covs, pred_covs, m)


class MeanFilterResult(NamedTuple):
    """``means (T, n)`` filtered means (or ``None`` with ``save_means=False``), ``log_likelihood ()``,
    ``final_mean (n,)`` the last filtered mean."""

    means: jax.Array | None
    log_likelihood: jax.Array
    final_mean: jax.Array


def mean_filter(
    model: LinearGaussianSSM, seq: CovarianceSequence, y: Any, u: Any = None, *, save_means: bool = True
) -> MeanFilterResult:
    """Filter one measurement sequence ``y (T, p)`` with precomputed gains (vmap it over runs); the
    model, ``seq``, ``y`` and ``u`` are cast to one float dtype as in ``kalman_filter``."""
    y = jnp.asarray(y)
    if y.ndim != 2 or y.shape != seq.mask.shape:
        raise ValueError(f"y: expected shape {tuple(seq.mask.shape)}, got {tuple(y.shape)}")
    (model, seq, y, u), _ = to_common_float((model, seq, y, None if u is None else jnp.asarray(u)))
    u = prepare_inputs(u, y.shape[0], model)
    return _mean_scan(model, seq, jnp.where(seq.mask, y, 0.0), u, save_means)


def _mean_scan(model, seq, y, u, save_means):
    tv = step_params(model)

    def step(m, x):
        y_t, k, w, ln, m_t, u_t, p = x
        H, F, B = at(model, p, "H"), at(model, p, "F"), at(model, p, "B")
        r = jnp.where(m_t, y_t - H @ m, 0.0)
        z = w @ r
        filt = m + k @ r
        nxt = F @ filt
        if B is not None and u_t is not None:
            nxt = nxt + B @ u_t
        return nxt, (filt if save_means else None, ln - 0.5 * jnp.dot(z, z), filt)

    xs = (y, seq.gains, seq.whitening, seq.log_norm, seq.mask, u, tv)
    _, (means, ll, filt) = jax.lax.scan(step, model.m0, xs)
    return MeanFilterResult(means, jnp.sum(ll), filt[-1])
