"""Known-turn filter bank drifts (jaxsim.estimation.filter_bank_asn) against independent references:
SciPy's matrix exponential and DARE, a brute-force NumPy moment recursion, finite differences."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg

from jaxsim.estimation import filter_bank_asn as fb
from jaxsim.estimation.mmae import sprt_bank_size, sprt_thresholds

Q, R = 1e-3 * np.eye(2), 0.1 * np.eye(2)
SPEED = float(np.hypot(0.5, 0.5))
H = np.asarray(fb.H_POSITION)


def test_turn_model_is_the_matrix_exponential_and_cv_at_zero_rate():
    w, dt = 0.3, 0.7
    a = np.zeros((4, 4))
    a[0, 1] = a[2, 3] = 1.0
    a[1, 3], a[3, 1] = -w, w  # v̇x = −ω vy, v̇y = ω vx (left turn for ω > 0)
    F, G = fb.turn_model(w, dt)
    np.testing.assert_allclose(F, scipy.linalg.expm(a * dt), atol=1e-13)
    F0, G0 = fb.turn_model(0.0, dt)
    cv = np.eye(4)
    cv[0, 1] = cv[2, 3] = dt
    np.testing.assert_allclose(F0, cv, atol=1e-15)
    np.testing.assert_allclose(G, [[dt**2 / 2, 0], [dt, 0], [0, dt**2 / 2], [0, dt]])
    with pytest.raises(ValueError, match="dt"):
        fb.turn_model(w, 0.0)


def test_steady_filter_matches_scipy_dare():
    w, dt = -0.1, 1.0
    f = fb.steady_filter(w, dt, Q, R)
    F, G = (np.asarray(x) for x in fb.turn_model(w, dt))
    P = scipy.linalg.solve_discrete_are(F.T, H.T, G @ Q @ G.T, R)
    np.testing.assert_allclose(f.P, P, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(f.S, H @ P @ H.T + R, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(f.K, P @ H.T @ np.linalg.inv(H @ P @ H.T + R), rtol=1e-8, atol=1e-12)


def test_innovation_moments_match_a_brute_force_moment_recursion():
    dt, w_true, w_filt = 1.0, SPEED / 5.0, -SPEED / 5.0
    f = fb.steady_filter(w_filt, dt, Q, R)
    bias, cov = fb.innovation_moments(w_true, f, dt, Q, R, SPEED)
    F0 = np.asarray(fb.turn_model(w_true, dt)[0])
    F1, K, G = np.asarray(f.F), np.asarray(f.K), np.asarray(f.G)
    A = F1 @ (np.eye(4) - K @ H)
    x, e, P = np.array([1.0, 0.5, 1.0, 0.5]), np.zeros(4), np.zeros((4, 4))
    for _ in range(600):  # ρ(A) ≈ 0.8: converged long before
        e = (F0 - F1) @ x + A @ e
        P = A @ P @ A.T + F1 @ K @ R @ K.T @ F1.T + G @ Q @ G.T
        x = F0 @ x
    # the bias rotates with the velocity: its size is fixed, its direction depends on the phase
    assert np.linalg.norm(H @ e) == pytest.approx(float(jnp.linalg.norm(bias)), rel=1e-9)
    np.testing.assert_allclose(cov, H @ P @ H.T + R, rtol=1e-9, atol=1e-12)


def test_matched_filter_has_no_bias_and_the_drifts_are_antisymmetric():
    dt, w = 1.0, SPEED / 8.0
    f = fb.steady_filter(w, dt, Q, R)
    bias, cov = fb.innovation_moments(w, f, dt, Q, R, SPEED)
    np.testing.assert_allclose(bias, 0.0, atol=1e-12)
    np.testing.assert_allclose(cov, f.S, rtol=1e-9, atol=1e-12)
    m = 2
    want = -0.5 * (m * np.log(2 * np.pi) + np.log(np.linalg.det(np.asarray(f.S)))) - m / 2
    assert float(fb.expected_loglik(w, f, dt, Q, R, SPEED)) == pytest.approx(want, rel=1e-12)
    mu0, mu1 = fb.llr_drifts(w, -w, dt, Q, R, SPEED)
    assert float(mu0) < 0 < float(mu1)
    assert float(mu1) == pytest.approx(-float(mu0), rel=1e-9)  # left/right mirror symmetry


def test_batched_drifts_grad_and_bank_size():
    """One compiled ``vmap(value_and_grad)`` over (radius, T): the bank size agrees with the mmae helper,
    the left/right symmetry holds per radius, and ∂μ₁/∂T equals the finite difference."""
    a, b = sprt_thresholds(1e-3, 1e-3)

    def mu1(r, dt):
        return fb.llr_drifts(SPEED / r, -SPEED / r, dt, Q, R, SPEED)[1]

    def both(r, dt):
        mu0, mu1_ = fb.llr_drifts(SPEED / r, -SPEED / r, dt, Q, R, SPEED)
        return fb.wald_bank_size(mu0, mu1_, a, b, 1e-3), mu0, mu1_

    run = jax.jit(jax.vmap(lambda r, dt: (jax.value_and_grad(mu1, argnums=1)(r, dt), both(r, dt))))
    h = 1e-5
    radii = jnp.array([2.0, 7.0, 20.0, 10.0, 10.0, 10.0])
    dts = jnp.array([1.0, 1.0, 1.0, 0.5 - h, 0.5, 0.5 + h])
    (val, grad), (n, mu0, mu1_) = run(radii, dts)
    np.testing.assert_allclose(val, mu1_, rtol=1e-12)
    np.testing.assert_allclose(mu0, -mu1_, rtol=1e-9)
    np.testing.assert_allclose(n, sprt_bank_size(1e-3, 1e-3, mu0, mu1_), rtol=1e-12)
    assert float(n[2]) > float(n[1])  # less distinguishable at a larger radius
    fd = (float(val[5]) - float(val[3])) / (2 * h)
    assert float(grad[4]) == pytest.approx(fd, rel=1e-5, abs=1e-9)
