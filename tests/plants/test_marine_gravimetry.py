"""Marine-gravimetry shaping filters (jaxsim.plants.marine_gravimetry) against SciPy: the Lyapunov
variances, the spectrum ↔ covariance Fourier pair by adaptive quadrature, the transfer function, the
χ²(4) threshold and the GNSS CA model against Van Loan."""

import math

import numpy as np
import pytest
import scipy.integrate
import scipy.linalg
import scipy.signal
import scipy.stats

from jaxsim.core.discretize import van_loan
from jaxsim.estimation.gating import chi2_threshold
from jaxsim.plants import marine_gravimetry as mg

BETA, SIGMA = 3.5e-4, 20.0


def test_jordan_filter_variance_and_state_space_covariance_by_scipy():
    f = mg.jordan_filter(BETA, SIGMA)
    A, G, H = (np.asarray(x) for x in f)
    assert G[2, 0] ** 2 == pytest.approx(10 * BETA**3 * SIGMA**2, rel=1e-14)
    P = scipy.linalg.solve_continuous_lyapunov(A, -G @ G.T)
    assert (H @ P @ H.T)[0, 0] == pytest.approx(SIGMA**2, rel=1e-7)
    for tau in (0.0, 1000.0, 6000.0):
        k_ss = (H @ scipy.linalg.expm(A * tau) @ P @ H.T)[0, 0]
        assert k_ss == pytest.approx(float(mg.jordan_covariance(tau, BETA, SIGMA)), rel=1e-6, abs=1e-6)


def test_spectrum_covariance_fourier_pair_by_scipy_quad():
    for tau in (0.0, 2000.0, 8000.0, 20000.0):
        if tau == 0.0:
            val, _ = scipy.integrate.quad(lambda w: float(mg.jordan_spectrum(w, BETA, SIGMA)), 0, np.inf)
        else:  # QAWF: Fourier integral on [0, ∞)
            val, _ = scipy.integrate.quad(
                lambda w: float(mg.jordan_spectrum(w, BETA, SIGMA)), 0, np.inf, weight="cos", wvar=tau
            )
        assert val / math.pi == pytest.approx(float(mg.jordan_covariance(tau, BETA, SIGMA)), rel=1e-6, abs=1e-6)


def test_transfer_function_is_q_s_plus_mu_beta_over_s_plus_beta_cubed():
    A, G, H = (np.asarray(x) for x in mg.jordan_filter(BETA, SIGMA))
    num, den = scipy.signal.ss2tf(A, G, H, np.zeros((1, 1)))
    q = math.sqrt(10 * BETA**3 * SIGMA**2)
    np.testing.assert_allclose(den, np.poly([-BETA] * 3), rtol=1e-9, atol=1e-20)
    np.testing.assert_allclose(num[0][-2:], [q, q * BETA / math.sqrt(5)], rtol=1e-9)
    assert np.all(np.abs(num[0][:-2]) < 1e-12 * q)
    w = np.array([0.0, BETA, 10 * BETA])
    _, h = scipy.signal.freqs(q * np.array([1.0, BETA * mg.MU]), np.poly([-BETA] * 3), w)
    np.testing.assert_allclose(np.abs(h) ** 2, mg.jordan_spectrum(w, BETA, SIGMA), rtol=1e-9)


@pytest.mark.parametrize("sigma_v, omega0, alpha, kappa", [(1.0, 0.6, 0.06, 1.0), (0.5, 0.8, 0.2, 2.0)])
def test_heave_filter_has_the_requested_variance(sigma_v, omega0, alpha, kappa):
    A, G, H = (np.asarray(x) for x in mg.heave_filter(sigma_v, omega0, alpha, kappa))
    P = scipy.linalg.solve_continuous_lyapunov(A, -G @ G.T)
    assert P[0, 0] == pytest.approx(sigma_v**2, rel=1e-10)
    a1, a2, a3 = mg.heave_coefficients(omega0, alpha, kappa)
    np.testing.assert_allclose(
        [1.0, a1, a2, a3], np.polymul([1.0, kappa * alpha], [1.0, 2 * alpha, alpha**2 + omega0**2]), rtol=1e-12
    )
    with pytest.raises(ValueError, match="sigma_v"):
        mg.heave_filter(-1.0, omega0, alpha, kappa)


def test_chi2_threshold_and_gnss_model():
    assert chi2_threshold(4, 0.99) == pytest.approx(scipy.stats.chi2.ppf(0.99, 4), rel=1e-14)
    assert round(chi2_threshold(4, 0.99), 2) == 13.28
    F, Qu, H = mg.gnss_ca_model(1.0)
    a = np.kron(np.eye(2), np.diag([1.0, 1.0], k=1))
    g = np.kron(np.eye(2), np.array([[0.0], [0.0], [1.0]]))
    Fd, Qd = van_loan(a, np.eye(2), 1.0, g)
    np.testing.assert_allclose(F, Fd, atol=1e-14)
    np.testing.assert_allclose(Qu, Qd, atol=1e-14)
    assert H.shape == (4, 6) and H[2, 1] == 1.0 and H[3, 4] == 1.0
