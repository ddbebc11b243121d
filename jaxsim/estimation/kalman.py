"""Linear Kalman predict and update steps: standard, Joseph and square-root (Cholesky) forms.

Model ``x_{t+1} = F x_t + B u_t + w_t``, ``w ~ N(0, Q)``; ``y_t = H x_t + v_t``, ``v ~ N(0, R)``.

Every step is a pure function of arrays (jit, vmap, grad, scan).  Missing components of a
measurement are handled by a boolean ``mask`` ``(p,)`` (``True`` = available): a masked component
gets a zero row in ``H``, a unit variance uncorrelated with the rest and a zero residual, which
makes the update (and the log-likelihood, once the ``log 2π`` of the dummy components is taken out)
*exactly* that of a filter that never saw those components.  ``mask=False`` for every component is a
pure prediction.

Update forms (``form=``):

* ``"joseph"`` (default): ``P⁺ = (I − KH) P (I − KH)ᵀ + K R Kᵀ`` — symmetric and PSD to rounding
  for any gain;
* ``"standard"``: ``P⁺ = P − K S Kᵀ`` (FilterPy's ``UnscentedKalmanFilter`` form);
* square-root: :func:`sqrt_predict` / :func:`sqrt_update` propagate a Cholesky factor by QR of the
  pre-arrays ``[F L, L_Q]ᵀ`` and ``[[L_R, H L], [0, L]]ᵀ`` (never forming ``P``).
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp

from jaxsim.estimation import linalg
from jaxsim.estimation.types import GaussianState, Innovation, SqrtGaussianState

LOG_2PI = math.log(2.0 * math.pi)
UPDATE_FORMS = ("joseph", "standard")


def symmetrize(m: jax.Array) -> jax.Array:
    """``(M + Mᵀ)/2`` on the last two axes."""
    return 0.5 * (m + jnp.swapaxes(m, -1, -2))


def full_mask(p: int, mask: jax.Array | bool | None) -> jax.Array:
    """A ``(p,)`` boolean availability mask from ``None`` (all available), a scalar or a ``(p,)``."""
    if mask is None:
        return jnp.ones((p,), dtype=bool)
    return jnp.broadcast_to(jnp.asarray(mask, dtype=bool), (p,))


def mask_measurement(
    residual: jax.Array, h: jax.Array | None, r: jax.Array, mask: jax.Array
) -> tuple[jax.Array, jax.Array | None, jax.Array]:
    """Decouple masked components: zero residual and ``H`` rows, unit uncorrelated noise."""
    both = mask[:, None] & mask[None, :]
    r_m = jnp.where(both, r, jnp.eye(r.shape[0], dtype=r.dtype))
    res_m = jnp.where(mask, residual, 0.0)
    h_m = None if h is None else jnp.where(mask[:, None], h, 0.0)
    return res_m, h_m, r_m


def innovation_stats(residual: jax.Array, chol_s: jax.Array, mask: jax.Array, s: jax.Array | None = None) -> Innovation:
    """NIS and Gaussian log-likelihood of ``residual`` given the Cholesky factor of ``S``."""
    z = linalg.solve_lower(chol_s, residual)
    nis = jnp.dot(z, z)
    dof = jnp.sum(mask)
    logdet = 2.0 * jnp.sum(jnp.log(jnp.abs(jnp.diagonal(chol_s))))
    ll = -0.5 * (nis + logdet + dof * LOG_2PI)
    if s is None:
        s = chol_s @ chol_s.T
    return Innovation(residual, s, ll, nis, dof)


def predict(
    state: GaussianState,
    F: jax.Array,
    Q: jax.Array,
    B: jax.Array | None = None,
    u: jax.Array | None = None,
) -> GaussianState:
    """``m⁻ = F m + B u``, ``P⁻ = F P Fᵀ + Q`` (shapes ``F (n, n)``, ``Q (n, n)``, ``B (n, m)``, ``u (m,)``)."""
    mean = F @ state.mean
    if B is not None and u is not None:
        mean = mean + B @ u
    return GaussianState(mean, propagate_covariance(state.cov, F, Q))


def propagate_covariance(P: jax.Array, F: jax.Array, Q: jax.Array) -> jax.Array:
    """``F P Fᵀ + Q``, symmetrised."""
    return symmetrize(linalg.matmul(linalg.matmul(F, P), F.T) + Q)


def condition(
    state: GaussianState,
    residual: jax.Array,
    H: jax.Array,
    R: jax.Array,
    *,
    mask: jax.Array | bool | None = None,
    form: str = "joseph",
) -> tuple[GaussianState, Innovation]:
    """Update on a given innovation ``residual = y − ŷ`` with the linear(ised) ``H (p, n)``, ``R (p, p)``.

    The linear update and the EKF both call this (the EKF with ``ŷ = h(m)``, ``H = ∂h/∂x``).
    """
    if form not in UPDATE_FORMS:
        raise ValueError(f"form: expected one of {UPDATE_FORMS}, got {form!r}")
    p = residual.shape[0]
    mask = full_mask(p, mask)
    res, h, r = mask_measurement(residual, H, R, mask)
    P = state.cov
    mm = linalg.matmul
    ph = mm(P, h.T)
    s = symmetrize(mm(h, ph) + r)
    chol_s = linalg.cholesky(s)
    k = linalg.cho_solve(chol_s, ph.T).T
    mean = state.mean + k @ res
    if form == "joseph":
        ikh = jnp.eye(P.shape[0], dtype=P.dtype) - mm(k, h)
        kr = mm(k, r)
        cov = mm(mm(ikh, P), ikh.T) + mm(kr, k.T)
    else:
        cov = P - mm(mm(k, s), k.T)
    return GaussianState(mean, symmetrize(cov)), innovation_stats(res, chol_s, mask, s)


def update(
    state: GaussianState,
    y: jax.Array,
    H: jax.Array,
    R: jax.Array,
    *,
    mask: jax.Array | bool | None = None,
    form: str = "joseph",
) -> tuple[GaussianState, Innovation]:
    """Measurement update with ``y (p,)``, ``H (p, n)``, ``R (p, p)``; returns the posterior and the
    :class:`Innovation`.  Masked components of ``y`` are ignored (they may hold NaN)."""
    p = y.shape[0]
    m = full_mask(p, mask)
    y = jnp.where(m, y, 0.0)
    return condition(state, y - H @ state.mean, H, R, mask=m, form=form)


def _positive_diag_lower(r_upper: jax.Array) -> jax.Array:
    """Lower factor ``Rᵀ`` of a QR with the signs fixed so the diagonal is non-negative."""
    low = r_upper.T
    sign = jnp.where(jnp.diagonal(low) < 0, -1.0, 1.0).astype(low.dtype)
    return low * sign[None, :]


def sqrt_predict(
    state: SqrtGaussianState,
    F: jax.Array,
    chol_Q: jax.Array,
    B: jax.Array | None = None,
    u: jax.Array | None = None,
) -> SqrtGaussianState:
    """Square-root prediction: ``L⁻ = tria([F L, L_Q])`` with ``chol_Q`` any ``(n, q)`` factor of ``Q``."""
    mean = F @ state.mean
    if B is not None and u is not None:
        mean = mean + B @ u
    pre = jnp.concatenate([F @ state.chol, chol_Q], axis=1)  # (n, n + q)
    r = jnp.linalg.qr(pre.T, mode="r")
    return SqrtGaussianState(mean, _positive_diag_lower(r[: F.shape[0]]))


def sqrt_update(
    state: SqrtGaussianState,
    y: jax.Array,
    H: jax.Array,
    chol_R: jax.Array,
    *,
    mask: jax.Array | bool | None = None,
) -> tuple[SqrtGaussianState, Innovation]:
    """Square-root update by QR of the pre-array ``[[L_R, H L], [0, L]]ᵀ``.

    ``chol_R`` is a ``(p, p)`` factor of ``R``.  Masked components are decoupled by replacing the
    noise factor with ``[D L_R, I − D]`` (``D`` the mask as a diagonal), still a factor of the masked
    ``R``.
    """
    p, n = H.shape
    m = full_mask(p, mask)
    y = jnp.where(m, y, 0.0)
    res = jnp.where(m, y - H @ state.mean, 0.0)
    h = jnp.where(m[:, None], H, 0.0)
    dm = m.astype(chol_R.dtype)
    noise = jnp.concatenate([chol_R * dm[:, None], jnp.diag(1.0 - dm)], axis=1)  # (p, 2p)
    top = jnp.concatenate([noise, h @ state.chol], axis=1)
    bottom = jnp.concatenate([jnp.zeros((n, 2 * p), dtype=top.dtype), state.chol], axis=1)
    pre = jnp.concatenate([top, bottom], axis=0)  # (p + n, 2p + n)
    post = _positive_diag_lower(jnp.linalg.qr(pre.T, mode="r")[: p + n])
    chol_s = post[:p, :p]
    kbar = post[p:, :p]  # K S^{1/2}
    chol_post = post[p:, p:]
    z = linalg.solve_lower(chol_s, res)
    mean = state.mean + kbar @ z
    return SqrtGaussianState(mean, chol_post), innovation_stats(res, chol_s, m)


def condition_moments(
    state: GaussianState,
    residual: jax.Array,
    S: jax.Array,
    cross: jax.Array,
    *,
    mask: jax.Array | bool | None = None,
) -> tuple[GaussianState, Innovation]:
    """Gaussian conditioning from moments: innovation ``residual (p,)``, its covariance ``S (p, p)``
    and the state–measurement cross-covariance ``cross (n, p)`` (sigma-point filters).

    ``P⁺ = P − K S Kᵀ`` with ``K = cross S⁻¹``; masked components are decoupled as in :func:`update`.
    """
    p = residual.shape[0]
    mask = full_mask(p, mask)
    res, _, s = mask_measurement(residual, None, S, mask)
    c = jnp.where(mask[None, :], cross, 0.0)
    s = symmetrize(s)
    chol_s = linalg.cholesky(s)
    k = linalg.cho_solve(chol_s, c.T).T
    mean = state.mean + k @ res
    cov = symmetrize(state.cov - k @ s @ k.T)
    return GaussianState(mean, cov), innovation_stats(res, chol_s, mask, s)
