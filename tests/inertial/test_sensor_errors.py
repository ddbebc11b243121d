"""Gyro error generators against the Allan variance each term must produce (IEEE 952 closed forms),
the PSD normalisation of the flicker synthesis, and allantools as an oracle of the Allan estimator."""

from __future__ import annotations

import math

import allantools
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.estimation.allan import allan_variance, random_walk_avar
from jaxsim.inertial.allan_fit import design_matrix
from jaxsim.inertial.sensor_errors import GyroNoise, flicker_noise, gyro_noise, noise_terms, wiener_sequence

DT, N, RUNS = 0.01, 4096, 64
SIZES = (1, 4, 16, 64, 256)
COEFFS = GyroNoise(R=2e-3, K=0.05, B=0.2, N=0.1, Q=0.01)


@pytest.fixture(scope="module")
def term_avars():
    """``(RUNS, 5 terms, len(SIZES))`` overlapping Allan variances of each term separately."""

    @jax.jit
    def run(keys):
        def one(k):
            rows = noise_terms(k, COEFFS, DT, N)
            return jax.vmap(lambda y: allan_variance(y, DT, SIZES).avar)(rows)

        return jax.vmap(one)(keys)

    return np.asarray(run(jax.random.split(jax.random.PRNGKey(0), RUNS)))


def test_each_term_has_its_closed_form_allan_variance(term_avars):
    tau = np.array(SIZES) * DT
    expected = np.asarray(design_matrix(tau, DT, sampling_correction=True)) * np.asarray(COEFFS.as_array()) ** 2
    mean = term_avars.mean(axis=0).T  # (sizes, terms)
    se = term_avars.std(axis=0, ddof=1).T / math.sqrt(RUNS)
    # the ramp is deterministic: exact
    np.testing.assert_allclose(mean[:, 0], expected[:, 0], rtol=1e-9)
    # random walk (with seed 004's sampling term), white and quantisation: unbiased estimators
    for i in (1, 3, 4):
        z = (mean[:, i] - expected[:, i]) / se[:, i]
        assert np.all(np.abs(z) < 4.0), (i, z)
    # flicker: flat at 2 ln2/π B² inside the band (dt ≪ τ ≪ n·dt = 41 s; at τ = dt it is 19 % higher)
    np.testing.assert_allclose(mean[1:4, 2] / expected[1:4, 2], 1.0, atol=0.1)
    # the K sampling term is needed at m = 1: without it the mean is 1.5× too large
    cont = COEFFS.K**2 * tau[0] / 3
    assert mean[0, 1] > 1.3 * cont


def test_flicker_variance_is_the_integral_of_its_psd_and_wiener_increments():
    n, b = 1024, 0.3
    x = jax.jit(jax.vmap(lambda k: flicker_noise(k, b, DT, n)))(jax.random.split(jax.random.PRNGKey(1), 400))
    f = np.arange(1, n // 2 + 1) / (n * DT)
    expected = np.sum(b**2 / (np.pi * f)) / (n * DT)
    var = np.asarray(jnp.var(x, axis=1) * n / (n - 1)).mean()
    # the sample variance about the sample mean loses the DC-free part only (none); 400 runs: ≈ 3 % SE
    assert var == pytest.approx(expected, rel=0.1)
    w = wiener_sequence(jax.random.PRNGKey(2), 2.0, 0.1, 20000, x0=5.0)
    inc = np.diff(np.concatenate([[5.0], np.asarray(w)]))
    assert np.std(inc) == pytest.approx(2.0 * 0.1, rel=0.02)


def test_vmap_equals_loop_and_sum_of_terms():
    keys = jax.random.split(jax.random.PRNGKey(3), 3)
    single = jax.jit(lambda k: (gyro_noise(k, COEFFS, DT, 256), noise_terms(k, COEFFS, DT, 256).sum(0)))
    batched = jax.jit(jax.vmap(lambda k: gyro_noise(k, COEFFS, DT, 256)))(keys)
    for i, k in enumerate(keys):
        one, summed = single(k)
        np.testing.assert_allclose(batched[i], one, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(batched[i], summed, rtol=1e-10, atol=1e-12)


def test_allantools_overlapping_and_non_overlapping_equal_ours():
    """allantools (oadev/adev on frequency data) is the oracle of jaxsim.estimation.allan on the same
    samples: a simulated gyro with all five terms."""
    y = np.asarray(gyro_noise(jax.random.PRNGKey(4), GyroNoise(), DT, 3000))
    sizes = (1, 2, 5, 20, 100, 500)
    rate = 1.0 / DT
    for overlapping, oracle in ((True, allantools.oadev), (False, allantools.adev)):
        ours = allan_variance(y, DT, sizes, overlapping=overlapping)
        taus, adev, _, n = oracle(y, rate=rate, data_type="freq", taus=np.array(sizes) * DT)
        np.testing.assert_allclose(taus, np.array(sizes) * DT, rtol=1e-12)
        np.testing.assert_allclose(np.asarray(ours.adev), adev, rtol=1e-9)
        np.testing.assert_array_equal(np.asarray(ours.n_terms), n)


def test_random_walk_closed_form_from_the_triangular_weights():
    """E σ²(τ) = σ_V²T²·Σw²/(2M²), w = 1, 2, …, M, …, 1 (box ∗ box), equals K²τ/3 + K²T²/(6τ)."""
    t, k2 = 0.1, 0.4
    for m in (1, 2, 5, 20):
        w = np.convolve(np.ones(m), np.ones(m))
        direct = (k2 / t) * t**2 * np.sum(w**2) / (2 * m**2)
        assert float(random_walk_avar(m * t, k2, t)) == pytest.approx(direct, rel=1e-12)


def test_bad_inputs_name_the_argument():
    key = jax.random.PRNGKey(0)
    with pytest.raises(ValueError, match="^n:"):
        gyro_noise(key, COEFFS, DT, 0)
    with pytest.raises(ValueError, match="^dt:"):
        noise_terms(key, COEFFS, -1.0, 10)
    with pytest.raises(ValueError, match="^b:"):
        flicker_noise(key, -0.1, DT, 16)
    with pytest.raises(ValueError, match="^sigma_v:"):
        wiener_sequence(key, -1.0, DT, 16)
