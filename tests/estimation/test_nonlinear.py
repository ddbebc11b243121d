"""EKF, UKF and cubature filter: equal to the KF on linear models; FilterPy's EKF/UKF/CKF as oracles."""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import filterpy.kalman as fk
import jax.numpy as jnp
import numpy as np
import pytest
from filterpy.kalman.CubatureKalmanFilter import spherical_radial_sigmas

from jaxsim.estimation.cubature import cubature_kalman_filter
from jaxsim.estimation.ekf import extended_kalman_filter
from jaxsim.estimation.lgssm import kalman_filter
from jaxsim.estimation.nonlinear import nonlinear_ssm
from jaxsim.estimation.ukf import unscented_kalman_filter
from tests.estimation.helpers import random_model, simulate_np

DT = 0.1


def pendulum_f(params, x, u):
    """Damped pendulum with a slowly decaying bias torque (x = [angle, rate, bias])."""
    return jnp.stack([x[0] + DT * x[1], x[1] - DT * (params["g"] * jnp.sin(x[0]) + 0.2 * x[1] - x[2]), 0.98 * x[2]])


def pendulum_h(params, x):
    return jnp.stack([jnp.sin(x[0]) + 0.5 * x[2], 0.5 * x[1] ** 2 + x[0]])


def pendulum_model():
    return nonlinear_ssm(
        pendulum_f,
        pendulum_h,
        Q=np.diag([1e-4, 4e-3, 1e-4]),
        R=np.diag([0.01, 0.02]),
        m0=np.array([0.8, 0.0, 0.1]),
        P0=np.diag([0.05, 0.05, 0.02]),
        params={"g": 9.81},
    )


def pendulum_data(t=25, seed=0):
    rng = np.random.default_rng(seed)
    m = pendulum_model()
    x = np.array([0.9, 0.1, 0.05])
    ys = []
    for _ in range(t):
        ys.append(np.asarray(pendulum_h(m.params, x)) + rng.normal(0, [0.1, np.sqrt(0.02)]))
        x = np.asarray(pendulum_f(m.params, x, None)) + rng.normal(0, np.sqrt([1e-4, 4e-3, 1e-4]))
    return np.array(ys)


def as_nonlinear(model):
    F, H = model.F, model.H
    return nonlinear_ssm(
        lambda p, x, u: F @ x + (0.0 if u is None else model.B @ u),
        lambda p, x: H @ x,
        model.Q,
        model.R,
        model.m0,
        model.P0,
    )


@pytest.mark.parametrize("which", ["ekf", "ukf", "ckf"])
def test_nonlinear_filters_equal_kf_on_linear_model(which):
    rng = np.random.default_rng(10)
    model = random_model(rng, n=4, p=2, m=1)
    u = rng.standard_normal((20, 1))
    _, y = simulate_np(model, rng, 20, u)
    ref = kalman_filter(model, y, u)
    nl = as_nonlinear(model)
    run = {
        "ekf": lambda: extended_kalman_filter(nl, y, u),
        "ukf": lambda: unscented_kalman_filter(nl, y, u, alpha=0.7, beta=2.0, kappa=1.0),
        "ckf": lambda: cubature_kalman_filter(nl, y, u),
    }[which]
    got = run()
    tol = 0.0 if which == "ekf" else 1e-9
    np.testing.assert_allclose(got.means, ref.means, rtol=tol, atol=tol)
    np.testing.assert_allclose(got.covs, ref.covs, rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(got.log_likelihood, ref.log_likelihood, rtol=1e-10)


def test_cubature_equals_unscented_with_alpha1_beta0_kappa0():
    y = pendulum_data()
    m = pendulum_model()
    a, b = cubature_kalman_filter(m, y), unscented_kalman_filter(m, y, alpha=1.0, beta=0.0, kappa=0.0)
    np.testing.assert_allclose(a.means, b.means, rtol=1e-11, atol=1e-12)
    np.testing.assert_allclose(a.covs, b.covs, rtol=1e-10, atol=1e-12)


def _filterpy_sigma_filter(kind, y, alpha=0.5, beta=2.0, kappa=1.0):
    """FilterPy's UKF/CKF, redrawing sigma points from the predicted belief before each update."""
    m = pendulum_model()
    fx = lambda x, dt: np.asarray(pendulum_f(m.params, jnp.asarray(x), None))  # noqa: E731
    hx = lambda x: np.asarray(pendulum_h(m.params, jnp.asarray(x)))  # noqa: E731
    if kind == "ukf":
        points = fk.MerweScaledSigmaPoints(3, alpha=alpha, beta=beta, kappa=kappa)
        f = fk.UnscentedKalmanFilter(dim_x=3, dim_z=2, dt=DT, hx=hx, fx=fx, points=points)
        redraw = lambda: points.sigma_points(f.x, f.P)  # noqa: E731
    else:
        f = fk.CubatureKalmanFilter(dim_x=3, dim_z=2, dt=DT, hx=hx, fx=fx)
        redraw = lambda: spherical_radial_sigmas(f.x.ravel(), f.P)  # noqa: E731
    f.x, f.P = np.asarray(m.m0, float).copy(), np.asarray(m.P0, float).copy()
    column = kind == "ckf"  # FilterPy's CKF keeps x and z as columns
    f.Q, f.R = np.asarray(m.Q), np.asarray(m.R)
    means, covs, lls = [], [], []
    for k in range(len(y)):
        f.sigmas_f = redraw()
        if column:
            f.x = f.x.reshape(-1, 1)
        f.update(y[k][:, None] if column else y[k])
        means.append(f.x.ravel().copy())
        covs.append(f.P.copy())
        lls.append(f.log_likelihood)
        f.predict()
    return f, np.array(means), np.array(covs), np.array(lls)


def test_ukf_matches_filterpy():
    y = pendulum_data()
    _, means, covs, lls = _filterpy_sigma_filter("ukf", y)
    got = unscented_kalman_filter(pendulum_model(), y, alpha=0.5, beta=2.0, kappa=1.0)
    np.testing.assert_allclose(got.means, means, rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(got.covs, covs, rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(got.log_likelihoods, lls, rtol=1e-9, atol=1e-10)


def test_cubature_matches_filterpy():
    y = pendulum_data(seed=1)
    _, means, covs, _ = _filterpy_sigma_filter("ckf", y)
    got = cubature_kalman_filter(pendulum_model(), y)
    np.testing.assert_allclose(got.means, means, rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(got.covs, covs, rtol=1e-9, atol=1e-10)


def test_ekf_tracks_pendulum_and_is_masked_consistently():
    y = pendulum_data(t=40, seed=2)
    m = pendulum_model()
    full = extended_kalman_filter(m, y)
    y_nan = y.copy()
    y_nan[::4, 1] = np.nan
    masked = extended_kalman_filter(m, y_nan, missing="nan")
    assert np.all(np.isfinite(masked.means))
    np.testing.assert_array_equal(masked.dof[::4], 1)
    # the first step has no earlier mask effect: only the second component's information differs
    assert not np.allclose(masked.means[0], full.means[0])


def test_nonlinear_model_validation():
    with pytest.raises(ValueError, match="^observation: must return shape"):
        nonlinear_ssm(pendulum_f, lambda p, x: x, np.eye(3), np.eye(2), np.zeros(3), np.eye(3), {"g": 9.81})
    with pytest.raises(ValueError, match="^Q: must be positive semi-definite"):
        nonlinear_ssm(pendulum_f, pendulum_h, -np.eye(3), np.eye(2), np.zeros(3), np.eye(3), {"g": 9.81})


# --- EKF against FilterPy's ExtendedKalmanFilter on nonlinear models --------------------------------
# Each case gives the model (JAX f, h: our EKF differentiates them with jax.jacfwd) and, for the
# oracle, the same f, h in NumPy with their Jacobians derived by hand.


class EKFCase(NamedTuple):
    model: object
    f: Callable[[np.ndarray], np.ndarray]
    jac_f: Callable[[np.ndarray], np.ndarray]
    h: Callable[[np.ndarray], np.ndarray]
    jac_h: Callable[[np.ndarray], np.ndarray]
    x_true0: np.ndarray


def _pendulum_case() -> EKFCase:
    g = 9.81
    return EKFCase(
        pendulum_model(),
        f=lambda x: np.array([x[0] + DT * x[1], x[1] - DT * (g * np.sin(x[0]) + 0.2 * x[1] - x[2]), 0.98 * x[2]]),
        jac_f=lambda x: np.array([[1.0, DT, 0.0], [-DT * g * np.cos(x[0]), 1.0 - 0.2 * DT, DT], [0.0, 0.0, 0.98]]),
        h=lambda x: np.array([np.sin(x[0]) + 0.5 * x[2], 0.5 * x[1] ** 2 + x[0]]),
        jac_h=lambda x: np.array([[np.cos(x[0]), 0.0, 0.5], [1.0, x[1], 0.0]]),
        x_true0=np.array([0.9, 0.1, 0.05]),
    )


TURN = 0.3  # rad/s, heading rate of the range–bearing target


def _rb_f(params, x, u):
    """Target at ``(px, py)`` moving at speed ``s`` along heading ``θ`` that turns at ``TURN``."""
    return jnp.stack([x[0] + DT * x[2] * jnp.cos(x[3]), x[1] + DT * x[2] * jnp.sin(x[3]), x[2], x[3] + DT * TURN])


def _rb_h(params, x):
    """Range and bearing from the origin."""
    return jnp.stack([jnp.sqrt(x[0] ** 2 + x[1] ** 2), jnp.arctan2(x[1], x[0])])


def _range_bearing_case() -> EKFCase:
    def jac_f(x):
        c, s = np.cos(x[3]), np.sin(x[3])
        return np.array(
            [
                [1.0, 0.0, DT * c, -DT * x[2] * s],
                [0.0, 1.0, DT * s, DT * x[2] * c],
                [0.0, 0.0, 1.0, 0.0],
                [0.0, 0.0, 0.0, 1.0],
            ]
        )

    def jac_h(x):
        r2 = x[0] ** 2 + x[1] ** 2
        r = np.sqrt(r2)
        return np.array([[x[0] / r, x[1] / r, 0.0, 0.0], [-x[1] / r2, x[0] / r2, 0.0, 0.0]])

    model = nonlinear_ssm(
        _rb_f,
        _rb_h,
        Q=np.diag([1e-3, 1e-3, 1e-2, 4e-3]),
        R=np.diag([0.04, 1e-3]),
        m0=np.array([10.0, 2.0, 1.0, 0.4]),
        P0=np.diag([0.5, 0.5, 0.1, 0.05]),
    )
    return EKFCase(
        model,
        f=lambda x: np.array(
            [x[0] + DT * x[2] * np.cos(x[3]), x[1] + DT * x[2] * np.sin(x[3]), x[2], x[3] + DT * TURN]
        ),
        jac_f=jac_f,
        h=lambda x: np.array([np.hypot(x[0], x[1]), np.arctan2(x[1], x[0])]),
        jac_h=jac_h,
        x_true0=np.array([10.3, 1.8, 1.1, 0.5]),
    )


EKF_CASES = {"pendulum": _pendulum_case, "range_bearing": _range_bearing_case}


def ekf_case_data(case: EKFCase, t: int = 20, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Measurements ``(T, 2)`` from a NumPy simulation, and a mask with one partially and two fully
    missing steps (masked entries hold NaN)."""
    rng = np.random.default_rng(seed)
    q, r = np.asarray(case.model.Q), np.asarray(case.model.R)
    x, ys = case.x_true0.copy(), []
    for _ in range(t):
        ys.append(case.h(x) + rng.multivariate_normal(np.zeros(2), r))
        x = case.f(x) + rng.multivariate_normal(np.zeros(len(x)), q)
    mask = np.ones((t, 2), bool)
    mask[3, 1] = mask[8, 0] = False
    mask[5] = mask[12] = False
    y = np.where(mask, np.array(ys), np.nan)
    return y, mask


def filterpy_ekf(case: EKFCase, y: np.ndarray, mask: np.ndarray) -> dict[str, np.ndarray]:
    """FilterPy's ``ExtendedKalmanFilter`` in our order (update with ``y_t``, then predict), the
    update restricted to the available components and skipped when none is; per-step moments."""
    m = case.model
    n = m.n_states
    ekf = fk.ExtendedKalmanFilter(dim_x=n, dim_z=2)
    ekf.Q, R = np.asarray(m.Q, float), np.asarray(m.R, float)
    ekf.x, ekf.P = np.asarray(m.m0, float).reshape(n, 1).copy(), np.asarray(m.P0, float).copy()
    ekf.predict_x = lambda u=0: setattr(ekf, "x", case.f(ekf.x.ravel()).reshape(n, 1))
    out = {k: [] for k in ("means", "covs", "predicted_means", "predicted_covs", "log_likelihoods")}
    for k in range(len(y)):
        out["predicted_means"].append(ekf.x.ravel().copy())
        out["predicted_covs"].append(ekf.P.copy())
        idx = np.flatnonzero(mask[k])
        ll = 0.0
        if idx.size:
            ekf.update(
                y[k, idx].reshape(-1, 1),
                lambda x, i=idx: case.jac_h(x.ravel())[i],
                lambda x, i=idx: case.h(x.ravel())[i].reshape(-1, 1),
                R=R[np.ix_(idx, idx)],
            )
            ll = ekf.log_likelihood
        out["means"].append(ekf.x.ravel().copy())
        out["covs"].append(ekf.P.copy())
        out["log_likelihoods"].append(ll)
        ekf.F = case.jac_f(ekf.x.ravel())  # FilterPy's predict propagates P with self.F
        ekf.predict()
    return {k: np.array(v) for k, v in out.items()}


@pytest.mark.parametrize("name", list(EKF_CASES))
def test_ekf_matches_filterpy_step_by_step_on_nonlinear_models(name):
    case = EKF_CASES[name]()
    y, mask = ekf_case_data(case)
    ref = filterpy_ekf(case, y, mask)
    got = extended_kalman_filter(case.model, y, mask=mask)
    for field, want in ref.items():
        np.testing.assert_allclose(np.asarray(getattr(got, field)), want, rtol=1e-10, atol=1e-10, err_msg=field)
    np.testing.assert_array_equal(got.dof, mask.sum(axis=1))
