"""Parallel-in-time Kalman filter and RTS smoother by associative scan (Särkkä & García-Fernández,
*Temporal parallelization of Bayesian smoothers*, IEEE TAC 2021).

Same model, arguments and results as :func:`~jaxsim.estimation.lgssm.kalman_filter` /
:func:`~jaxsim.estimation.smoothers.rts_smoother` (the serial-only options ``form`` and ``gate`` are
absent: a gate decides on the running state, which a parallel prefix cannot).  ``O(log T)`` depth
instead of ``O(T)``: it pays on accelerators and long horizons; on a CPU the serial scan is
usually faster.  Masking works as in the serial filter (masked components decoupled exactly).

Filtering element of step ``t`` (with ``c = B u_{t−1}``, the prior of ``x_0`` for ``t = 0``)::

    S = H Q Hᵀ + R,  K = Q Hᵀ S⁻¹,  A = (I − K H) F,  b = c + K (y − H c),  C = (I − K H) Q,
    η = Fᵀ Hᵀ S⁻¹ (y − H c),  J = Fᵀ Hᵀ S⁻¹ H F

combined by ``(A, b, C, η, J)ᵢ ⊗ (A, b, C, η, J)ⱼ`` (eqs. 14–15 of the paper).  Log-likelihood
and innovations are computed afterwards from the filtered moments, in parallel over ``t``.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.estimation import kalman
from jaxsim.estimation.lgssm import (
    LinearGaussianSSM,
    at,
    common_float_model,
    is_time_varying,
    prepare_inputs,
    prepare_measurements,
    step_params,
    validate_model,
)
from jaxsim.estimation.types import FilterResult, GaussianState, SmootherResult


def _per_step(model: LinearGaussianSSM, t: int, u: jax.Array | None):
    """Per-step ``F_{t−1}, Q_{t−1}, c_{t−1}`` (transition *into* ``t``) and ``H_t, R_t`` stacks."""
    n = model.n_states
    tv = step_params(model)

    def stack(name):
        v = at(model, tv, name)
        return v if name in tv else jnp.broadcast_to(v, (t,) + v.shape)

    F, Q, H, R = stack("F"), stack("Q"), stack("H"), stack("R")
    if u is not None:
        B = stack("B")
        c = jnp.einsum("tij,tj->ti", B, u)
    else:
        c = jnp.zeros((t, n), dtype=model.m0.dtype)
    # shift the transition by one step: element t uses the transition from t−1 into t
    shift = lambda a: jnp.concatenate([jnp.zeros_like(a[:1]), a[:-1]])  # noqa: E731
    return shift(F), shift(Q), shift(c), H, R


def _filter_elements(model, y, mask, F, Q, c, H, R):
    n = model.n_states
    eye = jnp.eye(n, dtype=model.m0.dtype)

    def element(y_t, m_t, F_t, Q_t, c_t, H_t, R_t, first):
        res, h, r = kalman.mask_measurement(y_t, H_t, R_t, m_t)
        F_e = jnp.where(first, jnp.zeros_like(F_t), F_t)
        # symmetrised as the serial filter's F P Fᵀ + Q is: the result (and its gradient in Q) then
        # depends on the symmetric part only, as there
        Q_e = jnp.where(first, model.P0, kalman.symmetrize(Q_t))
        c_e = jnp.where(first, model.m0, c_t)
        s = kalman.symmetrize(h @ Q_e @ h.T + r)
        chol = jnp.linalg.cholesky(s)
        k = jax.scipy.linalg.cho_solve((chol, True), h @ Q_e).T
        ikh = eye - k @ h
        A = ikh @ F_e
        b = c_e + k @ (res - h @ c_e)
        C = kalman.symmetrize(ikh @ Q_e @ ikh.T + k @ r @ k.T)
        hf = h @ F_e
        sinv_hf = jax.scipy.linalg.cho_solve((chol, True), hf)
        eta = sinv_hf.T @ (res - h @ c_e)
        J = kalman.symmetrize(hf.T @ sinv_hf)
        return A, b, C, eta, J

    first = jnp.arange(y.shape[0]) == 0
    return jax.vmap(element)(y, mask, F, Q, c, H, R, first)


def _combine_filter(ei, ej):
    """``ei ⊗ ej`` for one pair of elements (``i`` earlier in time)."""
    Ai, bi, Ci, eta_i, Ji = ei
    Aj, bj, Cj, eta_j, Jj = ej
    eye = jnp.eye(Ai.shape[-1], dtype=Ai.dtype)
    w = eye + Ci @ Jj  # (I + C_i J_j); (I + J_j C_i) = wᵀ with C, J symmetric
    A = Aj @ jnp.linalg.solve(w, Ai)
    b = Aj @ jnp.linalg.solve(w, bi + Ci @ eta_j) + bj
    C = Aj @ jnp.linalg.solve(w, Ci) @ Aj.T + Cj
    v = w.T
    eta = Ai.T @ jnp.linalg.solve(v, eta_j - Jj @ bi) + eta_i
    J = Ai.T @ jnp.linalg.solve(v, Jj) @ Ai + Ji
    return A, b, kalman.symmetrize(C), eta, kalman.symmetrize(J)


_filter_operator = jax.vmap(_combine_filter)


def parallel_kalman_filter(
    model: LinearGaussianSSM, y: Any, u: Any = None, *, mask: Any = None, missing: str = "error"
) -> FilterResult:
    """Kalman filter by associative scan; same results (and the same cast to one float dtype) as the
    serial ``kalman_filter``."""
    return _parallel_filter(*_prepare(model, y, u, mask, missing))


def _prepare(model: LinearGaussianSSM, y: Any, u: Any, mask: Any, missing: str):
    """Validated ``(model, y, mask, u)`` in one float dtype, as the serial filter prepares them."""
    validate_model(model, n_steps=int(jnp.shape(y)[0]) if jnp.ndim(y) >= 1 else None)
    model, y, u = common_float_model(model, y, u)
    y, m = prepare_measurements(y, model.n_outputs, mask, missing)
    return model, y, m, prepare_inputs(u, y.shape[0], model)


@jax.jit
def _parallel_filter(model: LinearGaussianSSM, y: jax.Array, m: jax.Array, u: jax.Array | None) -> FilterResult:
    t = y.shape[0]
    F, Q, c, H, R = _per_step(model, t, u)
    elems = _filter_elements(model, y, m, F, Q, c, H, R)
    _, means, covs, _, _ = jax.lax.associative_scan(_filter_operator, elems)

    # priors of each step from the previous filtered moments, then the innovations in parallel
    pred = jax.vmap(kalman.predict)(GaussianState(means[:-1], covs[:-1]), F[1:], Q[1:])
    pred_means = jnp.concatenate([model.m0[None], pred.mean + c[1:]])
    pred_covs = jnp.concatenate([model.P0[None], pred.cov])

    def innovation(mean, cov, y_t, m_t, H_t, R_t):
        return kalman.update(GaussianState(mean, cov), y_t, H_t, R_t, mask=m_t)[1]

    innov = jax.vmap(innovation)(pred_means, pred_covs, y, m, H, R)
    return FilterResult(
        means=means,
        covs=covs,
        predicted_means=pred_means,
        predicted_covs=pred_covs,
        log_likelihood=jnp.sum(innov.log_likelihood),
        log_likelihoods=innov.log_likelihood,
        innovations=innov.residual,
        innovation_covs=innov.cov,
        nis=innov.nis,
        dof=innov.dof,
        accepted=jnp.any(m, axis=1),
    )


def _combine_smoother(later, earlier):
    """Compose the backward maps: ``x_earlier = E₂ (E₁ x + g₁) + g₂`` (``reverse=True`` scan order)."""
    E1, g1, L1 = later
    E2, g2, L2 = earlier
    return E2 @ E1, E2 @ g1 + g2, kalman.symmetrize(E2 @ L1 @ E2.T + L2)


_smoother_operator = jax.vmap(_combine_smoother)


def parallel_rts_smoother(
    model: LinearGaussianSSM, y: Any, u: Any = None, *, mask: Any = None, missing: str = "error"
) -> SmootherResult:
    """RTS smoother by associative scan over the parallel filter; same results as ``rts_smoother``."""
    model, y, m, u = _prepare(model, y, u, mask, missing)
    return _parallel_smooth(model, _parallel_filter(model, y, m, u))


@jax.jit
def _parallel_smooth(model: LinearGaussianSSM, filtered: FilterResult) -> SmootherResult:
    t = filtered.means.shape[0]
    F_next = model.F[:-1] if is_time_varying(model, "F") else jnp.broadcast_to(model.F, (t - 1,) + model.F.shape)
    cross = filtered.covs[:-1] @ jnp.swapaxes(F_next, -1, -2)
    P_pred = filtered.predicted_covs[1:]
    chol = jnp.linalg.cholesky(P_pred)
    gains = jnp.swapaxes(jax.vmap(lambda c, l: jax.scipy.linalg.cho_solve((l, True), c.T))(cross, chol), -1, -2)
    g = filtered.means[:-1] - (gains @ filtered.predicted_means[1:, :, None])[..., 0]
    L = kalman.symmetrize(filtered.covs[:-1] - gains @ P_pred @ jnp.swapaxes(gains, -1, -2))
    n = model.n_states
    E = jnp.concatenate([gains, jnp.zeros((1, n, n), dtype=gains.dtype)])
    g = jnp.concatenate([g, filtered.means[-1:]])
    L = jnp.concatenate([L, filtered.covs[-1:]])
    _, means, covs = jax.lax.associative_scan(_smoother_operator, (E, g, L), reverse=True)
    return SmootherResult(means=means, covs=covs, gains=gains, filtered=filtered)
