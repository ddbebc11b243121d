"""α–β filters: growing memory = least-squares line fit; sliding-window LS = restarted growing memory."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.estimation.alpha_beta import (
    alpha_beta_filter,
    benedict_bordner_beta,
    growing_memory_filter,
    growing_memory_gains,
    poly_window_weights,
    sliding_window_fit,
    window_bank,
)

DT = 3.0  # radar scan period of the vessel tracker (seed 003)


def _track(t=30, seed=0):
    rng = np.random.default_rng(seed)
    times = np.arange(t) * DT
    truth = np.stack([100 + 8.0 * times + 0.02 * times**2, -50 + 3.0 * times], axis=1)
    return truth + rng.normal(0, 7.0, truth.shape)


def _line_fit(z, dt):
    """NumPy least-squares line through z (k, d) at times (−(k−1)dt … 0): (position, velocity) at 0."""
    k = z.shape[0]
    t = (np.arange(k) - (k - 1)) * dt
    coef = np.polyfit(t, z, 1)  # rows: slope, intercept
    return coef[1], coef[0]


def test_growing_memory_gains_formula_and_seed003_table():
    a, b = growing_memory_gains(np.arange(2, 11))
    np.testing.assert_allclose(a, 2 * (2 * np.arange(2, 11) - 1) / (np.arange(2, 11) * np.arange(3, 12)))
    # the spec's derived table (seed 003): α_3 = 0.8333, α_10 = 0.3455, β_4 = 0.3, β_10 = 0.0545
    assert np.round(np.asarray(a)[[1, 8]], 4).tolist() == [0.8333, 0.3455]
    assert np.round(np.asarray(b)[[2, 8]], 4).tolist() == [0.3, 0.0545]
    assert float(a[0]) == 1.0 and float(b[0]) == 1.0  # two-point fit
    np.testing.assert_allclose(benedict_bordner_beta(0.5), 0.25 / 1.5)


def test_growing_memory_filter_is_the_least_squares_line_fit():
    z = _track()
    res = growing_memory_filter(z, DT)
    for k in range(2, 31):
        pos, vel = _line_fit(z[:k], DT)
        np.testing.assert_allclose(res.positions[k - 1], pos, rtol=1e-10, atol=1e-8)
        np.testing.assert_allclose(res.velocities[k - 1], vel, rtol=1e-10, atol=1e-10)


def test_sliding_window_line_fit_equals_growing_memory_over_last_k_samples():
    z = _track(t=25, seed=1)
    k = 6
    fits = sliding_window_fit(z, window=k, degree=1, dt=DT)
    for end in range(k - 1, 25):
        restarted = growing_memory_filter(z[end - k + 1 : end + 1], DT)
        np.testing.assert_allclose(fits[end - k + 1, 0], restarted.positions[-1], rtol=1e-10, atol=1e-8)
        np.testing.assert_allclose(fits[end - k + 1, 1], restarted.velocities[-1], rtol=1e-10, atol=1e-10)
    bank = window_bank(z[-10:], DT)  # the vessel tracker's tuple j = 2..10
    for j in range(2, 11):
        pos, vel = _line_fit(z[-j:], DT)
        np.testing.assert_allclose(bank[j - 2, 0], pos, rtol=1e-10, atol=1e-8)
        np.testing.assert_allclose(bank[j - 2, 1], vel, rtol=1e-10, atol=1e-10)


def test_poly_window_weights_reproduce_polynomials_and_seed002_noise_gains():
    w = poly_window_weights(51, 4, 0.1)
    t = (np.arange(51) - 50) * 0.1
    p = 1.0 - 2.0 * t + 0.5 * t**2 + 0.3 * t**3 - 0.1 * t**4
    np.testing.assert_allclose(w @ p, [1.0, -2.0, 1.0, 1.8, -2.4], rtol=1e-9, atol=1e-9)
    gains = np.sqrt(np.sum(np.asarray(w) ** 2, axis=1))
    # seed 002 (M = 50, N = 4, Δt = 0.1 s): position 0.625, velocity 1.769 s⁻¹, acceleration 2.920 s⁻²
    assert np.round(gains[:3], 3).tolist() == [0.625, 1.769, 2.920]


def test_fixed_gain_alpha_beta_on_noise_free_line_has_no_lag():
    t = np.arange(80) * DT
    z = np.stack([5.0 + 2.0 * t], axis=1)
    res = alpha_beta_filter(z, DT, alpha=0.5, beta=benedict_bordner_beta(0.5))
    # the error of a constant-velocity target decays as |λ|^k, λ the roots of
    # λ² − (2 − α − β)λ + (1 − α) (|λ| = √0.5 here): no steady-state lag
    err = np.abs(np.asarray(res.positions[:, 0]) - z[:, 0])
    assert err[-1] < 1e-9 and err[40] < 2.0 * err[20] * 0.5**10
    capped = growing_memory_filter(z, DT, max_memory=5)
    np.testing.assert_allclose(capped.velocities[1:, 0], 2.0, rtol=1e-12)


def test_alpha_beta_bad_input():
    with pytest.raises(ValueError, match="^window:"):
        poly_window_weights(2, 3, 0.1)
    with pytest.raises(ValueError, match="^dt:"):
        growing_memory_filter(np.zeros((4, 2)), 0.0)
    with pytest.raises(ValueError, match="^max_memory:"):
        growing_memory_filter(np.zeros((4, 2)), 1.0, max_memory=1)
    with pytest.raises(ValueError, match="^z:"):
        growing_memory_filter(jnp.zeros((2, 2, 2)), 1.0)
