"""Adapters that plug a filter into :class:`jaxsim.core.system.Estimator` for the closed-loop rollout.

The rollout calls ``update(params, state, y)`` when a measurement arrives (selected by a mask),
``read(params, state)`` to feed the controller, and ``predict(params, state, u, dt)`` once per
controller tick with the held control ``u``.  The model must be discretised at the controller
period (``dt`` is not used by these discrete filters).

:func:`filter_estimator` turns any :class:`~jaxsim.estimation.filtering.FilterMember` (the Gaussian
filters' one interface, shared with the scanned filters and the IMM) into an ``Estimator``;
:func:`kalman_estimator`, :func:`ekf_estimator` and :func:`ukf_estimator` are it applied to the
Kalman, extended and unscented members of a model.

``read="mean"`` gives the controller the state estimate ``(n,)``; ``read="output"`` the estimated
output ``H m`` (linear) or ``h(m)`` (nonlinear), a drop-in for the measurement a controller expects.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.pytree import pytree_dataclass
from jaxsim.core.system import Estimator
from jaxsim.core.validation import check_covariance, check_finite
from jaxsim.estimation import kalman
from jaxsim.estimation.ekf import ekf_member
from jaxsim.estimation.filtering import FilterMember
from jaxsim.estimation.lgssm import LinearGaussianSSM, linear_member, validate_model
from jaxsim.estimation.nonlinear import NonlinearSSM
from jaxsim.estimation.types import GaussianState
from jaxsim.estimation.ukf import ukf_member

READS = ("mean", "output")


def _check_read(read: str) -> None:
    if read not in READS:
        raise ValueError(f"read: expected one of {READS}, got {read!r}")


@pytree_dataclass
class FilterEstimatorParams:
    """The filter (a :class:`~jaxsim.estimation.filtering.FilterMember`) and its initial belief
    ``N(m0 (n,), P0 (n, n))``."""

    member: FilterMember
    m0: jax.Array
    P0: jax.Array


def _init(p: FilterEstimatorParams, y0: jax.Array) -> GaussianState:
    return GaussianState(p.m0, p.P0)


def _predict(p: FilterEstimatorParams, state: GaussianState, u: jax.Array, dt: Any) -> GaussianState:
    return p.member.predict(p.member.params, state, u)


def _update(p: FilterEstimatorParams, state: GaussianState, y: jax.Array) -> GaussianState:
    return p.member.update(p.member.params, state, y, None)[0]


def _read_mean(p: FilterEstimatorParams, state: GaussianState) -> jax.Array:
    return state.mean


def _read_output(p: FilterEstimatorParams, state: GaussianState) -> jax.Array:
    return p.member.observe(p.member.params, state.mean)


def filter_estimator(member: FilterMember, m0: Any, P0: Any, *, read: str = "mean", name: str = "filter") -> Estimator:
    """Any :class:`~jaxsim.estimation.filtering.FilterMember` as a closed-loop :class:`Estimator`
    starting from ``N(m0 (n,), P0 (n, n))``; ``read`` ``"mean"`` (``(n,)``) or ``"output"``
    (``member.observe`` of the mean, ``(p,)``; the member must define ``observe``).  Every
    measurement the rollout delivers is used in full (no mask)."""
    _check_read(read)
    if not isinstance(member, FilterMember):
        raise ValueError(f"member: expected a FilterMember, got {type(member).__name__}")
    if read == "output" and member.observe is None:
        raise ValueError("read: 'output' needs the member's observe function (it is None)")
    m0 = jnp.asarray(m0)
    if m0.ndim != 1:
        raise ValueError(f"m0: expected shape (n,), got {tuple(m0.shape)}")
    check_finite("m0", m0)
    check_covariance("P0", P0, m0.shape[0])
    params = FilterEstimatorParams(member, m0, jnp.asarray(P0))
    return Estimator(params, _init, _predict, _update, _read_mean if read == "mean" else _read_output, name=name)


def kalman_estimator(model: LinearGaussianSSM, *, form: str = "joseph", read: str = "mean") -> Estimator:
    """A time-invariant Kalman filter as an :class:`Estimator` (``form`` ``"joseph"``/``"standard"``)."""
    validate_model(model)
    if any(jnp.ndim(getattr(model, k)) == 3 for k in ("F", "Q", "H", "R")):
        raise ValueError("model: time-varying matrices are not supported by the closed-loop adapter")
    if form not in kalman.UPDATE_FORMS:
        raise ValueError(f"form: expected one of {kalman.UPDATE_FORMS}, got {form!r}")
    _check_read(read)
    member = linear_member(model.F, model.Q, model.H, model.R, model.B, form=form)
    return filter_estimator(member, model.m0, model.P0, read=read, name=f"kalman_{form}")


def ekf_estimator(model: NonlinearSSM, *, read: str = "mean") -> Estimator:
    """An EKF as an :class:`Estimator` (``model.transition`` receives the held control as ``u``)."""
    _check_read(read)
    return filter_estimator(ekf_member(model), model.m0, model.P0, read=read, name="ekf")


def ukf_estimator(
    model: NonlinearSSM, *, alpha: float = 1.0, beta: float = 2.0, kappa: float = 0.0, read: str = "mean"
) -> Estimator:
    """A UKF (Merwe scaled sigma points; admissible ranges in
    :class:`~jaxsim.estimation.ukf.MerweScaledSigmaPoints`) as an :class:`Estimator`."""
    _check_read(read)
    return filter_estimator(ukf_member(model, alpha, beta, kappa), model.m0, model.P0, read=read, name="ukf")


# Luenberger observer (current form) ---------------------------------------------------------


@pytree_dataclass
class LuenbergerParams:
    """``A (n, n)``, ``B (n, m)``, ``C (p, n)``, current-form gain ``L (n, p)``, initial ``x0 (n,)``."""

    A: jax.Array
    B: jax.Array
    C: jax.Array
    L: jax.Array
    x0: jax.Array


def _lu_init(p, y0):
    return p.x0


def _lu_predict(p, x, u, dt):
    return p.A @ x + p.B @ u


def _lu_update(p, x, y):
    return x + p.L @ (y - p.C @ x)


def _lu_read_mean(p, x):
    return x


def _lu_read_output(p, x):
    return p.C @ x


def luenberger_estimator(A: Any, B: Any, C: Any, L: Any, x0: Any, *, read: str = "mean") -> Estimator:
    """A discrete Luenberger observer in current form (``L`` from
    :func:`~jaxsim.estimation.observers.current_observer_gain`) as an :class:`Estimator`."""
    _check_read(read)
    p = LuenbergerParams(*(jnp.asarray(v) for v in (A, B, C, L, x0)))
    n = p.A.shape[0]
    if (
        p.A.shape != (n, n)
        or p.B.shape[0] != n
        or p.C.shape[1] != n
        or p.L.shape != (n, p.C.shape[0])
        or p.x0.shape != (n,)
    ):
        raise ValueError(
            f"A, B, C, L, x0: inconsistent shapes {p.A.shape}, {p.B.shape}, {p.C.shape}, {p.L.shape}, {p.x0.shape}"
        )
    return Estimator(
        p, _lu_init, _lu_predict, _lu_update, _lu_read_mean if read == "mean" else _lu_read_output, name="luenberger"
    )
