"""Quartz pendulous accelerometer plant (seed 004 B6): static deflection, linear model vs the
nonlinear dynamics, stops, RK4 vs SciPy, bad input."""

import dataclasses

import jax.numpy as jnp
import numpy as np
import pytest
import scipy.integrate

from jaxsim.plants import quartz_accelerometer as qa


def test_static_deflection_and_scale_factor():
    p = qa.Params()
    a = 1.0 * qa.G0  # inside the stops: θ = m_l a / k ≈ 1.2 mrad
    assert float(qa.dynamics(p, jnp.array([p.m_l * a / p.k, 0.0]), 0.0, a)[1]) == pytest.approx(0.0, abs=1e-6)
    i = float(qa.scale_factor(p)) * 3.0  # 3 g rebalanced at null
    assert float(qa.dynamics(p, jnp.zeros(2), i, 3.0 * qa.G0)[1]) == pytest.approx(0.0, abs=1e-6)
    assert float(qa.scale_factor(p)) == pytest.approx(3.0e-6 * 9.80665 / 0.0226)


def test_linear_model_matches_dynamics_inside_stops_and_stop_force_outside():
    p = qa.Params()
    A, bi, ba, c = (np.asarray(v) for v in qa.linear_model(p))
    x = np.array([1e-3, 0.3])
    f = np.asarray(qa.dynamics(p, jnp.asarray(x), 0.01, 5.0))
    np.testing.assert_allclose(f, A @ x + bi[:, 0] * 0.01 + ba[:, 0] * 5.0, rtol=1e-12)
    assert np.sqrt(-A[1, 0]) / (2 * np.pi) == pytest.approx(200.0)
    assert float(qa.pickoff(p, jnp.asarray(x))) == pytest.approx(c[0] @ x)
    xo = np.array([3e-3, 0.0])  # 1 mrad beyond the stop: extra restoring torque k_stop·1e-3
    fo = np.asarray(qa.dynamics(p, jnp.asarray(xo), 0.0, 0.0))
    lin = A @ xo
    assert fo[1] - lin[1] == pytest.approx(-float(p.k_stop_ratio * p.k) * 1e-3 / float(p.J), rel=1e-10)


def test_rk4_against_solve_ivp_linear_range():
    p = qa.Params()
    h, n = 2.5e-5, 400
    x = jnp.zeros(2)
    i, a = 1e-3, 1.5 * qa.G0
    xs = []
    for _ in range(n):
        x = qa.rk4_step(p, x, i, a, h)
        xs.append(np.asarray(x))
    A, bi, ba, _ = (np.asarray(v) for v in qa.linear_model(p))
    sol = scipy.integrate.solve_ivp(
        lambda t, y: A @ y + bi[:, 0] * i + ba[:, 0] * a,
        (0, n * h),
        np.zeros(2),
        rtol=1e-11,
        atol=1e-15,
        t_eval=h * np.arange(1, n + 1),
        method="DOP853",
    )
    np.testing.assert_allclose(np.array(xs)[:, 0], sol.y[0], atol=1e-6 * np.abs(sol.y[0]).max())


def test_bad_params():
    with pytest.raises(ValueError, match="zeta"):
        qa.check_params(dataclasses.replace(qa.Params(), zeta=-1.0))
    with pytest.raises(ValueError, match="theta_stop"):
        qa.check_params(dataclasses.replace(qa.Params(), theta_stop=0.0))
