"""Distributions against SciPy's (Kolmogorov–Smirnov), their parameter checks, and key independence."""

import jax
import numpy as np
import pytest
from scipy import stats

import jaxsim.montecarlo as mc

N = 20_000


def _samples(dist, n=N, seed=0):
    keys = jax.vmap(lambda i: jax.random.fold_in(jax.random.key(seed), i))(np.arange(n))
    return np.asarray(jax.vmap(dist.sample)(keys))


@pytest.mark.parametrize(
    "dist, oracle",
    [
        (mc.normal(1.5, 0.3), stats.norm(1.5, 0.3)),
        (mc.uniform(-2.0, 5.0), stats.uniform(-2.0, 7.0)),
        (mc.lognormal(0.2, 0.5), stats.lognorm(s=0.5, scale=np.exp(0.2))),
        (mc.truncated_normal(1.0, 2.0, 0.0, 2.5), stats.truncnorm(-0.5, 0.75, loc=1.0, scale=2.0)),
        (mc.truncated_normal(0.0, 1.0, low=1.0), stats.truncnorm(1.0, np.inf)),
        (mc.deviation(3.0, 0.5), stats.uniform(2.5, 1.0)),
        (mc.deviation(-4.0, 0.2, relative=True), stats.uniform(-4.8, 1.6)),
    ],
)
def test_samples_follow_the_scipy_distribution(dist, oracle):
    x = _samples(dist)
    assert stats.kstest(x, oracle.cdf).pvalue > 1e-3
    lo, hi = oracle.support()
    assert np.all(x >= lo) and np.all(x <= hi)
    assert np.mean(x) == pytest.approx(oracle.mean(), abs=4 * oracle.std() / np.sqrt(N))


def test_array_parameters_broadcast_and_use_each_element():
    d = mc.deviation(np.array([1.0, 10.0, 100.0]), 0.1, relative=True)
    x = _samples(d, 5000)
    assert x.shape == (5000, 3)
    np.testing.assert_allclose(x.min(axis=0), [0.9, 9.0, 90.0], rtol=1e-3)
    np.testing.assert_allclose(x.max(axis=0), [1.1, 11.0, 110.0], rtol=1e-3)


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda: mc.normal(0.0, -1.0), "Normal.std"),
        (lambda: mc.normal(np.nan, 1.0), "Normal.mean"),
        (lambda: mc.uniform(1.0, 1.0), "Uniform.high"),
        (lambda: mc.lognormal(0.0, 0.0), "LogNormal.sigma"),
        (lambda: mc.truncated_normal(0.0, 1.0, 2.0, 1.0), "TruncatedNormal.high"),
        (lambda: mc.truncated_normal(0.0, 0.0), "TruncatedNormal.std"),
        (lambda: mc.deviation(1.0, -0.1), "Deviation.delta"),
        (lambda: mc.deviation(1.0, 1.5, relative=True), "Deviation.delta"),
        (lambda: mc.deviation(1.0, 0.1, relative="yes"), "Deviation.relative"),
    ],
)
def test_invalid_parameters_name_the_argument(make, match):
    with pytest.raises(ValueError, match=match):
        make()


def test_unvalidated_distribution_is_caught_at_the_monte_carlo_boundary():
    with pytest.raises(ValueError, match="Uniform.high"):
        mc.monte_carlo(lambda k, p: p["u"], {"u": mc.Uniform(2.0, 1.0)}, 10, 0)
    with pytest.raises(ValueError, match=r"space\['z'\]"):
        mc.monte_carlo(lambda k, p: p["z"], {"z": np.inf}, 10, 0)


def test_each_parameter_draws_from_its_own_key():
    key = jax.random.key(3)
    both = mc.draw({"a": mc.normal(), "b": mc.uniform()}, key)
    alone = mc.draw({"a": mc.normal()}, key)
    assert float(both["a"]) == float(alone["a"])
    fixed = mc.draw({"a": mc.normal(), "k": 2.5}, key)
    assert float(fixed["k"]) == 2.5 and float(fixed["a"]) == float(alone["a"])
