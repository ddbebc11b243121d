"""Sigma-point (unscented) Kalman filter with the scaled sigma points of van der Merwe.

Points ``m``, ``m ± √(n+λ) Lᵢ`` (``Lᵢ`` the columns of ``chol(P)``), ``λ = α²(n+κ) − n``; mean weights
``W₀ = λ/(n+λ)``, ``Wᵢ = 1/(2(n+λ))``; covariance weight ``W₀ᶜ = W₀ + 1 − α² + β`` — FilterPy's
``MerweScaledSigmaPoints``.  Any object with ``points(mean, cov)`` and ``weights(n)`` works as a
scheme (see :mod:`jaxsim.estimation.cubature`).

The update redraws sigma points from the predicted ``(m⁻, P⁻)`` (FilterPy's ``update`` instead reuses
the points propagated by ``predict``; the two agree when ``Q = 0`` or after a redraw).
"""

from __future__ import annotations

import functools
from typing import Any, Callable, Protocol

import jax
import jax.numpy as jnp

from jaxsim.core.pytree import pytree_dataclass
from jaxsim.estimation import kalman
from jaxsim.estimation.filtering import scan_filter
from jaxsim.estimation.lgssm import prepare_measurements
from jaxsim.estimation.nonlinear import NonlinearSSM, validate_nonlinear
from jaxsim.estimation.types import FilterResult, GaussianState, Innovation


class SigmaPointScheme(Protocol):
    def points(self, mean: jax.Array, cov: jax.Array) -> jax.Array: ...
    def weights(self, n: int) -> tuple[jax.Array, jax.Array]: ...


@pytree_dataclass
class MerweScaledSigmaPoints:
    """``2n + 1`` scaled sigma points; ``alpha``, ``beta``, ``kappa`` are array leaves (tunable)."""

    alpha: Any = 1.0
    beta: Any = 2.0
    kappa: Any = 0.0

    def _lambda(self, n: int) -> jax.Array:
        return jnp.asarray(self.alpha) ** 2 * (n + jnp.asarray(self.kappa)) - n

    def points(self, mean: jax.Array, cov: jax.Array) -> jax.Array:
        """Sigma points ``(2n + 1, n)``: ``[m, m + √(n+λ) Lᵢ…, m − √(n+λ) Lᵢ…]``."""
        n = mean.shape[0]
        scaled = jnp.linalg.cholesky((n + self._lambda(n)) * kalman.symmetrize(cov))
        return jnp.concatenate([mean[None], mean[None] + scaled.T, mean[None] - scaled.T], axis=0)

    def weights(self, n: int) -> tuple[jax.Array, jax.Array]:
        """Mean and covariance weights, each ``(2n + 1,)``."""
        lam = self._lambda(n)
        wi = jnp.full((2 * n,), 0.5 / (n + lam))
        wm = jnp.concatenate([jnp.atleast_1d(lam / (n + lam)), wi])
        w0c = lam / (n + lam) + 1.0 - jnp.asarray(self.alpha) ** 2 + jnp.asarray(self.beta)
        return wm, jnp.concatenate([jnp.atleast_1d(w0c), wi])


def unscented_transform(
    scheme: SigmaPointScheme, mean: jax.Array, cov: jax.Array, fn: Callable[[jax.Array], jax.Array]
) -> tuple[jax.Array, jax.Array, jax.Array]:
    """Push ``N(mean, cov)`` through ``fn``: returns ``(mean_y, cov_y, cross_xy)`` (no noise added)."""
    x = scheme.points(mean, cov)
    wm, wc = scheme.weights(mean.shape[0])
    fy = jax.vmap(fn)(x)
    my = wm @ fy
    dy = fy - my
    dx = x - mean
    return my, (dy.T * wc) @ dy, (dx.T * wc) @ dy


def ukf_predict(
    state: GaussianState, fx: Callable[[jax.Array], jax.Array], Q: jax.Array, scheme: SigmaPointScheme
) -> GaussianState:
    """``m⁻ = Σ Wᵢ f(Xᵢ)``, ``P⁻ = Σ Wᵢᶜ (f(Xᵢ) − m⁻)(…)ᵀ + Q``."""
    mean, cov, _ = unscented_transform(scheme, state.mean, state.cov, fx)
    return GaussianState(mean, kalman.symmetrize(cov + Q))


def ukf_update(
    state: GaussianState,
    y: jax.Array,
    hx: Callable[[jax.Array], jax.Array],
    R: jax.Array,
    scheme: SigmaPointScheme,
    *,
    mask: jax.Array | bool | None = None,
) -> tuple[GaussianState, Innovation]:
    """Update with ``y (p,)`` from sigma points of the current belief (masked entries ignored)."""
    m = kalman.full_mask(y.shape[0], mask)
    y = jnp.where(m, y, 0.0)
    y_hat, s, cross = unscented_transform(scheme, state.mean, state.cov, hx)
    return kalman.condition_moments(state, y - y_hat, s + R, cross, mask=m)


def sigma_point_filter(
    model: NonlinearSSM,
    y: Any,
    u: Any = None,
    *,
    scheme: SigmaPointScheme,
    mask: Any = None,
    missing: str = "error",
    gate: float | None = None,
) -> FilterResult:
    """Scanned sigma-point filter with any ``scheme`` (arguments as the linear filter's)."""
    validate_nonlinear(model)
    y, m = prepare_measurements(y, model.n_outputs, mask, missing)
    u = None if u is None else jnp.asarray(u)
    return _sigma_scan(model, scheme, y, m, u, gate)


@functools.partial(jax.jit, static_argnames=("gate",))
def _sigma_scan(model: NonlinearSSM, scheme: SigmaPointScheme, y, m, u, gate: float | None) -> FilterResult:
    def update(state, y_t, m_t, _):
        return ukf_update(state, y_t, model.h, model.R, scheme, mask=m_t)

    def predict(state, u_t, _):
        return ukf_predict(state, lambda x: model.f(x, u_t), model.Q, scheme)

    return scan_filter(GaussianState(model.m0, model.P0), predict, update, y, m, u, None, gate)


def unscented_kalman_filter(
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
) -> FilterResult:
    """Scanned UKF with Merwe scaled sigma points ``(alpha, beta, kappa)``."""
    scheme = MerweScaledSigmaPoints(alpha, beta, kappa)
    return sigma_point_filter(model, y, u, scheme=scheme, mask=mask, missing=missing, gate=gate)
