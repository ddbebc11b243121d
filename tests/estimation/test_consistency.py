"""NEES/NIS χ² consistency over 1,000 Monte-Carlo runs (one vmapped call) and χ² gating."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.estimation.gating import chi2_bounds, chi2_gate, chi2_threshold, fraction_inside, nees, nis
from jaxsim.estimation.lgssm import LinearGaussianSSM, kalman_filter, sample
from tests.estimation.helpers import random_model

N_RUNS, T = 1000, 40


def _mc_statistics(truth: LinearGaussianSSM, assumed: LinearGaussianSSM):
    """Per-step NEES and NIS averaged over N_RUNS runs simulated from ``truth``."""

    @jax.jit
    def run(keys):
        def one(key):
            x, y = sample(truth, key, T)
            res = kalman_filter(assumed, y)
            return nees(x, res.means, res.covs), res.nis

        return jax.vmap(one)(keys)

    e, s = run(jax.random.split(jax.random.PRNGKey(42), N_RUNS))
    return np.asarray(e).mean(axis=0), np.asarray(s).mean(axis=0)


def test_nees_and_nis_inside_chi2_bounds_for_consistent_filter_and_outside_for_mistuned():
    rng = np.random.default_rng(30)
    model = random_model(rng, n=4, p=2)
    nees_bounds = chi2_bounds(4, N_RUNS, prob=0.95)
    nis_bounds = chi2_bounds(2, N_RUNS, prob=0.95)
    e, s = _mc_statistics(model, model)
    assert fraction_inside(e, nees_bounds) >= 0.85, (e, nees_bounds)
    assert fraction_inside(s, nis_bounds) >= 0.85, (s, nis_bounds)
    # over-confident filter: it assumes a tenth of the process and measurement noise
    bad = LinearGaussianSSM(model.F, model.Q / 10, model.H, model.R / 10, model.m0, model.P0)
    e_bad, s_bad = _mc_statistics(model, bad)
    assert fraction_inside(e_bad, nees_bounds) <= 0.05 and np.all(e_bad[5:] > nees_bounds[1])
    assert fraction_inside(s_bad, nis_bounds) <= 0.05 and np.all(s_bad[5:] > nis_bounds[1])


def test_chi2_threshold_reproduces_gravimetry_gate():
    # seed 004 (Nosov & Motorin): χ²(4) at 0.99 used as the GNSS manoeuvre gate, printed as 13.28
    assert round(chi2_threshold(4, 0.99), 2) == 13.28
    lo, hi = chi2_bounds(3, 1)
    assert lo < 3 < hi


def test_gated_filter_equals_filter_masked_by_its_decisions_and_rejects_outliers():
    rng = np.random.default_rng(31)
    model = random_model(rng, n=4, p=2)
    _, y = sample(model, jax.random.PRNGKey(3), 60)
    y = np.asarray(y).copy()
    outliers = np.zeros(60, bool)
    outliers[[10, 25, 26, 40]] = True
    y[outliers] += 50.0
    thr = chi2_threshold(2, 0.999)
    gated = kalman_filter(model, y, gate=thr)
    rejected = ~np.asarray(gated.accepted)
    assert np.all(rejected[outliers])
    assert rejected.sum() <= outliers.sum() + 1
    masked = kalman_filter(model, y, mask=~rejected)
    np.testing.assert_allclose(gated.means, masked.means, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(gated.covs, masked.covs, rtol=1e-12, atol=1e-12)
    # the gate's statistic is the innovation NIS
    r, S = gated.innovations[10], gated.innovation_covs[10]
    assert not bool(chi2_gate(r, S, thr))
    np.testing.assert_allclose(nis(r, S), gated.nis[10], rtol=1e-12)


def test_false_alarm_rate_of_gate_matches_its_probability():
    rng = np.random.default_rng(32)
    model = random_model(rng, n=3, p=2)
    thr = chi2_threshold(2, 0.95)

    @jax.jit
    def rate(keys):
        return jax.vmap(lambda k: 1.0 - jnp.mean(kalman_filter(model, sample(model, k, 50)[1], gate=thr).accepted))(
            keys
        )

    r = float(jnp.mean(rate(jax.random.split(jax.random.PRNGKey(5), 400))))
    # 20,000 decisions: binomial sd of the rate ≈ 0.0015 around 0.05 (rejections slightly perturb later steps)
    assert abs(r - 0.05) < 0.008, r
