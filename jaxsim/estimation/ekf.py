"""Extended Kalman filter: the linear steps applied to Jacobians taken by ``jax.jacfwd``.

Step-wise use takes closures ``fx(x) -> x_next`` and ``hx(x) -> y``; the scanned
:func:`extended_kalman_filter` takes a :class:`~jaxsim.estimation.nonlinear.NonlinearSSM`.  On a
linear model the EKF *is* the Kalman filter (same arithmetic).
"""

from __future__ import annotations

import functools
from typing import Any, Callable

import jax
import jax.numpy as jnp

from jaxsim.estimation import kalman
from jaxsim.estimation.filtering import check_gate, scan_filter
from jaxsim.estimation.lgssm import prepare_measurements
from jaxsim.estimation.nonlinear import NonlinearSSM, common_float_nonlinear, validate_nonlinear
from jaxsim.estimation.types import FilterResult, GaussianState, Innovation


def ekf_predict(state: GaussianState, fx: Callable[[jax.Array], jax.Array], Q: jax.Array) -> GaussianState:
    """``m⁻ = f(m)``, ``P⁻ = F P Fᵀ + Q`` with ``F = ∂f/∂x`` at ``m``."""
    mean, F = fx(state.mean), jax.jacfwd(fx)(state.mean)
    return GaussianState(mean, kalman.propagate_covariance(state.cov, F, Q))


def ekf_update(
    state: GaussianState,
    y: jax.Array,
    hx: Callable[[jax.Array], jax.Array],
    R: jax.Array,
    *,
    mask: jax.Array | bool | None = None,
    form: str = "joseph",
) -> tuple[GaussianState, Innovation]:
    """Update with ``y (p,)``: residual ``y − h(m)``, ``H = ∂h/∂x`` at ``m`` (masked entries ignored)."""
    m = kalman.full_mask(y.shape[0], mask)
    y = jnp.where(m, y, 0.0)
    H = jax.jacfwd(hx)(state.mean)
    return kalman.condition(state, y - hx(state.mean), H, R, mask=m, form=form)


def extended_kalman_filter(
    model: NonlinearSSM,
    y: Any,
    u: Any = None,
    *,
    mask: Any = None,
    missing: str = "error",
    form: str = "joseph",
    gate: float | None = None,
) -> FilterResult:
    """Scanned EKF over ``y (T, p)``; arguments (including the cast to one float dtype) as
    :func:`~jaxsim.estimation.lgssm.kalman_filter`."""
    gate = check_gate(gate)
    validate_nonlinear(model)
    model, y, u, _ = common_float_nonlinear(model, y, u)
    y, m = prepare_measurements(y, model.n_outputs, mask, missing)
    return _ekf_scan(model, y, m, u, form, gate)


@functools.partial(jax.jit, static_argnames=("form", "gate"))
def _ekf_scan(model: NonlinearSSM, y, m, u, form: str, gate: float | None) -> FilterResult:
    def update(state, y_t, m_t, _):
        return ekf_update(state, y_t, model.h, model.R, mask=m_t, form=form)

    def predict(state, u_t, _):
        return ekf_predict(state, lambda x: model.f(x, u_t), model.Q)

    return scan_filter(GaussianState(model.m0, model.P0), predict, update, y, m, u, None, gate)
