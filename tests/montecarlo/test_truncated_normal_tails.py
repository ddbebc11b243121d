"""Truncated normal far in the tails: the sample mean against the closed form
``μ + σ (φ(α) − φ(β)) / (Φ(β) − Φ(α))`` (evaluated in log space with SciPy's ``log_ndtr``), no
sample outside the window.  The old sampler (``jax.random.truncated_normal``) returned the same
number for every sample once the window lay ≳ 8σ out."""

import jax
import numpy as np
import pytest
from scipy import special, stats

import jaxsim.montecarlo as mc

N = 20_000


def _log_phi(z):
    return -0.5 * z * z - 0.5 * np.log(2 * np.pi)


def _log_sf(z):
    return special.log_ndtr(-z)


def standard_moments(a: float, b: float) -> tuple[float, float]:
    """Mean and standard deviation of N(0, 1) truncated to [a, b], stable for windows far out."""
    if a + b < 0:  # mirror into the upper tail
        m, s = standard_moments(-b, -a)
        return -m, s
    # Z = S(a) − S(b) = S(a)(1 − e^{log S(b) − log S(a)}); φ(b) = φ(a) e^{log φ(b) − log φ(a)}
    log_z = _log_sf(a) + np.log(-np.expm1(_log_sf(b) - _log_sf(a)))

    def ratio(x):  # x φ(x) / Z with x φ(x) → 0 at ±inf
        return 0.0 if np.isinf(x) else x * np.exp(_log_phi(x) - log_z)

    phi_a, phi_b = (0.0 if np.isinf(v) else np.exp(_log_phi(v) - log_z) for v in (a, b))
    mean = phi_a - phi_b
    var = 1.0 + ratio(a) - ratio(b) - mean**2
    return mean, np.sqrt(var)


def _samples(dist):
    keys = jax.vmap(lambda i: jax.random.fold_in(jax.random.key(3), i))(np.arange(N))
    return np.asarray(jax.vmap(dist.sample)(keys))


def test_closed_form_agrees_with_scipy_where_scipy_is_reliable():
    for a, b in [(0.0, np.inf), (3.0, np.inf), (-np.inf, -3.0), (10.0, 10.5), (-1.0, 2.0)]:
        m, s = standard_moments(a, b)
        assert m == pytest.approx(stats.truncnorm(a, b).mean(), rel=1e-9)
        assert s == pytest.approx(stats.truncnorm(a, b).std(), rel=1e-6)
    assert standard_moments(10.0, np.inf)[0] == pytest.approx(10.0980, abs=1e-4)
    assert standard_moments(50.0, np.inf)[0] == pytest.approx(50.0200, abs=1e-4)


WINDOWS = [
    (0.0, np.inf),
    (3.0, np.inf),
    (10.0, np.inf),
    (50.0, np.inf),
    (-np.inf, 0.0),
    (-np.inf, -3.0),
    (-np.inf, -10.0),
    (-np.inf, -50.0),
    (10.0, 10.5),
    (-10.5, -10.0),
    (50.0, 50.01),
    (-40.0, 40.0),
    (-60.0, -2.0),
]


@pytest.mark.parametrize("a, b", WINDOWS)
def test_sample_mean_matches_the_closed_form_and_stays_in_the_window(a, b):
    mean, std = 2.0, 0.5
    low = mean + std * a
    high = mean + std * b
    x = _samples(mc.truncated_normal(mean, std, low, high))
    assert np.all(np.isfinite(x))
    assert np.all(x >= low) and np.all(x <= high)
    m, s = standard_moments(a, b)
    assert np.mean(x) == pytest.approx(mean + std * m, abs=5 * std * s / np.sqrt(N))
    assert np.std(x) == pytest.approx(std * s, rel=0.05)


def test_far_upper_tail_follows_the_exponential_limit():
    # Beyond α the excess α(Z − α) tends to Exp(1) as α → ∞ (Mills ratio): a distribution test far out.
    alpha = 50.0
    z = _samples(mc.truncated_normal(0.0, 1.0, low=alpha))
    assert stats.kstest(alpha * (z - alpha), stats.expon().cdf).pvalue > 1e-3


def test_inverse_log_survival_matches_scipy_far_into_the_tail():
    # log P(Z > x) from −1e−15 (x ≈ −8) to −1e5 (x ≈ 447; P underflows beyond x ≈ 37 in float64)
    log_p = -np.logspace(-15, 5, 401)
    x = np.asarray(mc.distributions.inverse_log_survival(log_p))
    np.testing.assert_allclose(x, -special.ndtri_exp(log_p), rtol=1e-10, atol=1e-10)


@pytest.mark.parametrize(
    "low, high", [(0.0, np.inf), (-np.inf, np.inf), (-1.0, 2.0), (10.0, np.inf), (-np.inf, -10.0), (10.0, 10.5)]
)
def test_draw_derivatives_in_mean_and_std_match_finite_differences(low, high):
    # Implicit (fixed-u) derivatives; an infinite bound contributes 0, not ∞·0 = NaN.
    key = jax.random.key(1)

    def draw(m, s):
        return mc.TruncatedNormal(m, s, low, high).sample(key)

    grad = np.asarray(jax.grad(draw, argnums=(0, 1))(0.3, 1.0))
    h = 1e-6
    fd = [(draw(0.3 + h, 1.0) - draw(0.3 - h, 1.0)) / (2 * h), (draw(0.3, 1.0 + h) - draw(0.3, 1.0 - h)) / (2 * h)]
    np.testing.assert_allclose(grad, np.asarray(fd), rtol=1e-6, atol=1e-9)
