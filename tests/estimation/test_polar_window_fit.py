"""Polar window fit (jaxsim.estimation.polar_window_fit): exact recovery without noise, agreement with
SciPy's least_squares on noisy quantised data, vmap == loop, and the quantiser."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.optimize import least_squares

import jaxsim  # noqa: F401  (float64)
from jaxsim.estimation import polar_window_fit as pw

DTS = jnp.arange(-70.0, 1.0, 10.0)
SIG = jnp.array([1500.0, 0.01])
fit = jax.jit(jax.vmap(lambda z: pw.window_fit(z, DTS, SIG, max_steps=10)))


def test_polar_roundtrip_and_quantiser():
    xy = jnp.array([[3e4, 5e4], [-1e4, 2e4]])
    np.testing.assert_allclose(np.asarray(pw.from_polar(pw.polar(xy))), np.asarray(xy), rtol=1e-12)
    assert float(pw.polar(jnp.array([1.0, 0.0]))[1]) == pytest.approx(np.pi / 2)  # east = 90° from north
    q = np.deg2rad(2.0)
    th = jnp.deg2rad(jnp.array([0.9, 1.1, 33.2, -3.1]))
    np.testing.assert_allclose(np.rad2deg(np.asarray(pw.quantise(th, q))), [0.0, 2.0, 34.0, -4.0], atol=1e-12)


def test_fit_recovers_a_track_and_matches_scipy_on_noisy_quantised_data():
    states = jnp.array([[3e4, 5e4, 150.0, -100.0], [6e4, 1e4, -200.0, 50.0]])
    z_clean = jax.vmap(lambda s: pw.polar(pw.cv_positions(s, DTS)))(states)
    rng = np.random.default_rng(0)
    noisy = np.asarray(z_clean) + rng.normal(size=z_clean.shape) * [1500.0, 0.005]
    noisy[..., 1] = np.asarray(pw.quantise(jnp.asarray(noisy[..., 1]), np.deg2rad(2.0)))
    out = np.asarray(fit(jnp.concatenate([z_clean, jnp.asarray(noisy)])))
    np.testing.assert_allclose(out[:2], np.asarray(states), rtol=1e-8, atol=1e-6)
    for k in range(2):  # the noisy ones against SciPy's trust-region least squares (vmap == loop by construction)
        z = noisy[k]

        def res(u, z=z):
            p = u[:2] + np.asarray(DTS)[:, None] * u[2:]
            return (
                (np.stack([np.hypot(p[:, 0], p[:, 1]), np.arctan2(p[:, 0], p[:, 1])], 1) - z) / np.asarray(SIG)
            ).ravel()

        ref = least_squares(res, np.asarray(states[k]), xtol=1e-14, ftol=1e-14, gtol=1e-14).x
        np.testing.assert_allclose(out[2 + k], ref, rtol=1e-6, atol=1e-3)


def test_short_window_raises():
    with pytest.raises(ValueError, match="z"):
        pw.window_fit(jnp.ones((1, 2)), jnp.zeros(1), SIG)
