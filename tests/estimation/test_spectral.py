"""Welch CSD and the H1 estimator against scipy.signal.csd and a known digital filter."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.signal

from jaxsim.estimation.spectral import csd, frf_h1


@pytest.mark.parametrize("nperseg, noverlap", [(256, None), (255, 100)])
def test_csd_matches_scipy(nperseg, noverlap):
    rng = np.random.default_rng(0)
    x = rng.standard_normal(4000) + 0.3
    y = np.convolve(x, [0.5, -0.2, 0.1], mode="same") + 0.1 * rng.standard_normal(4000)
    f, p = csd(jnp.asarray(x), jnp.asarray(y), 1000.0, nperseg, noverlap)
    f_ref, p_ref = scipy.signal.csd(x, y, fs=1000.0, nperseg=nperseg, noverlap=noverlap)
    np.testing.assert_allclose(np.asarray(f), f_ref, rtol=1e-12)
    np.testing.assert_allclose(np.asarray(p), p_ref, rtol=1e-9, atol=1e-12 * np.abs(p_ref).max())


def test_h1_recovers_a_fir_filter_and_batches():
    b = np.array([0.3, 0.5, -0.2])
    keys = jax.random.split(jax.random.PRNGKey(1), 3)

    def one(key):
        u = jax.random.normal(key, (8192,))
        y = jnp.convolve(u, jnp.asarray(b))[: u.shape[0]]
        return frf_h1(u, y, 1.0, 512)

    batched = jax.jit(jax.vmap(one))(keys)
    single = jax.jit(one)(keys[1])
    np.testing.assert_allclose(np.asarray(batched.h[1]), np.asarray(single.h), rtol=1e-10)
    _, h_true = scipy.signal.freqz(b, worN=np.asarray(single.f) * 2 * np.pi)
    # leakage of the Hann window over a 3-tap filter is small; noise-free, so coherence ≈ 1
    np.testing.assert_allclose(np.asarray(single.h), h_true, rtol=2e-2, atol=2e-3)
    assert float(jnp.min(single.coherence)) > 0.99 and float(jnp.max(single.coherence)) <= 1 + 1e-12


def test_bad_input_raises():
    with pytest.raises(ValueError, match="y:"):
        csd(jnp.ones(100), jnp.ones(99), 1.0, 32)
    with pytest.raises(ValueError, match="noverlap"):
        csd(jnp.ones(100), jnp.ones(100), 1.0, 32, 32)
    with pytest.raises(ValueError, match="nperseg"):
        csd(jnp.ones(100), jnp.ones(100), 1.0, 128)
