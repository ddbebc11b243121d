"""Seed 003's tracker: window bank = LS line fits, the Sugeno window selector (exact and smooth)."""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.control.fuzzy import evaluate
from jaxsim.estimation.alpha_beta import window_bank
from jaxsim.estimation.window_selector import (
    WindowBank,
    fixed_window,
    noise_scale,
    predicted_plots,
    select_estimates,
    select_windows,
    selector_fis,
    window_bank_filter,
    window_selector,
)

DT = 3.0
J = 10
select = jax.jit(select_windows, static_argnames=("smooth",))  # eager dispatch of many small ops is slow


def _plots(t=20, seed=0):
    rng = np.random.default_rng(seed)
    times = np.arange(t) * DT
    truth = np.stack([-600 + 10.0 * times + 0.05 * times**2, 8000 - 2.0 * times], axis=1)
    return truth + rng.normal(0, 7.0, truth.shape)


def test_bank_is_the_least_squares_line_over_the_last_j_plots():
    z = _plots()
    bank = window_bank_filter(z, J, DT)
    for t in range(1, z.shape[0]):
        for j in range(2, J + 1):
            k = min(j, t + 1)  # a young track's window holds every plot so far
            tt = (np.arange(k) - (k - 1)) * DT
            slope, icpt = np.polyfit(tt, z[t - k + 1 : t + 1], 1)
            np.testing.assert_allclose(bank.positions[t, j - 2], icpt, rtol=0, atol=1e-9)
            np.testing.assert_allclose(bank.velocities[t, j - 2], slope, rtol=0, atol=1e-9)
            np.testing.assert_allclose(bank.predictions[t, j - 2], icpt + slope * DT, rtol=0, atol=1e-9)
    # on full windows it is alpha_beta.window_bank (the FIR form of the same fits)
    for t in range(J - 1, z.shape[0]):
        ref = np.asarray(window_bank(z[t - J + 1 : t + 1], DT))  # (J − 1, 2, d)
        np.testing.assert_allclose(bank.positions[t], ref[:, 0], atol=1e-9)
        np.testing.assert_allclose(bank.velocities[t], ref[:, 1], atol=1e-9)
    # residual norm of window j at scan t: ‖z_t − prediction made at t − 1‖, from the third plot on
    expect = np.linalg.norm(z[2:, None, :] - np.asarray(bank.predictions)[1:-1], axis=-1)
    np.testing.assert_allclose(bank.residuals[2:], expect, atol=1e-9)
    assert not np.any(bank.residuals[:2]) and np.asarray(bank.valid).tolist() == [False, False] + [True] * 18


def _bank_with_residuals(L):
    """A bank whose inputs L (T, J − 1) become the selector's inputs exactly (σ̂ = 1 by construction)."""
    L = np.asarray(L, float)
    t = L.shape[0]
    res = L.copy()
    res[:, 0] = 1.0  # Δz⁽²⁾ = 1 → σ̂ = 1 (κ = 1) and L⁽²⁾ = 1
    zeros = jnp.zeros((t, J - 1, 2))
    return WindowBank(zeros, zeros, zeros, jnp.asarray(res), jnp.ones(t, bool))


def _sugeno_by_hand(L, a=5.0, c=1.5):
    """The paper's rule table evaluated directly: product t-norm, weighted mean of crisp outputs."""
    good = 1.0 / (1.0 + np.exp(a * (L - c)))
    bad = 1.0 - good
    num = den = 0.0
    for p in range(J, 1, -1):  # Q⁽²…ᵖ⁾ good, Q⁽ᵖ⁺¹…ᴶ⁾ bad ⇒ m = p
        w = np.prod(good[: p - 1]) * np.prod(bad[p - 1 :])
        num, den = num + w * p, den + w
    w = np.prod(bad)  # all bad ⇒ 2
    return (num + 2 * w) / (den + w)


def test_selector_follows_the_rule_table_and_matches_a_direct_evaluation():
    sel = window_selector(J, kappa=1.0)
    rng = np.random.default_rng(3)
    for L in rng.uniform(0, 3, (5, J - 1)):
        np.testing.assert_allclose(evaluate(selector_fis(sel), jnp.asarray(L)), _sugeno_by_hand(L), rtol=1e-12)
    # threshold patterns: inputs 2..p clearly good, p+1..J clearly bad ⇒ window p
    for p in range(2, J + 1):
        L = np.array([1.0] + [0.0] * (p - 2) + [3.0] * (J - p))
        assert abs(float(evaluate(selector_fis(sel), jnp.asarray(L))) - p) < 0.05
    assert abs(float(evaluate(selector_fis(sel), jnp.full(J - 1, 3.0))) - 2.0) < 1e-3  # all bad


def test_max_with_previous_holds_a_one_scan_outlier_and_rounding():
    L = np.zeros((6, J - 1))
    L[3, 4:] = 3.0  # one scan where windows 6..10 look bad ⇒ raw m ≈ 5
    sel = window_selector(J, kappa=1.0)
    s = select(sel, _bank_with_residuals(L))
    raw = np.asarray(s.m_raw)
    assert raw[3] < 5.2 and np.all(raw[[0, 1, 2, 4, 5]] > 9.0)
    np.testing.assert_array_equal(s.m, [10, 10, 10, 10, 10, 10])  # max with the previous raw output
    L[4, 4:] = 3.0  # two bad scans in a row: the window falls on the second
    s = select(sel, _bank_with_residuals(L))
    np.testing.assert_array_equal(s.m, [10, 10, 10, 10, 5, 10])
    np.testing.assert_array_equal(np.argmax(s.weights, -1) + 2, s.m)
    assert np.all(np.asarray(s.weights).sum(-1) == 1.0)


def test_smooth_selector_tends_to_the_exact_one():
    z = _plots(t=30, seed=5)
    z[18:] += np.cumsum(np.full((12, 2), [0.0, 25.0]), 0)  # a manoeuvre
    bank = window_bank_filter(z, J, DT)
    sel = window_selector(J)
    exact = select(sel, bank)
    for temp in (0.25, 0.05):
        smooth = select(sel, bank, smooth=True, temperature=temp)
        m_max = np.maximum(smooth.m_raw, np.concatenate([smooth.m_raw[:1], smooth.m_raw[:-1]]))
        assert np.all(smooth.m >= m_max - 1e-12) and np.all(smooth.m <= m_max + temp * np.log(2) + 1e-12)
        np.testing.assert_allclose(np.asarray(smooth.weights).sum(-1), 1.0, atol=1e-12)
    # at a small temperature the soft selection picks the exact window (away from rounding ties)
    far_from_tie = np.abs(np.asarray(m_max) - np.floor(m_max) - 0.5) > 0.2
    np.testing.assert_array_equal(np.argmax(smooth.weights, -1)[far_from_tie], np.asarray(exact.m - 2)[far_from_tie])
    assert exact.m[17] == 10 and min(exact.m[18:]) <= 4  # the manoeuvre shrinks the window


def test_noise_scale_is_the_running_mean_of_the_two_plot_residual():
    bank = window_bank_filter(_plots(), J, DT)
    s = noise_scale(bank.residuals, bank.valid, kappa=2.0)
    r2 = np.asarray(bank.residuals[:, 0])
    np.testing.assert_allclose(s[2:], np.cumsum(r2[2:]) / np.arange(1, 19) / 2.0, rtol=1e-12)


def test_selector_gradient_matches_finite_differences():
    z = _plots(t=30, seed=7)
    z[15:] += np.cumsum(np.full((15, 2), [0.0, 15.0]), 0)
    bank = window_bank_filter(z, J, DT)
    sel = window_selector(J)

    def loss(c):
        s = select_windows(dataclasses.replace(sel, centres=c), bank, smooth=True)
        est = select_estimates(bank, s.weights)
        return jnp.mean(jnp.sum((predicted_plots(est)[3:] - z[3:]) ** 2, -1))

    loss = jax.jit(loss)
    c0 = jnp.asarray(sel.centres)
    g = jax.jit(jax.grad(loss))(c0)
    h = 1e-5
    fd = [(loss(c0.at[i].add(h)) - loss(c0.at[i].add(-h))) / (2 * h) for i in (0, 4, 8)]
    np.testing.assert_allclose(np.asarray(g)[[0, 4, 8]], fd, rtol=1e-5, atol=1e-6)
    assert np.any(np.abs(np.asarray(g)) > 1e-3)


def test_bank_residual_gradient_is_finite_where_the_residual_is_zero():
    z = jnp.zeros((6, 2))  # a still target at the origin without noise: every residual is exactly 0
    bank = window_bank_filter(z, 4, DT)
    assert np.all(np.asarray(bank.residuals) == 0.0)
    g = jax.grad(lambda z: jnp.sum(window_bank_filter(z, 4, DT).residuals))(z)
    assert np.all(np.isfinite(np.asarray(g)))


@pytest.mark.parametrize("bad", [1, 0, -3, 2.5, True])
def test_empty_or_invalid_window_range_raises(bad):
    with pytest.raises(ValueError, match="max_window"):
        window_selector(bad)
    with pytest.raises(ValueError, match="max_window"):
        window_bank_filter(_plots(), bad, DT)


@pytest.mark.parametrize("dt", [0.0, -3.0])
def test_non_positive_scan_period_raises(dt):
    with pytest.raises(ValueError, match="dt"):
        window_bank_filter(_plots(), J, dt)


def test_other_bad_inputs_raise():
    with pytest.raises(ValueError, match="tnorm"):
        window_selector(J, tnorm="lukasiewicz")
    with pytest.raises(ValueError, match="slope"):
        window_selector(J, slope=0.0)
    with pytest.raises(ValueError, match="slope"):
        window_selector(J, slope=np.ones(J))
    with pytest.raises(ValueError, match="centre"):
        window_selector(J, centre=np.ones((J - 1, 1)))
    with pytest.raises(ValueError, match="z"):
        window_bank_filter(np.zeros((5, 3)), J, DT)
    with pytest.raises(ValueError, match="window"):
        fixed_window(window_bank_filter(_plots(), J, DT), 11)
