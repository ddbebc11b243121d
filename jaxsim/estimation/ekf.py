"""Extended Kalman filter: the linear steps applied to Jacobians taken by ``jax.jacfwd``.

Step-wise use takes closures ``fx(x) -> x_next`` and ``hx(x) -> y``; :func:`ekf_member` binds them to a
:class:`~jaxsim.estimation.nonlinear.NonlinearSSM` as a :class:`~jaxsim.estimation.filtering.FilterMember`
(the one place the model meets the steps), which the scanned :func:`extended_kalman_filter`, the
IMM and the closed-loop adapter all use.  On a linear model the EKF *is* the Kalman filter (same
arithmetic).
"""

from __future__ import annotations

import functools
from typing import Any, Callable

import jax
import jax.numpy as jnp

from jaxsim.estimation import kalman
from jaxsim.estimation.filtering import FilterMember, check_gate, scan_member
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


def _predict(model: NonlinearSSM, state: GaussianState, u: Any) -> GaussianState:
    return ekf_predict(state, lambda x: model.f(x, u), model.Q)


def _update_joseph(model: NonlinearSSM, state: GaussianState, y: jax.Array, mask: jax.Array):
    return ekf_update(state, y, model.h, model.R, mask=mask, form="joseph")


def _update_standard(model: NonlinearSSM, state: GaussianState, y: jax.Array, mask: jax.Array):
    return ekf_update(state, y, model.h, model.R, mask=mask, form="standard")


def _observe(model: NonlinearSSM, x: jax.Array) -> jax.Array:
    return model.h(x)


# module-level functions, not partials: static fields must compare equal across rebuilt members
_UPDATES = {"joseph": _update_joseph, "standard": _update_standard}


def _member(model: NonlinearSSM, form: str) -> FilterMember:
    return FilterMember(model, _predict, _UPDATES[form], model.n_outputs, _observe)


def ekf_member(model: NonlinearSSM, *, form: str = "joseph") -> FilterMember:
    """The EKF of ``model`` as a :class:`~jaxsim.estimation.filtering.FilterMember` (``model.m0, P0``
    unused; ``form`` ``"joseph"``/``"standard"`` of the covariance update).  ``ValueError`` for a
    model that fails :func:`~jaxsim.estimation.nonlinear.validate_nonlinear` or an unknown ``form``."""
    validate_nonlinear(model)
    if form not in kalman.UPDATE_FORMS:
        raise ValueError(f"form: expected one of {kalman.UPDATE_FORMS}, got {form!r}")
    return _member(model, form)


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
    if form not in kalman.UPDATE_FORMS:
        raise ValueError(f"form: expected one of {kalman.UPDATE_FORMS}, got {form!r}")
    validate_nonlinear(model)
    model, y, u, _ = common_float_nonlinear(model, y, u)
    y, m = prepare_measurements(y, model.n_outputs, mask, missing)
    return _ekf_scan(model, y, m, u, form, gate)


@functools.partial(jax.jit, static_argnames=("form", "gate"))
def _ekf_scan(model: NonlinearSSM, y, m, u, form: str, gate: float | None) -> FilterResult:
    return scan_member(_member(model, form), GaussianState(model.m0, model.P0), y, m, u, gate)
