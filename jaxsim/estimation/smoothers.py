"""Rauch–Tung–Striebel smoothers: linear, extended and unscented, sharing one backward pass.

The backward pass needs, for every ``t < T − 1``, the filtered moments, the predicted moments of
``t + 1`` (both in the :class:`~jaxsim.estimation.types.FilterResult`) and the cross-covariance
``C_t = Cov(x_t, x_{t+1} | y_0..y_t)``: ``P_t Fᵀ`` for the linear filter, ``P_t (∂f/∂x)ᵀ`` for the
EKF, the sigma-point cross-covariance for the UKF.  Then ``G_t = C_t (P⁻_{t+1})⁻¹``,
``m^s_t = m_t + G_t (m^s_{t+1} − m⁻_{t+1})``, ``P^s_t = P_t + G_t (P^s_{t+1} − P⁻_{t+1}) G_tᵀ``.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.estimation import kalman
from jaxsim.estimation.ekf import extended_kalman_filter
from jaxsim.estimation.lgssm import LinearGaussianSSM, is_time_varying, kalman_filter
from jaxsim.estimation.nonlinear import NonlinearSSM
from jaxsim.estimation.types import FilterResult, SmootherResult
from jaxsim.estimation.ukf import MerweScaledSigmaPoints, SigmaPointScheme, sigma_point_filter, unscented_transform


def rts_backward(filtered: FilterResult, cross: jax.Array) -> SmootherResult:
    """Backward RTS pass from a forward run and the cross-covariances ``cross (T − 1, n, n)``."""

    def step(carry, x):
        ms_next, ps_next = carry
        m, P, m_pred, P_pred, c = x
        chol = jnp.linalg.cholesky(kalman.symmetrize(P_pred))
        g = jax.scipy.linalg.cho_solve((chol, True), c.T).T
        ms = m + g @ (ms_next - m_pred)
        ps = kalman.symmetrize(P + g @ (ps_next - P_pred) @ g.T)
        return (ms, ps), (ms, ps, g)

    xs = (filtered.means[:-1], filtered.covs[:-1], filtered.predicted_means[1:], filtered.predicted_covs[1:], cross)
    last = (filtered.means[-1], filtered.covs[-1])
    _, (ms, ps, gains) = jax.lax.scan(step, last, xs, reverse=True)
    return SmootherResult(
        means=jnp.concatenate([ms, last[0][None]]),
        covs=jnp.concatenate([ps, last[1][None]]),
        gains=gains,
        filtered=filtered,
    )


def rts_smoother(
    model: LinearGaussianSSM,
    y: Any,
    u: Any = None,
    *,
    mask: Any = None,
    missing: str = "error",
    form: str = "joseph",
    gate: float | None = None,
) -> SmootherResult:
    """Kalman filter + RTS smoother (arguments as :func:`~jaxsim.estimation.lgssm.kalman_filter`)."""
    filtered = kalman_filter(model, y, u, mask=mask, missing=missing, form=form, gate=gate)
    F = model.F[:-1] if is_time_varying(model, "F") else model.F
    cross = filtered.covs[:-1] @ jnp.swapaxes(F, -1, -2)
    return rts_backward(filtered, cross)


def _inputs(u: Any, t: int) -> Any:
    return None if u is None else jnp.asarray(u)[: t - 1]


def extended_rts_smoother(
    model: NonlinearSSM,
    y: Any,
    u: Any = None,
    *,
    mask: Any = None,
    missing: str = "error",
    form: str = "joseph",
    gate: float | None = None,
) -> SmootherResult:
    """EKF + RTS with Jacobians of ``f`` at the filtered means."""
    filtered = extended_kalman_filter(model, y, u, mask=mask, missing=missing, form=form, gate=gate)

    def cross(m, P, u_t):
        F = jax.jacfwd(lambda x: model.f(x, u_t))(m)
        return P @ F.T

    t = filtered.means.shape[0]
    c = jax.vmap(cross)(filtered.means[:-1], filtered.covs[:-1], _inputs(u, t))
    return rts_backward(filtered, c)


def sigma_point_rts_smoother(
    model: NonlinearSSM,
    y: Any,
    u: Any = None,
    *,
    scheme: SigmaPointScheme,
    mask: Any = None,
    missing: str = "error",
    gate: float | None = None,
) -> SmootherResult:
    """Sigma-point filter + RTS with sigma-point cross-covariances (any scheme)."""
    filtered = sigma_point_filter(model, y, u, scheme=scheme, mask=mask, missing=missing, gate=gate)

    def cross(m, P, u_t):
        return unscented_transform(scheme, m, P, lambda x: model.f(x, u_t))[2]

    t = filtered.means.shape[0]
    c = jax.vmap(cross)(filtered.means[:-1], filtered.covs[:-1], _inputs(u, t))
    return rts_backward(filtered, c)


def unscented_rts_smoother(
    model: NonlinearSSM,
    y: Any,
    u: Any = None,
    *,
    alpha: float = 1.0,
    beta: float = 2.0,
    kappa: float = 0.0,
    mask: Any = None,
    missing: str = "error",
    gate: float | None = None,
) -> SmootherResult:
    """UKF + unscented RTS smoother with Merwe scaled sigma points."""
    return sigma_point_rts_smoother(
        model, y, u, scheme=MerweScaledSigmaPoints(alpha, beta, kappa), mask=mask, missing=missing, gate=gate
    )
