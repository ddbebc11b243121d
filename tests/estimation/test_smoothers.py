"""RTS smoothers (FilterPy oracle), extended/unscented RTS, and the parallel-in-time twins."""

from __future__ import annotations

import filterpy.kalman as fk
import numpy as np
import pytest

from jaxsim.estimation.lgssm import kalman_filter, lgssm
from jaxsim.estimation.parallel import parallel_kalman_filter, parallel_rts_smoother
from jaxsim.estimation.smoothers import extended_rts_smoother, rts_smoother, unscented_rts_smoother
from tests.estimation.helpers import filterpy_kalman, random_model, random_time_varying, simulate_np
from tests.estimation.test_nonlinear import (
    EKF_CASES,
    _filterpy_sigma_filter,
    as_nonlinear,
    ekf_case_data,
    filterpy_ekf,
    pendulum_data,
    pendulum_model,
)


def test_rts_matches_filterpy():
    rng = np.random.default_rng(20)
    model = random_model(rng, n=4, p=2)
    _, y = simulate_np(model, rng, 30, None)
    ours = rts_smoother(model, y)
    kf = fk.KalmanFilter(dim_x=4, dim_z=2)
    F, Q = np.asarray(model.F), np.asarray(model.Q)
    kf.F, kf.Q, kf.H, kf.R = F, Q, np.asarray(model.H), np.asarray(model.R)
    kf.x, kf.P = np.asarray(model.m0)[:, None].copy(), np.asarray(model.P0).copy()
    xs, ps = [], []
    for t in range(30):
        kf.update(y[t][:, None])
        xs.append(kf.x.copy())
        ps.append(kf.P.copy())
        kf.predict()
    sx, sp, _, _ = kf.rts_smoother(np.array(xs), np.array(ps), [F] * 30, [Q] * 30)
    np.testing.assert_allclose(ours.means, sx[:, :, 0], rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(ours.covs, sp, rtol=1e-9, atol=1e-10)


def test_time_varying_masked_rts_matches_filterpy():
    """Per-step ``F_t, Q_t, H_t, R_t`` and missing components (two steps fully masked, the last one
    included): FilterPy's ``KalmanFilter`` with per-step matrices, then its ``rts_smoother`` with the
    per-step ``Fs, Qs`` (``Fs[t]`` drives ``t → t+1``, as our ``F[t]``)."""
    rng = np.random.default_rng(24)
    t = 16
    tv = random_time_varying(rng, t)
    model = lgssm(tv.F, tv.Q, tv.H, tv.R, tv.m0, tv.P0)  # FilterPy's smoother takes no inputs
    _, y = simulate_np(model, rng, t, None)
    mask = rng.random((t, 2)) > 0.3
    mask[[4, t - 1]] = False
    ref = filterpy_kalman(model, y, mask=mask)
    sx, sp, gains, _ = fk.rts_smoother(ref["means"], ref["covs"], np.asarray(model.F), np.asarray(model.Q))
    got = rts_smoother(model, np.where(mask, y, np.nan), missing="nan")
    np.testing.assert_allclose(got.filtered.means, ref["means"], rtol=1e-10, atol=1e-11)
    np.testing.assert_allclose(got.means, sx, rtol=1e-10, atol=1e-11)
    np.testing.assert_allclose(got.covs, sp, rtol=1e-10, atol=1e-11)
    np.testing.assert_allclose(got.gains, gains[:-1], rtol=1e-10, atol=1e-11)


def test_unscented_rts_matches_filterpy():
    y = pendulum_data(t=20, seed=3)
    f, means, covs, _ = _filterpy_sigma_filter("ukf", y)
    sx, sp, _ = f.rts_smoother(means, covs)
    ours = unscented_rts_smoother(pendulum_model(), y, alpha=0.5, beta=2.0, kappa=1.0)
    np.testing.assert_allclose(ours.means, sx, rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(ours.covs, sp, rtol=1e-9, atol=1e-10)


def test_extended_and_unscented_rts_equal_rts_on_linear_model():
    rng = np.random.default_rng(21)
    model = random_model(rng, n=3, p=2, m=1)
    u = rng.standard_normal((15, 1))
    _, y = simulate_np(model, rng, 15, u)
    ref = rts_smoother(model, y, u)
    nl = as_nonlinear(model)
    for got in (extended_rts_smoother(nl, y, u), unscented_rts_smoother(nl, y, u, alpha=0.8)):
        np.testing.assert_allclose(got.means, ref.means, rtol=1e-9, atol=1e-10)
        np.testing.assert_allclose(got.covs, ref.covs, rtol=1e-9, atol=1e-10)


def test_smoother_reduces_covariance_and_interpolates_a_gap():
    rng = np.random.default_rng(22)
    model = random_model(rng, n=3, p=1)
    _, y = simulate_np(model, rng, 40, None)
    mask = np.ones(40, bool)
    mask[15:25] = False  # a rejected segment: the smoother bridges it
    s = rts_smoother(model, y, mask=mask)
    trace_s = np.trace(np.asarray(s.covs), axis1=1, axis2=2)
    trace_f = np.trace(np.asarray(s.filtered.covs), axis1=1, axis2=2)
    assert np.all(trace_s <= trace_f + 1e-12)
    assert np.all(trace_s[15:25] < trace_f[15:25])


@pytest.mark.parametrize("time_varying", [False, True])
def test_parallel_equals_serial(time_varying):
    rng = np.random.default_rng(23)
    t = 33
    model = random_time_varying(rng, t) if time_varying else random_model(rng, n=4, p=2, m=1)
    u = rng.standard_normal((t, 1))
    _, y = simulate_np(model, rng, t, u)
    mask = rng.random((t, 2)) > 0.25
    ser, par = kalman_filter(model, y, u, mask=mask), parallel_kalman_filter(model, y, u, mask=mask)
    for field in ser._fields:
        np.testing.assert_allclose(
            np.asarray(getattr(par, field), float),
            np.asarray(getattr(ser, field), float),
            rtol=1e-9,
            atol=1e-10,
            err_msg=field,
        )
    ss, ps = rts_smoother(model, y, u, mask=mask), parallel_rts_smoother(model, y, u, mask=mask)
    np.testing.assert_allclose(ps.means, ss.means, rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(ps.covs, ss.covs, rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(ps.gains, ss.gains, rtol=1e-9, atol=1e-10)


@pytest.mark.parametrize("name", list(EKF_CASES))
def test_extended_rts_matches_numpy_recursion_on_filterpy_ekf(name):
    """Oracle: FilterPy's EKF moments, then the RTS recursion written out in NumPy with the
    hand-derived Jacobian of ``f`` at each filtered mean (FilterPy has no extended smoother)."""
    case = EKF_CASES[name]()
    y, mask = ekf_case_data(case, seed=1)
    ref = filterpy_ekf(case, y, mask)
    m, P, Q = ref["means"], ref["covs"], np.asarray(case.model.Q)
    ms, ps, gains = m.copy(), P.copy(), np.zeros_like(P[:-1])
    for t in range(len(y) - 2, -1, -1):
        F = case.jac_f(m[t])
        p_pred = F @ P[t] @ F.T + Q
        gains[t] = P[t] @ F.T @ np.linalg.inv(p_pred)
        ms[t] = m[t] + gains[t] @ (ms[t + 1] - case.f(m[t]))
        ps[t] = P[t] + gains[t] @ (ps[t + 1] - p_pred) @ gains[t].T
    got = extended_rts_smoother(case.model, y, mask=mask)
    np.testing.assert_allclose(got.means, ms, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(got.covs, ps, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(got.gains, gains, rtol=1e-10, atol=1e-10)
    # the smoother actually changed the filtered estimates (the check above is not vacuous)
    assert np.max(np.abs(ms[:-1] - m[:-1])) > 1e-2
