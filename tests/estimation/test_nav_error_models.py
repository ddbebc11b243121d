"""Motorin's navigation error models and the exact mismatched-filter covariance, against independent
oracles: SciPy's DARE, a NumPy error-covariance recursion, forward-mode Jacobians of the nonlinear
dead-reckoning step, Monte Carlo, and vmap == loop."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg

from jaxsim.estimation import nav_error_models as nav
from jaxsim.estimation.lgssm import LinearGaussianSSM, kalman_filter, sample


@pytest.mark.parametrize("q, r", [(1.96, 25.0), (0.04, 25.0), (16.0, 1.0)])
def test_random_walk_steady_state_matches_scipy_dare(q, r):
    ss = nav.random_walk_steady_state(q, r)
    p = scipy.linalg.solve_discrete_are(np.eye(1), np.eye(1), q * np.eye(1), r * np.eye(1))[0, 0]
    assert float(ss.predicted) == pytest.approx(p, rel=1e-12)
    assert float(ss.filtered) == pytest.approx(p - p * p / (p + r), rel=1e-12)
    assert float(ss.gain) == pytest.approx(p / (p + r), rel=1e-12)


def test_random_walk_filter_converges_to_closed_form():
    model = nav.random_walk_gnss(1.4, 5.0, 10.0)
    _, y = sample(model, jax.random.PRNGKey(0), 120)
    kf = kalman_filter(model, y)
    ss = nav.random_walk_steady_state(1.4**2, 25.0)
    np.testing.assert_allclose(np.asarray(kf.covs[-1]), float(ss.filtered) * np.eye(2), rtol=1e-10)


def _dr_model(tau_dk: float, t: int = 60):
    speed = np.full(t, 1.4)
    course = 0.8 * np.sin(2 * np.pi * np.arange(t) / 40.0)
    track = nav.dead_reckoning_track([0.0, 0.0], speed, course, 1.0)
    rows = nav.range_jacobians(track[:-1], np.array([[60.0, 40.0], [-30.0, 90.0]]))
    return nav.dead_reckoning_error_model(speed, course, 1.0, 0.1, 60.0, 0.05, tau_dk, rows, 2.0, 3.0), speed, course


def test_dead_reckoning_transition_is_the_jacobian_of_eq6():
    model, speed, course = _dr_model(100.0)

    def step(v, k):  # eq. (6): displacement over one step
        return 1.0 * v * jnp.stack([jnp.sin(k), jnp.cos(k)])

    for i in (0, 7, 31):
        jv, jk = jax.jacfwd(step, argnums=(0, 1))(speed[i], course[i])
        np.testing.assert_allclose(np.asarray(model.F[i, :2, 2]), np.asarray(jv), rtol=1e-12)
        np.testing.assert_allclose(np.asarray(model.F[i, :2, 3]), np.asarray(jk), rtol=1e-12)
    phi, q = nav.gauss_markov(0.05, 100.0, 1.0)
    assert float(q / (1 - phi**2)) == pytest.approx(0.05**2, rel=1e-12)  # stationary variance kept
    assert nav.gauss_markov(0.05, np.inf, 1.0) == (1.0, 0.0)


def test_range_jacobian_is_the_gradient_of_the_range():
    track = np.array([[3.0, 4.0], [10.0, -2.0]])
    lm = np.array([[0.0, 0.0], [5.0, 5.0]])
    rows = np.asarray(nav.range_jacobians(track, lm))
    for i in range(2):
        for j in range(2):
            g = jax.grad(lambda x: jnp.linalg.norm(x - lm[j]))(jnp.asarray(track[i]))
            np.testing.assert_allclose(rows[i, j], np.asarray(g), rtol=1e-12)


def numpy_actual_mse(true: LinearGaussianSSM, assumed: LinearGaussianSSM, t: int) -> np.ndarray:
    """Error-only recursion, valid when F and H are the same in both models: the filter's gains from its
    own Riccati recursion, the actual MSE ``(I − KH) P (I − KH)ᵀ + K R Kᵀ``, ``F P Fᵀ + Q`` (NumPy)."""
    F, H = np.asarray(true.F), np.asarray(true.H)
    Q, R, Qf, Rf = (np.asarray(m) for m in (true.Q, true.R, assumed.Q, assumed.R))
    pf, pa, out = np.asarray(assumed.P0), np.asarray(true.P0), []
    for _ in range(t):
        k = pf @ H.T @ np.linalg.inv(H @ pf @ H.T + Rf)
        ikh = np.eye(len(pf)) - k @ H
        pf = ikh @ pf @ ikh.T + k @ Rf @ k.T
        pa = ikh @ pa @ ikh.T + k @ R @ k.T
        out.append(pa)
        pf, pa = F @ pf @ F.T + Qf, F @ pa @ F.T + Q
    return np.array(out)


def test_mismatched_covariance_against_numpy_error_recursion():
    true = nav.random_walk_gnss(1.4, 5.0, 10.0)
    wrong = nav.random_walk_gnss(0.3, 8.0, 4.0)
    res = nav.mismatched_covariance(true, wrong, 50)
    np.testing.assert_allclose(np.asarray(res.actual), numpy_actual_mse(true, wrong, 50), rtol=1e-10)
    assert float(res.actual[-1, 0, 0]) > float(res.claimed[-1, 0, 0])  # over-confident when q is too small


def test_mismatched_covariance_equals_filter_covariance_under_the_true_model():
    model, *_ = _dr_model(100.0)
    mask = np.arange(60) % 5 == 0
    _, y = sample(model, jax.random.PRNGKey(1), 60)
    kf = kalman_filter(model, y, mask=mask)
    res = nav.mismatched_covariance(model, model, 60, mask=mask)
    np.testing.assert_allclose(np.asarray(res.actual), np.asarray(kf.covs), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(np.asarray(res.claimed), np.asarray(kf.covs), rtol=1e-9, atol=1e-12)


def test_mismatched_covariance_with_structural_mismatch_against_monte_carlo():
    """True: random walk plus a Gauss–Markov bias in the measurement (2 states); filter: random walk
    only (1 state, C = [1, 0]).  Monte-Carlo MSE of 4000 runs within 4 standard errors of the exact value."""
    phi = 0.9
    true = LinearGaussianSSM(
        F=jnp.array([[1.0, 0.0], [0.0, phi]]),
        Q=jnp.diag(jnp.array([0.5, 1.0 - phi**2])),
        H=jnp.array([[1.0, 1.0]]),
        R=jnp.array([[1.0]]),
        m0=jnp.zeros(2),
        P0=jnp.eye(2),
    )
    filt = LinearGaussianSSM(
        F=jnp.eye(1), Q=jnp.array([[0.5]]), H=jnp.eye(1), R=jnp.array([[1.0]]), m0=jnp.zeros(1), P0=jnp.eye(1)
    )
    t = 30
    res = nav.mismatched_covariance(true, filt, t, C=jnp.array([[1.0, 0.0]]))

    def err(key):
        x, y = sample(true, key, t)
        return x[:, 0] - kalman_filter(filt, y).means[:, 0]

    e = jax.jit(jax.vmap(err))(jax.random.split(jax.random.PRNGKey(2), 4000))
    mse = np.mean(np.asarray(e) ** 2, axis=0)
    exact = np.asarray(res.actual[:, 0, 0])
    se = exact * np.sqrt(2.0 / e.shape[0])  # SD of a χ²-type mean of squares
    assert np.all(np.abs(mse - exact) < 4 * se)
    assert exact[-1] > float(res.claimed[-1, 0, 0]) * 1.2  # the unmodelled bias makes the filter over-confident


def test_bank_of_dead_reckoning_models_vmap_equals_loop():
    taus = jnp.array([10.0, 100.0, 1000.0])
    _, speed, course = _dr_model(100.0)
    model, *_ = _dr_model(100.0)
    rows = model.H[:, :, :2]
    _, y = sample(model, jax.random.PRNGKey(3), 60)

    def ll(tau):
        m = nav.dead_reckoning_error_model(speed, course, 1.0, 0.1, 60.0, 0.05, tau, rows, 2.0, 3.0)
        return kalman_filter(m, y).log_likelihood

    batched = np.asarray(jax.vmap(ll)(taus))
    looped = np.array([float(ll(tau)) for tau in taus])
    np.testing.assert_allclose(batched, looped, rtol=1e-12)


def test_bad_inputs_name_the_argument():
    with pytest.raises(ValueError, match="sigma_v"):
        nav.random_walk_gnss(1.0, -1.0, 1.0)
    with pytest.raises(ValueError, match="range_rows"):
        nav.dead_reckoning_error_model(
            np.ones(5), np.zeros(5), 1.0, 0.1, 60.0, 0.05, 100.0, np.ones((4, 2, 2)), 2.0, 3.0
        )
    with pytest.raises(ValueError, match="speed, course"):
        nav.dead_reckoning_track([0.0, 0.0], np.ones(5), np.zeros(4), 1.0)
    true = nav.random_walk_gnss(1.0, 1.0, 1.0)
    with pytest.raises(ValueError, match="C"):
        nav.mismatched_covariance(true, true, 10, C=np.eye(3))
    with pytest.raises(ValueError, match="mask"):
        nav.mismatched_covariance(true, true, 10, mask=np.ones(7, bool))
