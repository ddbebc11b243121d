"""Allan variance against closed forms: white noise σ²/m, sampled random walk K²τ/3 + K²T²/(6τ)."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.estimation.allan import allan_variance, cluster_sizes, random_walk_avar, white_noise_avar

RUNS = 2000


@pytest.mark.parametrize("overlapping", [False, True])
def test_white_noise_allan_variance(overlapping):
    sizes = (1, 4, 16, 64)

    @jax.jit
    def run(keys):
        return jax.vmap(
            lambda k: allan_variance(0.3 * jax.random.normal(k, (1024,)), 0.01, sizes, overlapping=overlapping).avar
        )(keys)

    avar = np.asarray(run(jax.random.split(jax.random.PRNGKey(0), RUNS)))
    expected = np.asarray(white_noise_avar(np.array(sizes) * 0.01, 0.09, 0.01))
    # relative standard error of one estimate ≈ 1/√(terms); averaged over RUNS runs
    terms = np.array([1024 // m - 1 for m in sizes], float)
    tol = 4.0 / np.sqrt(terms * RUNS)
    np.testing.assert_allclose(avar.mean(axis=0) / expected, 1.0, atol=float(tol.max()))


@pytest.mark.parametrize("overlapping", [False, True])
def test_random_walk_allan_variance_matches_seed004_closed_form(overlapping):
    """Seed 004 (Allan variance of a discrete Wiener sequence): x_M = Σ V_i T, σ_V = 2, T = 0.1, L = 50."""
    t_s, sigma_v, groups = 0.1, 2.0, 50
    for m in (1, 2, 5, 20):

        @jax.jit
        def run(keys, m=m):
            def one(k):
                x = jnp.cumsum(sigma_v * jax.random.normal(k, (groups * m,)) * t_s)
                return allan_variance(x, t_s, (m,), overlapping=overlapping).avar[0]

            return jax.vmap(one)(keys)

        avar = np.asarray(run(jax.random.split(jax.random.PRNGKey(m), RUNS)))
        expected = float(random_walk_avar(m * t_s, sigma_v**2 * t_s, t_s))
        se = avar.std() / np.sqrt(RUNS)
        assert abs(avar.mean() - expected) < 4 * se, (m, avar.mean(), expected, se)
        # the sampling bias K²T²/(6τ) is visible at m = 1: the continuous K²τ/3 alone is 1.5× too small
        if m == 1:
            assert avar.mean() > 1.4 * sigma_v**2 * t_s * t_s / 3


def test_overlapping_and_non_overlapping_agree_for_cluster_one_and_bad_input():
    y = np.random.default_rng(1).standard_normal(101)
    a = allan_variance(y, 1.0, (1,), overlapping=True).avar[0]
    b = allan_variance(y, 1.0, (1,), overlapping=False).avar[0]
    np.testing.assert_allclose(a, b, rtol=1e-12)
    np.testing.assert_allclose(a, 0.5 * np.mean(np.diff(y) ** 2), rtol=1e-12)
    assert cluster_sizes(1000)[0] == 1 and cluster_sizes(1000)[-1] <= 500
    with pytest.raises(ValueError, match="^m: cluster size 60"):
        allan_variance(y, 1.0, (60,))
    with pytest.raises(ValueError, match="^y: expected shape"):
        allan_variance(np.zeros((3, 3)), 1.0, (1,))
