"""Sigma-point (unscented) Kalman filter with the scaled sigma points of van der Merwe.

Points ``m``, ``m ± √(n+λ) Lᵢ`` (``Lᵢ`` the columns of ``chol(P)``), ``λ = α²(n+κ) − n``; mean weights
``W₀ = λ/(n+λ)``, ``Wᵢ = 1/(2(n+λ))``; covariance weight ``W₀ᶜ = W₀ + 1 − α² + β`` — FilterPy's
``MerweScaledSigmaPoints``.  Any object with ``points(mean, cov)`` and ``weights(n)`` works as a
scheme (see :mod:`jaxsim.estimation.cubature`).

:func:`sigma_point_member` binds a model and a scheme to the steps as a
:class:`~jaxsim.estimation.filtering.FilterMember` (:func:`ukf_member` with Merwe points), used by
the scanned :func:`sigma_point_filter`, the IMM and the closed-loop adapter alike.

The update redraws sigma points from the predicted ``(m⁻, P⁻)`` (FilterPy's ``update`` instead reuses
the points propagated by ``predict``; the two agree when ``Q = 0`` or after a redraw).
"""

from __future__ import annotations

import functools
from typing import Any, Callable, Protocol

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.pytree import pytree_dataclass
from jaxsim.core.validation import check_finite, check_positive, is_concrete
from jaxsim.estimation import kalman
from jaxsim.estimation.filtering import FilterMember, check_gate, scan_member
from jaxsim.estimation.lgssm import prepare_measurements
from jaxsim.estimation.nonlinear import NonlinearSSM, common_float_nonlinear, validate_nonlinear
from jaxsim.estimation.types import FilterResult, GaussianState, Innovation


class SigmaPointScheme(Protocol):
    def points(self, mean: jax.Array, cov: jax.Array) -> jax.Array: ...
    def weights(self, n: int) -> tuple[jax.Array, jax.Array]: ...


# n + λ below this multiple of n·ε leaves the weights 1/(n + λ) and W₀ = 1 − n/(n + λ) with fewer
# than three significant digits in the weighted sums (ε of the filter's float type)
_MIN_SPREAD_EPS = 1e3


@pytree_dataclass
class MerweScaledSigmaPoints:
    """``2n + 1`` scaled sigma points; ``alpha``, ``beta``, ``kappa`` are array leaves (tunable).

    Admissible values (checked by :func:`check_merwe` at every public filter boundary on concrete
    values): ``alpha`` finite and ``> 0`` (usually ``1e-3 ≤ α ≤ 1``), ``beta`` finite (2 is optimal
    for a Gaussian prior), ``kappa`` finite with ``n + κ > 0`` (usually ``0`` or ``3 − n``), and the
    spread ``n + λ = α²(n + κ)`` above ``10³·ε·n`` (``ε`` the float type's epsilon: about
    ``2·10⁻¹³ n`` in float64, ``10⁻⁴ n`` in float32).  Traced values are not checked: ``α = 0`` or
    ``n + κ ≤ 0`` under ``jit``/``vmap`` give inf/NaN weights and NaN estimates.
    """

    alpha: Any = 1.0
    beta: Any = 2.0
    kappa: Any = 0.0

    def _spread(self, n: int) -> jax.Array:
        """``n + λ = α²(n + κ)``, formed without the cancellation of ``λ = α²(n + κ) − n``."""
        return jnp.asarray(self.alpha) ** 2 * (n + jnp.asarray(self.kappa))

    def points(self, mean: jax.Array, cov: jax.Array) -> jax.Array:
        """Sigma points ``(2n + 1, n)``: ``[m, m + √(n+λ) Lᵢ…, m − √(n+λ) Lᵢ…]``."""
        n = mean.shape[0]
        scaled = jnp.linalg.cholesky(self._spread(n) * kalman.symmetrize(cov))
        return jnp.concatenate([mean[None], mean[None] + scaled.T, mean[None] - scaled.T], axis=0)

    def weights(self, n: int) -> tuple[jax.Array, jax.Array]:
        """Mean and covariance weights, each ``(2n + 1,)``."""
        c = self._spread(n)
        wi = jnp.full((2 * n,), 0.5 / c)
        w0 = 1.0 - n / c  # λ/(n + λ)
        w0c = w0 + 1.0 - jnp.asarray(self.alpha) ** 2 + jnp.asarray(self.beta)
        return jnp.concatenate([jnp.atleast_1d(w0), wi]), jnp.concatenate([jnp.atleast_1d(w0c), wi])


def check_merwe(scheme: Any, n: int, dtype: Any = float) -> None:
    """Check the parameters of a :class:`MerweScaledSigmaPoints` for state dimension ``n`` (other
    schemes pass); ``ValueError`` naming ``alpha``, ``beta`` or ``kappa`` and the bad value."""
    if not isinstance(scheme, MerweScaledSigmaPoints):
        return
    check_positive("alpha", scheme.alpha)
    check_finite("beta", scheme.beta)
    check_finite("kappa", scheme.kappa)
    if not is_concrete((scheme.alpha, scheme.kappa)):
        return
    alpha, kappa = np.asarray(scheme.alpha, dtype=float), np.asarray(scheme.kappa, dtype=float)
    floor = _MIN_SPREAD_EPS * np.finfo(dtype).eps * n
    if np.any(n + kappa <= floor):
        raise ValueError(
            f"kappa: n + kappa must be > 0 (the sigma-point spread n + λ = α²(n + κ)), "
            f"got kappa={scheme.kappa!r} for n={n}"
        )
    spread = alpha**2 * (n + kappa)
    if np.any(spread <= floor):
        raise ValueError(
            f"alpha: too small, n + λ = α²(n + κ) = {float(np.min(spread)):.3g} ≈ 0 for "
            f"n={n} (weights 1/(n + λ) blow up; need > {floor:.3g}), got alpha={scheme.alpha!r}"
        )


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


def _predict(params: tuple, state: GaussianState, u: Any) -> GaussianState:
    model, scheme = params
    return ukf_predict(state, lambda x: model.f(x, u), model.Q, scheme)


def _update(params: tuple, state: GaussianState, y: jax.Array, mask: jax.Array) -> tuple[GaussianState, Innovation]:
    model, scheme = params
    return ukf_update(state, y, model.h, model.R, scheme, mask=mask)


def _observe(params: tuple, x: jax.Array) -> jax.Array:
    return params[0].h(x)


def _member(model: NonlinearSSM, scheme: SigmaPointScheme) -> FilterMember:
    return FilterMember((model, scheme), _predict, _update, model.n_outputs, _observe)


def sigma_point_member(model: NonlinearSSM, scheme: SigmaPointScheme) -> FilterMember:
    """The sigma-point filter of ``model`` with ``scheme`` (any object with ``points``/``weights``)
    as a :class:`~jaxsim.estimation.filtering.FilterMember`; ``params = (model, scheme)``
    (``model.m0, P0`` unused).  ``ValueError`` for a bad model or bad Merwe parameters."""
    validate_nonlinear(model)
    check_merwe(scheme, model.n_states)
    return _member(model, scheme)


def ukf_member(model: NonlinearSSM, alpha: float = 1.0, beta: float = 2.0, kappa: float = 0.0) -> FilterMember:
    """A UKF member (Merwe scaled sigma points; admissible ranges in :class:`MerweScaledSigmaPoints`)."""
    return sigma_point_member(model, MerweScaledSigmaPoints(alpha, beta, kappa))


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
    """Scanned sigma-point filter with any ``scheme`` (arguments, including the cast to one float
    dtype, as the linear filter's; the float leaves of ``scheme`` take part in the cast)."""
    gate = check_gate(gate)
    validate_nonlinear(model)
    model, y, u, scheme = common_float_nonlinear(model, y, u, scheme)
    check_merwe(scheme, model.n_states, model.m0.dtype)
    y, m = prepare_measurements(y, model.n_outputs, mask, missing)
    return _sigma_scan(model, scheme, y, m, u, gate)


@functools.partial(jax.jit, static_argnames=("gate",))
def _sigma_scan(model: NonlinearSSM, scheme: SigmaPointScheme, y, m, u, gate: float | None) -> FilterResult:
    return scan_member(_member(model, scheme), GaussianState(model.m0, model.P0), y, m, u, gate)


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
    """Scanned UKF with Merwe scaled sigma points ``(alpha, beta, kappa)`` (admissible ranges in
    :class:`MerweScaledSigmaPoints`; bad concrete values raise ``ValueError``)."""
    scheme = MerweScaledSigmaPoints(alpha, beta, kappa)
    return sigma_point_filter(model, y, u, scheme=scheme, mask=mask, missing=missing, gate=gate)
