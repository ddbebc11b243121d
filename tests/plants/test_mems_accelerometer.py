"""MEMS accelerometer kernels (seed 004 #35): the sweep's steady state against SciPy's solve_ivp at
tight tolerance, the bisection pull-in against the closed-form parametric boundary (brentq), its
envelope-theorem gradient against finite differences, the multiple-scales pieces against their
formulas, input validation."""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.integrate
import scipy.optimize

from jaxsim.plants import mems_accelerometer as mm


def test_sweep_matches_solve_ivp():
    p = mm.Params(F=0.004)
    om = jnp.array([0.7, 0.76])
    s = mm.sweep(p, om, jnp.zeros(2), n_periods=6, n_measure=3, steps_per_period=128)

    def rhs_np(t, y, w):
        x, v = y
        el = p.beta * (1 / (1 - x) ** 2 - 1 / (1 + x) ** 2)
        return [v, p.F * np.sin(w * t) - 2 * p.eps * p.mu * v - x - p.eps * p.kappa * x**3 + el]

    y = np.zeros(2)
    for w in np.asarray(om):  # state carried over, forcing phase restarts at each frequency
        T = 2 * np.pi / w
        sol = scipy.integrate.solve_ivp(rhs_np, (0, 6 * T), y, args=(w,), rtol=1e-11, atol=1e-13, dense_output=True)
        t = np.linspace(3 * T, 6 * T, 3 * 128 + 1)[1:]
        x = sol.sol(t)[0]
        c1 = 2 * abs(np.mean(x * np.exp(-1j * w * t)))
        y = sol.y[:, -1]
        assert float(s.c1[list(np.asarray(om)).index(w)]) == pytest.approx(c1, rel=1e-5)
    np.testing.assert_allclose(np.asarray(s.x_end), y, atol=1e-6)  # RK4, 128 steps/period
    assert not bool(s.collapsed.any())


def test_pull_in_against_closed_form_boundary():
    p = mm.Params()
    betas = jnp.array([0.02, 0.1, 0.2])
    res = jax.vmap(lambda b: mm.pull_in(dataclasses.replace(p, beta=b)))(betas)
    for b, x, a in zip(np.asarray(betas), np.asarray(res.x), np.asarray(res.a)):
        ek = p.eps * p.kappa

        def gp(x):
            return 1 + 3 * ek * x**2 - 2 * b * (1 / (1 - x) ** 3 + 1 / (1 + x) ** 3)

        xs = scipy.optimize.brentq(gp, 0.0, 0.999, xtol=1e-15)
        assert x == pytest.approx(xs, abs=1e-10)
        # the parametric closed form: β(x*) from g'(x*) = 0, then a* = g(x*)
        beta_of_x = (1 + 3 * ek * xs**2) / (2 * (1 / (1 - xs) ** 3 + 1 / (1 + xs) ** 3))
        assert beta_of_x == pytest.approx(b, rel=1e-9)
        assert a == pytest.approx(xs + ek * xs**3 - b * (1 / (1 - xs) ** 2 - 1 / (1 + xs) ** 2), rel=1e-10)
    # β → 1/4 pulls in at the origin
    assert float(mm.pull_in(dataclasses.replace(p, beta=0.2499999)).x) < 0.01


def test_pull_in_gradient_matches_finite_differences():
    p = mm.Params()

    def a_of(th):
        return mm.pull_in(dataclasses.replace(p, beta=th[0], kappa=th[1])).a

    th = jnp.array([0.07, 2.0])
    g = jax.grad(a_of)(th)
    h = 1e-6
    pts = jnp.concatenate([th + h * jnp.eye(2), th - h * jnp.eye(2)])
    vals = jax.vmap(a_of)(pts)
    fd = (vals[:2] - vals[2:]) / (2 * h)
    np.testing.assert_allclose(np.asarray(g), np.asarray(fd), rtol=1e-5)
    assert g[0] < 0 < g[1]  # the field lowers the pull-in acceleration, a hardening suspension raises it


def test_multiple_scales_pieces():
    p = mm.Params()
    w0, a3, a5, c = mm.ms_coefficients(p)
    assert float(w0) == pytest.approx(np.sqrt(1 - 4 * p.beta))
    assert float(a3) == pytest.approx(p.eps * p.kappa - 8 * p.beta)
    # the expansion's coefficients: g(x) ≈ ω0²x + α3x³ + α5x⁵ near 0
    x = 1e-2
    assert float(mm.static_force(p, x)) == pytest.approx(
        float(w0) ** 2 * x + float(a3) * x**3 + float(a5) * x**5, rel=1e-9
    )
    a_top = float(mm.ms_peak_amplitude(p))
    lo, hi = mm.ms_response_branches(p, jnp.array(a_top * (1 - 1e-12)))
    assert float(lo) == pytest.approx(float(hi), abs=1e-5)
    assert float(lo) == pytest.approx(float(mm.ms_backbone(p, a_top)), abs=1e-5)
    dn, up = mm.ms_jump_frequencies(p)
    assert dn < up < float(w0)  # softening: the hysteresis lies below ω0
    assert np.isnan(mm.ms_jump_frequencies(dataclasses.replace(p, F=1e-4))[0])  # linear regime: no folds


def test_voltage_beta_round_trip_and_validation():
    b = mm.beta_from_voltage(3.0, 1e-7, 2e-6, 5.0)
    assert float(b) == pytest.approx(8.854e-12 * 1e-7 * 9 / (2 * 5 * 8e-18))
    assert float(mm.voltage_from_beta(b, 1e-7, 2e-6, 5.0)) == pytest.approx(3.0)
    with pytest.raises(ValueError, match="beta"):
        mm.validate(mm.Params(beta=0.3))
    with pytest.raises(ValueError, match="mu"):
        mm.validate(mm.Params(mu=-1.0))
    with pytest.raises(ValueError, match="n_measure"):
        mm.sweep(mm.Params(), jnp.array([1.0]), jnp.zeros(2), n_periods=6, n_measure=4)
