"""Adapters that plug a filter into :class:`jaxsim.core.system.Estimator` for the closed-loop rollout.

The rollout calls ``update(params, state, y)`` when a measurement arrives (selected by a mask),
``read(params, state)`` to feed the controller, and ``predict(params, state, u, dt)`` once per
controller tick with the held control ``u``.  The model must be discretised at the controller
period (``dt`` is not used by these discrete filters).

``read="mean"`` gives the controller the state estimate ``(n,)``; ``read="output"`` the estimated
output ``H m`` (linear) or ``h(m)`` (nonlinear), a drop-in for the measurement a controller expects.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.pytree import pytree_dataclass
from jaxsim.core.system import Estimator
from jaxsim.estimation import kalman
from jaxsim.estimation.ekf import ekf_predict, ekf_update
from jaxsim.estimation.lgssm import LinearGaussianSSM, validate_model
from jaxsim.estimation.nonlinear import NonlinearSSM, validate_nonlinear
from jaxsim.estimation.types import GaussianState
from jaxsim.estimation.ukf import MerweScaledSigmaPoints, check_merwe, ukf_predict, ukf_update

READS = ("mean", "output")


def _check_read(read: str) -> None:
    if read not in READS:
        raise ValueError(f"read: expected one of {READS}, got {read!r}")


def _init(params, y0):
    model = params[0] if isinstance(params, tuple) else params
    return GaussianState(model.m0, model.P0)


def _read_mean(params, state):
    return state.mean


# linear Kalman filter ------------------------------------------------------------------------

def _kf_predict(model, state, u, dt):
    return kalman.predict(state, model.F, model.Q, model.B, u if model.B is not None else None)


def _kf_update_joseph(model, state, y):
    return kalman.update(state, y, model.H, model.R, form="joseph")[0]


def _kf_update_standard(model, state, y):
    return kalman.update(state, y, model.H, model.R, form="standard")[0]


def _kf_read_output(model, state):
    return model.H @ state.mean


def kalman_estimator(model: LinearGaussianSSM, *, form: str = "joseph", read: str = "mean") -> Estimator:
    """A time-invariant Kalman filter as an :class:`Estimator` (``form`` ``"joseph"``/``"standard"``)."""
    validate_model(model)
    if any(jnp.ndim(getattr(model, k)) == 3 for k in ("F", "Q", "H", "R")):
        raise ValueError("model: time-varying matrices are not supported by the closed-loop adapter")
    if form not in kalman.UPDATE_FORMS:
        raise ValueError(f"form: expected one of {kalman.UPDATE_FORMS}, got {form!r}")
    _check_read(read)
    update = _kf_update_joseph if form == "joseph" else _kf_update_standard
    return Estimator(model, _init, _kf_predict, update,
                     _read_mean if read == "mean" else _kf_read_output, name=f"kalman_{form}")


# extended and unscented ----------------------------------------------------------------------

def _ekf_pred(model, state, u, dt):
    return ekf_predict(state, lambda x: model.f(x, u), model.Q)


def _ekf_upd(model, state, y):
    return ekf_update(state, y, model.h, model.R)[0]


def _nl_read_output(params, state):
    model = params[0] if isinstance(params, tuple) else params
    return model.h(state.mean)


def ekf_estimator(model: NonlinearSSM, *, read: str = "mean") -> Estimator:
    """An EKF as an :class:`Estimator` (``model.transition`` receives the held control as ``u``)."""
    validate_nonlinear(model)
    _check_read(read)
    return Estimator(model, _init, _ekf_pred, _ekf_upd,
                     _read_mean if read == "mean" else _nl_read_output, name="ekf")


def _ukf_pred(params, state, u, dt):
    model, scheme = params
    return ukf_predict(state, lambda x: model.f(x, u), model.Q, scheme)


def _ukf_upd(params, state, y):
    model, scheme = params
    return ukf_update(state, y, model.h, model.R, scheme)[0]


def ukf_estimator(
    model: NonlinearSSM, *, alpha: float = 1.0, beta: float = 2.0, kappa: float = 0.0, read: str = "mean"
) -> Estimator:
    """A UKF (Merwe scaled sigma points; admissible ranges in
    :class:`~jaxsim.estimation.ukf.MerweScaledSigmaPoints`) as an :class:`Estimator`."""
    validate_nonlinear(model)
    _check_read(read)
    scheme = MerweScaledSigmaPoints(alpha, beta, kappa)
    check_merwe(scheme, model.n_states)
    return Estimator((model, scheme), _init, _ukf_pred, _ukf_upd,
                     _read_mean if read == "mean" else _nl_read_output, name="ukf")


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
    if p.A.shape != (n, n) or p.B.shape[0] != n or p.C.shape[1] != n or p.L.shape != (n, p.C.shape[0]) \
            or p.x0.shape != (n,):
        raise ValueError(
            f"A, B, C, L, x0: inconsistent shapes {p.A.shape}, {p.B.shape}, {p.C.shape}, {p.L.shape}, {p.x0.shape}"
        )
    return Estimator(p, _lu_init, _lu_predict, _lu_update,
                     _lu_read_mean if read == "mean" else _lu_read_output, name="luenberger")
