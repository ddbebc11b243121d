"""IMM (FilterPy oracle; linear, EKF and UKF members), static MMAE bank, Wald SPRT helpers."""

from __future__ import annotations

import filterpy.kalman as fk
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.estimation.imm import (
    ekf_member,
    imm,
    imm_estimate,
    imm_filter,
    imm_init,
    imm_predict,
    imm_update,
    linear_member,
    ukf_member,
)
from jaxsim.estimation.lgssm import LinearGaussianSSM, kalman_filter, lgssm, sample
from jaxsim.estimation.mmae import bank_filter, sprt, sprt_bank_size, sprt_thresholds, wald_asn
from jaxsim.estimation.nonlinear import nonlinear_ssm

DT = 1.0
F_CV = np.array([[1, DT, 0, 0], [0, 1, 0, 0], [0, 0, 1, DT], [0, 0, 0, 1]], float)
H_POS = np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0]])
G = np.array([[DT**2 / 2, 0], [DT, 0], [0, DT**2 / 2], [0, DT]])
PI = np.array([[0.95, 0.05], [0.10, 0.90]])


def _manoeuvring_track(t=40, seed=0):
    """A constant-velocity track with a turn in the middle, position measurements (σ = 1)."""
    rng = np.random.default_rng(seed)
    x, ys = np.array([0.0, 1.0, 0.0, 0.5]), []
    for k in range(t):
        ys.append(H_POS @ x + rng.normal(0, 1.0, 2))
        acc = np.array([0.0, 0.0]) if not 15 <= k < 25 else np.array([-0.3, 0.4])
        x = F_CV @ x + G @ (acc + rng.normal(0, 0.05, 2))
    return np.array(ys)


def _members():
    return (linear_member(F_CV, G @ G.T * 0.01, H_POS, np.eye(2)), linear_member(F_CV, G @ G.T * 1.0, H_POS, np.eye(2)))


def _init():
    return imm_init(np.zeros((2, 4)), np.stack([np.eye(4) * 10.0] * 2), np.array([0.6, 0.4]))


def test_imm_matches_filterpy():
    y = _manoeuvring_track()
    filters = []
    for q in (0.01, 1.0):
        kf = fk.KalmanFilter(dim_x=4, dim_z=2)
        kf.F, kf.H, kf.R, kf.Q = F_CV, H_POS, np.eye(2), G @ G.T * q
        kf.x, kf.P = np.zeros((4, 1)), np.eye(4) * 10.0
        filters.append(kf)
    ref = fk.IMMEstimator(filters, np.array([0.6, 0.4]), PI)
    model, state = imm(_members(), PI), _init()
    step = jax.jit(lambda s, y_t: imm_update(model, imm_predict(model, s), y_t)[0])
    for k in range(len(y)):
        ref.predict()
        ref.update(y[k][:, None])
        state = step(state, y[k])
        np.testing.assert_allclose(state.probs, ref.mu, rtol=1e-9, atol=1e-12)
        for j in range(2):
            np.testing.assert_allclose(state.means[j], filters[j].x[:, 0], rtol=1e-9, atol=1e-9)
            np.testing.assert_allclose(state.covs[j], filters[j].P, rtol=1e-9, atol=1e-9)
        est = imm_estimate(state)
        np.testing.assert_allclose(est.mean, ref.x[:, 0], rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(est.cov, ref.P, rtol=1e-9, atol=1e-9)
    # the manoeuvre raises the probability of the high-noise mode
    res = imm_filter(model, imm_predict(model, _init()), y)
    assert float(res.mode_probs[22, 1]) > 0.5 > float(res.mode_probs[10, 1])
    np.testing.assert_allclose(res.means[-1], est.mean, rtol=1e-10, atol=1e-10)


def test_single_member_imm_is_the_kalman_filter():
    y = _manoeuvring_track(seed=1)
    model = imm(_members()[:1], np.ones((1, 1)))
    res = imm_filter(model, imm_init(np.zeros((1, 4)), np.eye(4)[None] * 10.0, np.ones(1)), y)
    kf = kalman_filter(lgssm(F_CV, G @ G.T * 0.01, H_POS, np.eye(2), np.zeros(4), np.eye(4) * 10.0), y)
    np.testing.assert_allclose(res.means, kf.means, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(res.log_likelihood, kf.log_likelihood, rtol=1e-12)


@pytest.mark.parametrize("kind", ["ekf", "ukf"])
def test_imm_with_nonlinear_members_on_linear_models_equals_linear_imm(kind):
    y = _manoeuvring_track(seed=2)
    ref = imm_filter(imm(_members(), PI), _init(), y)
    mems = []
    for q in (0.01, 1.0):
        nl = nonlinear_ssm(
            lambda p, x, u: jnp.asarray(F_CV) @ x,
            lambda p, x: jnp.asarray(H_POS) @ x,
            G @ G.T * q,
            np.eye(2),
            np.zeros(4),
            np.eye(4),
        )
        mems.append(ekf_member(nl) if kind == "ekf" else ukf_member(nl, alpha=0.9))
    got = imm_filter(imm(mems, PI), _init(), y)
    np.testing.assert_allclose(got.mode_probs, ref.mode_probs, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(got.means, ref.means, rtol=1e-9, atol=1e-9)


def test_imm_rejects_bad_transition_matrix():
    with pytest.raises(
        ValueError,
        match=r"^transition: probabilities must sum to 1 along the last axis, "
        r"got sums \[1.1, 1.0\]",
    ):
        imm(_members(), np.array([[0.9, 0.2], [0.1, 0.9]]))
    with pytest.raises(ValueError, match="^transition: expected shape"):
        imm(_members(), np.eye(3))


def test_static_bank_identifies_the_true_noise_level_and_equals_separate_filters():
    scales = np.array([0.25, 1.0, 4.0])
    truth = lgssm(F_CV, G @ G.T * 0.1, H_POS, np.eye(2), np.zeros(4), np.eye(4))
    _, y = sample(truth, jax.random.PRNGKey(7), 150)
    models = LinearGaussianSSM(
        F=jnp.stack([F_CV] * 3),
        Q=jnp.stack([G @ G.T * 0.1] * 3),
        H=jnp.stack([H_POS] * 3),
        R=jnp.stack([np.eye(2) * s for s in scales]),
        m0=jnp.zeros((3, 4)),
        P0=jnp.stack([np.eye(4)] * 3),
    )
    bank = bank_filter(models, y)
    assert float(jnp.exp(bank.log_probs[-1, 1])) > 0.99
    lls = []
    for i, s in enumerate(scales):
        one = kalman_filter(lgssm(F_CV, G @ G.T * 0.1, H_POS, np.eye(2) * s, np.zeros(4), np.eye(4)), y)
        np.testing.assert_allclose(bank.filtered.log_likelihood[i], one.log_likelihood, rtol=1e-12)
        lls.append(float(jnp.sum(one.log_likelihoods[:20])))
    # posterior after 20 steps = prior × likelihood of y_0..y_19, normalised
    lls = np.array(lls)
    post = np.exp(lls - lls.max()) / np.exp(lls - lls.max()).sum()
    np.testing.assert_allclose(np.exp(bank.log_probs[19]), post, rtol=1e-9)


def test_sprt_thresholds_and_wald_average_sample_numbers():
    a, b = sprt_thresholds(0.001, 0.001)
    assert round(a, 4) == 6.9068 and round(b, 4) == -6.9068  # seed 004, Golubkov: A = −B = 6.9068
    alpha = beta = 0.01
    delta = 0.5  # Gaussian mean shift: λ = δ y − δ²/2, μ₀ = −δ²/2, μ₁ = δ²/2
    upper, lower = sprt_thresholds(alpha, beta)
    keys = jax.random.split(jax.random.PRNGKey(0), 4000)

    @jax.jit
    def run(mean):
        def one(k):
            yv = mean + jax.random.normal(k, (400,))
            return sprt(delta * yv - delta**2 / 2, upper, lower)

        return jax.vmap(one)(keys)

    r0, r1 = run(0.0), run(delta)
    assert np.all(np.asarray(r0.decision) != 0) and np.all(np.asarray(r1.decision) != 0)
    type1 = float(jnp.mean(r0.decision == 1))
    type2 = float(jnp.mean(r1.decision == -1))
    assert type1 <= alpha / (1 - beta) + 0.005 and type2 <= beta / (1 - alpha) + 0.005
    n0, n1 = wald_asn(alpha, beta, -(delta**2) / 2, delta**2 / 2)
    # Wald's ASN neglects the overshoot over the thresholds, so the true ASN is a little larger
    for mc, approx in ((r0.n_samples.mean(), n0), (r1.n_samples.mean(), n1)):
        assert 1.0 <= float(mc) / float(approx) <= 1.3, (mc, approx)
    size = sprt_bank_size(alpha, beta, -(delta**2) / 2, delta**2 / 2)
    np.testing.assert_allclose(size, max((upper - lower) / (delta**2 / 2), float(n0)), rtol=1e-12)
