"""Steady-state Kalman gain (DARE, SciPy oracle), Kalman–Bucy (CARE), continuous–discrete prediction, and
the deprecated aliases of the one steady-state API (:mod:`jaxsim.control.kalman_gain`)."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg

from jaxsim.control.kalman_gain import discrete_kalman, kalman_bucy
from jaxsim.core.discretize import van_loan
from jaxsim.estimation.kalman_bucy import continuous_discrete_predict, kalman_bucy_step, steady_state_kalman_bucy
from jaxsim.estimation.lgssm import kalman_filter, lgssm
from jaxsim.estimation.steady_state import steady_state_kalman
from jaxsim.estimation.types import GaussianState
from tests.estimation.helpers import spd


def test_steady_state_gain_matches_scipy_dare_and_the_converged_filter():
    rng = np.random.default_rng(50)
    f = rng.standard_normal((4, 4)) * 0.6  # possibly unstable: detectable with H below
    h, q, r = rng.standard_normal((2, 4)), spd(rng, 4), spd(rng, 2)
    ss = discrete_kalman(f, h, q, r)
    ref = scipy.linalg.solve_discrete_are(f.T, h.T, q, r)
    np.testing.assert_allclose(ss.p_prior, ref, rtol=1e-9, atol=1e-10)
    model = lgssm(f, q, h, r, np.zeros(4), np.eye(4))
    res = kalman_filter(model, np.zeros((200, 2)))
    np.testing.assert_allclose(res.predicted_covs[-1], ss.p_prior, rtol=1e-8, atol=1e-9)
    np.testing.assert_allclose(res.covs[-1], ss.p_post, rtol=1e-8, atol=1e-9)
    np.testing.assert_allclose(res.innovation_covs[-1], h @ np.asarray(ss.p_prior) @ h.T + r, rtol=1e-8, atol=1e-9)


def test_kalman_bucy_steady_state_matches_scipy_care_and_the_integrated_riccati():
    rng = np.random.default_rng(51)
    a = rng.standard_normal((3, 3))
    c, q, r = rng.standard_normal((1, 3)), spd(rng, 3), np.array([[0.2]])
    k, p = kalman_bucy(a, c, q, r)
    ref = scipy.linalg.solve_continuous_are(a.T, c.T, q, r)
    np.testing.assert_allclose(p, ref, rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(k, ref @ c.T / 0.2, rtol=1e-9)
    step = lambda _, s: kalman_bucy_step(s, jnp.zeros(1), a, c, q, r, 0.05, substeps=2)  # noqa: E731
    state = jax.jit(lambda s: jax.lax.fori_loop(0, 400, step, s))(GaussianState(jnp.zeros(3), jnp.eye(3)))
    np.testing.assert_allclose(state.cov, ref, rtol=1e-6, atol=1e-8)


def test_continuous_discrete_prediction_matches_van_loan():
    rng = np.random.default_rng(52)
    a, qc, g = rng.standard_normal((3, 3)), spd(rng, 2), rng.standard_normal((3, 2))
    b, u = rng.standard_normal((3, 1)), np.array([0.7])
    s0 = GaussianState(jnp.asarray(rng.standard_normal(3)), jnp.asarray(spd(rng, 3)))
    got = continuous_discrete_predict(s0, a, qc, 0.2, B=b, u=u, G=g, substeps=40)
    ad, qd = van_loan(a, qc, 0.2, g)
    blk = scipy.linalg.expm(np.block([[a, b], [np.zeros((1, 4))]]) * 0.2)
    np.testing.assert_allclose(got.mean, ad @ s0.mean + blk[:3, 3:] @ u, rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(got.cov, ad @ s0.cov @ ad.T + qd, rtol=1e-9, atol=1e-10)


def test_deprecated_aliases_warn_and_equal_the_one_steady_state_api():
    rng = np.random.default_rng(53)
    f, h, q, r = rng.standard_normal((3, 3)) * 0.5, rng.standard_normal((2, 3)), spd(rng, 3), spd(rng, 2)
    with pytest.warns(DeprecationWarning, match="discrete_kalman"):
        old = steady_state_kalman(f, q, h, r)  # the old (F, Q, H, R) order
    new = discrete_kalman(f, h, q, r)
    np.testing.assert_array_equal(old.predicted_cov, new.p_prior)
    np.testing.assert_array_equal(old.filtered_cov, new.p_post)
    np.testing.assert_array_equal(old.gain, new.k)
    np.testing.assert_allclose(old.innovation_cov, h @ np.asarray(new.p_prior) @ h.T + r, rtol=1e-13)
    with pytest.warns(DeprecationWarning, match="kalman_bucy"):
        p, k = steady_state_kalman_bucy(f, h, q, r)
    gain = kalman_bucy(f, h, q, r)
    np.testing.assert_array_equal(p, gain.p)
    np.testing.assert_array_equal(k, gain.l)


def test_steady_state_bad_input():
    with pytest.warns(DeprecationWarning), pytest.raises(ValueError, match="^Q: must be symmetric"):
        steady_state_kalman(np.eye(2), np.array([[1.0, 0.5], [0.0, 1.0]]), np.eye(2), np.eye(2))
    with pytest.warns(DeprecationWarning), pytest.raises(ValueError, match="^H: expected shape"):
        steady_state_kalman(np.eye(2), np.eye(2), np.ones((1, 3)), np.eye(1))
    with pytest.raises(ValueError, match="^q: must be symmetric"):
        discrete_kalman(np.eye(2), np.eye(2), np.array([[1.0, 0.5], [0.0, 1.0]]), np.eye(2))


def test_errors_name_the_callers_arguments():
    # the unstable mode 2 is invisible to H: the message names F and H, not the dual pair's a/c
    with pytest.warns(DeprecationWarning), pytest.raises(ValueError, match=r"^\(F, H\): not detectable"):
        steady_state_kalman(np.diag([2.0, 0.5]), np.eye(2), np.array([[0.0, 1.0]]), np.eye(1))
    with pytest.warns(DeprecationWarning), pytest.raises(ValueError, match=r"^\(A, C\): not detectable"):
        steady_state_kalman_bucy(np.diag([1.0, -1.0]), np.array([[0.0, 1.0]]), np.eye(2), np.eye(1))
