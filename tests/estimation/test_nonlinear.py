"""EKF, UKF and cubature filter: equal to the KF on linear models; FilterPy's UKF/CKF as oracles."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.estimation.cubature import cubature_kalman_filter
from jaxsim.estimation.ekf import extended_kalman_filter
from jaxsim.estimation.lgssm import kalman_filter
from jaxsim.estimation.nonlinear import nonlinear_ssm
from jaxsim.estimation.ukf import unscented_kalman_filter
from tests.estimation.helpers import random_model, simulate_np

DT = 0.1


def pendulum_f(params, x, u):
    """Damped pendulum with a slowly decaying bias torque (x = [angle, rate, bias])."""
    return jnp.stack([x[0] + DT * x[1], x[1] - DT * (params["g"] * jnp.sin(x[0]) + 0.2 * x[1] - x[2]),
                      0.98 * x[2]])


def pendulum_h(params, x):
    return jnp.stack([jnp.sin(x[0]) + 0.5 * x[2], 0.5 * x[1] ** 2 + x[0]])


def pendulum_model():
    return nonlinear_ssm(pendulum_f, pendulum_h, Q=np.diag([1e-4, 4e-3, 1e-4]), R=np.diag([0.01, 0.02]),
                         m0=np.array([0.8, 0.0, 0.1]), P0=np.diag([0.05, 0.05, 0.02]), params={"g": 9.81})


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
    return nonlinear_ssm(lambda p, x, u: F @ x + (0.0 if u is None else model.B @ u), lambda p, x: H @ x,
                         model.Q, model.R, model.m0, model.P0)


@pytest.mark.parametrize("which", ["ekf", "ukf", "ckf"])
def test_nonlinear_filters_equal_kf_on_linear_model(which):
    rng = np.random.default_rng(10)
    model = random_model(rng, n=4, p=2, m=1)
    u = rng.standard_normal((20, 1))
    _, y = simulate_np(model, rng, 20, u)
    ref = kalman_filter(model, y, u)
    nl = as_nonlinear(model)
    run = {"ekf": lambda: extended_kalman_filter(nl, y, u),
           "ukf": lambda: unscented_kalman_filter(nl, y, u, alpha=0.7, beta=2.0, kappa=1.0),
           "ckf": lambda: cubature_kalman_filter(nl, y, u)}[which]
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
    fk = pytest.importorskip("filterpy.kalman")
    m = pendulum_model()
    fx = lambda x, dt: np.asarray(pendulum_f(m.params, jnp.asarray(x), None))  # noqa: E731
    hx = lambda x: np.asarray(pendulum_h(m.params, jnp.asarray(x)))  # noqa: E731
    if kind == "ukf":
        points = fk.MerweScaledSigmaPoints(3, alpha=alpha, beta=beta, kappa=kappa)
        f = fk.UnscentedKalmanFilter(dim_x=3, dim_z=2, dt=DT, hx=hx, fx=fx, points=points)
        redraw = lambda: points.sigma_points(f.x, f.P)  # noqa: E731
    else:
        from filterpy.kalman.CubatureKalmanFilter import spherical_radial_sigmas
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
