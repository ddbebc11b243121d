"""Float-gyro drift kernels against independent references: the discretisation against SciPy's matrix
exponential (Van Loan), the Kalman log-likelihood against the batch Gaussian density of the whole record
(SciPy), the bank against a loop, the ML gradient against finite differences, and the augmented EKF with
frozen parameters against the Kalman filter."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg
import scipy.stats

from jaxsim.estimation.ekf import extended_kalman_filter
from jaxsim.estimation.lgssm import kalman_filter, sample
from jaxsim.inertial import float_gyro as fg

DT, T = 10.0, 40
KW = dict(dt=DT, sigma=1.0, sigma0=3.0, r=0.3)


@pytest.fixture(scope="module")
def record():
    u = fg.warmup_temperature(jnp.arange(T) * DT, 10.0, 200.0)[:, None]
    model = fg.drift_model(fg.ALPHA_TRUE * 20, fg.BETA_TRUE * 20, **KW)
    _, y = jax.jit(sample, static_argnums=2)(model, jax.random.PRNGKey(3), T, u)
    return np.asarray(y), np.asarray(u)


@pytest.fixture(scope="module")
def loglik(record):
    """One compiled log-likelihood of (α, β) on the record (used by every check)."""
    y, u = record
    return jax.jit(lambda a, b: fg.log_likelihood(a, b, y, u, **KW))


def test_discretisation_against_van_loan():
    alpha, beta, sigma = 0.011, -0.02, 1.3
    phi, b, q = (float(v) for v in fg.transition_terms(alpha, beta, DT, sigma))
    # input gain: expm of [[−α, β], [0, 0]]·Δ
    m = scipy.linalg.expm(np.array([[-alpha, beta], [0.0, 0.0]]) * DT)
    assert phi == pytest.approx(m[0, 0], rel=1e-12) and b == pytest.approx(m[0, 1], rel=1e-12)
    # noise: Van Loan with diffusion 2ασ²
    vl = scipy.linalg.expm(np.array([[alpha, 2 * alpha * sigma**2], [0.0, -alpha]]) * DT)
    assert q == pytest.approx(vl[1, 1] * vl[0, 1], rel=1e-10)


def test_log_likelihood_equals_batch_gaussian_density(record, loglik):
    y, u = record
    alpha, beta = 0.004, -0.03
    phi, b, _ = (float(v) for v in fg.transition_terms(alpha, beta, DT, 1.0))
    mean = np.zeros(T)  # forced response: m_{k+1} = φ m_k + b u_k
    for k in range(T - 1):
        mean[k + 1] = phi * mean[k] + b * u[k, 0]
    lag = np.abs(np.subtract.outer(np.arange(T), np.arange(T)))
    cov = KW["sigma0"] ** 2 + KW["sigma"] ** 2 * phi**lag + KW["r"] ** 2 * np.eye(T)  # stationary ε̃ + ε₀ + v
    ref = scipy.stats.multivariate_normal(mean, cov).logpdf(y[:, 0])
    assert float(loglik(alpha, beta)) == pytest.approx(ref, rel=1e-10)


def test_bank_equals_loop_and_posterior(record, loglik):
    y, u = record
    A = jnp.array([0.004, 0.011, 0.02])
    B = jnp.array([-0.03, -0.02, -0.01])
    ll = np.asarray(fg.bank_log_likelihoods(A, B, y, u, **KW))
    loop = [float(loglik(a, b)) for a, b in zip(A, B)]
    np.testing.assert_allclose(ll, loop, rtol=1e-12)
    post = fg.grid_posterior_mean(A, B, ll)
    w = np.exp(ll - ll.max()) / np.exp(ll - ll.max()).sum()
    np.testing.assert_allclose(post.weights, w, rtol=1e-12)
    assert float(post.alpha) == pytest.approx(w @ np.asarray(A), rel=1e-12)
    assert float(post.beta_std) == pytest.approx(np.sqrt(w @ (np.asarray(B) - w @ np.asarray(B)) ** 2), rel=1e-9)


def test_ml_gradient_and_stationary_point(record, loglik):
    y, u = record
    ml = jax.jit(lambda n: fg.ml_estimate(y, u, 0.008, -0.015, iterations=n, **KW))  # one compilation
    start = ml(0)  # the gradient at the start against central finite differences of the log-likelihood
    f = lambda th: float(loglik(np.exp(th[0]), th[1] * fg.BETA_SCALE))  # noqa: E731
    th, h = np.array([np.log(0.008), -15.0]), 1e-6
    fd = [(f(th + h * e) - f(th - h * e)) / (2 * h) for e in np.eye(2)]
    np.testing.assert_allclose(start.grad, fd, rtol=1e-5)
    assert float(start.alpha) == pytest.approx(0.008, rel=1e-12)
    est = ml(20)
    assert float(est.grad_norm) < 1e-6
    assert float(est.log_likelihood) >= float(start.log_likelihood) - 1e-9
    assert float(est.log_likelihood) >= float(loglik(fg.ALPHA_TRUE * 20, fg.BETA_TRUE * 20))
    assert float(est.alpha_std) > 0 and float(est.beta_std) > 0


def test_augmented_ekf_with_frozen_parameters_is_the_kalman_filter(record):
    y, u = record
    alpha, beta = 0.011, -0.02
    ekf = fg.augmented_ekf_model(DT, 1.0, 3.0, 0.3, alpha, beta, 1e-15, 1e-15)
    e = jax.jit(extended_kalman_filter)(ekf, y, u)
    kf = jax.jit(kalman_filter)(fg.drift_model(alpha, beta, **KW), y, u)
    np.testing.assert_allclose(e.means[:, :2], kf.means, rtol=1e-8, atol=1e-9)
    np.testing.assert_allclose(e.covs[:, :2, :2], kf.covs, rtol=1e-7, atol=1e-12)
    assert float(e.log_likelihood) == pytest.approx(float(kf.log_likelihood), rel=1e-9)
    assert np.all(np.linalg.eigvalsh(np.asarray(e.covs)) > -1e-12)


def test_bad_input_names_the_argument():
    with pytest.raises(ValueError, match="alpha"):
        fg.drift_model(-1e-3, 0.0)
    with pytest.raises(ValueError, match="dt"):
        fg.drift_model(1e-3, 0.0, dt=0.0)
    with pytest.raises(ValueError, match="tau"):
        fg.warmup_temperature(1.0, 10.0, 0.0)
