"""Carousel heading least squares: exact recovery without noise, NumPy lstsq as oracle, NEES
consistency of its covariance, the error budget against its whole-turn closed form and a Monte Carlo
with bias drift and table-rate error, gradients against finite differences."""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy import stats

from jaxsim.inertial.carousel import (
    EARTH_RATE,
    carousel_rate,
    closed_form_heading_std,
    heading_error_budget,
    heading_ls,
    regressors,
    whole_turn_budget,
)
from tests.covariance import assert_covariance_close

DEG = math.pi / 180
LAT = 59.94 * DEG
W = 6 * DEG  # one turn per minute


def test_noise_free_heading_and_bias_are_recovered():
    t = jnp.arange(600) / 10.0
    k0 = np.array([-179.9, -90.0, 0.0, 37.0, 179.9]) * DEG
    est = jax.jit(jax.vmap(lambda k: heading_ls(t, carousel_rate(t, k, W, LAT, 0.5 * DEG), W, 1e-6)))(jnp.asarray(k0))
    np.testing.assert_allclose(np.asarray(est.heading), k0, atol=1e-10)
    omega_h = EARTH_RATE * math.cos(LAT)
    expected = np.stack([omega_h * np.cos(k0), omega_h * np.sin(k0), np.full(5, 0.5 * DEG)], axis=1)
    np.testing.assert_allclose(est.theta, expected, rtol=1e-9, atol=1e-15)


def test_least_squares_against_numpy_and_vmap_equals_loop():
    rng = np.random.default_rng(0)
    t = np.arange(300) / 5.0
    y = np.asarray(carousel_rate(t, 1.0, W, LAT, 0.01)) + 1e-4 * rng.standard_normal(300)
    h = np.asarray(regressors(t, W))
    theta, *_ = np.linalg.lstsq(h, y, rcond=None)
    est = heading_ls(t, y, W, 1e-4)
    np.testing.assert_allclose(est.theta, theta, rtol=1e-9)
    assert_covariance_close(est.cov, 1e-8 * np.linalg.inv(h.T @ h), rtol=1e-9)
    assert float(est.heading) == pytest.approx(math.atan2(theta[1], theta[0]), abs=1e-12)
    ys = np.stack([y, y[::-1], 2 * y])
    batched = jax.vmap(lambda yy: heading_ls(t, yy, W, 1e-4).heading)(jnp.asarray(ys))
    np.testing.assert_allclose(batched, [float(heading_ls(t, yy, W, 1e-4).heading) for yy in ys], rtol=1e-12)


def test_nees_is_chi2_consistent_and_rms_matches_the_closed_form():
    runs, fs, T, density = 300, 2.0, 300.0, 0.001 * DEG
    t = jnp.arange(int(T * fs)) / fs
    sigma = density * math.sqrt(fs)

    @jax.jit
    def one(k):
        k1, k2 = jax.random.split(k)
        k0 = jax.random.uniform(k1, (), minval=-math.pi, maxval=math.pi)
        est = heading_ls(t, carousel_rate(t, k0, W, LAT, 0.3) + sigma * jax.random.normal(k2, t.shape), W, sigma)
        e = jnp.angle(jnp.exp(1j * (est.heading - k0)))
        return e, e**2 / est.heading_var

    e, nees = (np.asarray(a) for a in jax.vmap(one)(jax.random.split(jax.random.PRNGKey(0), runs)))
    lo, hi = stats.chi2.ppf([0.005, 0.995], runs) / runs
    assert lo <= nees.mean() <= hi
    rms = math.sqrt(np.mean(e**2))
    assert rms == pytest.approx(float(closed_form_heading_std(density, T, LAT)), rel=0.12)


def test_budget_reduces_to_the_whole_turn_closed_form():
    args = (LAT, 0.001 * DEG, 2e-5 * DEG, 1e-4)
    for w_deg, turns in ((2.0, 10), (6.0, 60), (20.0, 100)):
        w = w_deg * DEG
        T = turns * 360 / w_deg
        general = heading_error_budget(w, T, *args, n_quad=8192)
        closed = whole_turn_budget(w, T, *args)
        np.testing.assert_allclose(general.white, closed.white, rtol=1e-9)
        np.testing.assert_allclose(general.rate_random_walk, closed.rate_random_walk, rtol=1e-3)
        np.testing.assert_allclose(general.table_rate, closed.table_rate, rtol=1e-3)
        assert float(closed.white) == pytest.approx(float(closed_form_heading_std(0.001 * DEG, T, LAT)) ** 2, rel=1e-12)


def test_budget_against_monte_carlo_with_drift_and_table_error():
    fs, T, w = 1.0, 600.0, 2 * DEG
    density, k_rw, eps = 0.001 * DEG, 5e-5 * DEG, 3e-3
    n = int(T * fs)
    t = jnp.arange(n) / fs
    sigma = density * math.sqrt(fs)

    @jax.jit
    def one(k):
        k1, k2, k3, k4 = jax.random.split(k, 4)
        k0 = jax.random.uniform(k1, (), minval=-math.pi, maxval=math.pi)
        bias = 0.1 + jnp.cumsum(k_rw / math.sqrt(fs) * jax.random.normal(k2, (n,)))
        y = carousel_rate(t, k0, w * (1 + eps * jax.random.normal(k3, ())), LAT, bias)
        y = y + sigma * jax.random.normal(k4, (n,))
        return jnp.angle(jnp.exp(1j * (heading_ls(t, y, w, sigma).heading - k0)))

    runs = 400
    e = np.asarray(jax.vmap(one)(jax.random.split(jax.random.PRNGKey(1), runs)))
    budget = heading_error_budget(w, T, LAT, density, k_rw, eps)
    # all three sources matter here: 1.6°, 2.8°, 1.8°
    assert min(budget.white, budget.rate_random_walk, budget.table_rate) > 0.15 * budget.total
    assert math.sqrt(np.mean(e**2)) == pytest.approx(math.sqrt(float(budget.total)), rel=0.1)


def test_gradients_and_the_analytic_best_rate():
    args = (LAT, 0.001 * DEG, 2e-5 * DEG, 1e-4)

    @jax.jit
    def f(x):
        return whole_turn_budget(x[0], x[1], *args).total

    x = jnp.array([4 * DEG, 1800.0])
    g = jax.grad(f)(x)
    for i, h in enumerate((1e-7, 1e-3)):
        fd = (f(x.at[i].add(h)) - f(x.at[i].add(-h))) / (2 * h)
        assert float(g[i]) == pytest.approx(float(fd), rel=1e-6)
    T = 1800.0
    omega_h = EARTH_RATE * math.cos(LAT)
    best = (16 * (2e-5 * DEG) ** 2 / (1e-4**2 * T**3 * omega_h**2)) ** 0.25
    rates = np.geomspace(0.5, 30, 4001) * DEG
    vals = np.asarray(jax.jit(jax.vmap(lambda r: whole_turn_budget(r, T, *args).total))(jnp.asarray(rates)))
    assert rates[np.argmin(vals)] == pytest.approx(best, rel=2e-3)
    # the general budget differentiates too (through the quadrature)
    gq = jax.jit(jax.grad(lambda w: heading_error_budget(w, T, *args, n_quad=1024).total))(3 * DEG)
    assert np.isfinite(float(gq))


def test_bad_inputs_name_the_argument():
    t = jnp.arange(10.0)
    with pytest.raises(ValueError, match="^y:"):
        heading_ls(t, jnp.zeros(9), W, 1.0)
    with pytest.raises(ValueError, match="^t:"):
        heading_ls(t[:2], jnp.zeros(2), W, 1.0)
    with pytest.raises(ValueError, match="^sigma:"):
        heading_ls(t, jnp.zeros(10), W, 0.0)
    with pytest.raises(ValueError, match="^n_quad:"):
        heading_error_budget(W, 60.0, LAT, 1e-5, n_quad=0)
