"""Wind from air data + INS: the algebraic estimator against the wind that made the readings, its
propagated covariance against a Monte Carlo, the filter model's consistency on its own samples."""

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.estimation import wind as we
from jaxsim.estimation.gating import chi2_bounds, nees
from jaxsim.estimation.lgssm import kalman_filter, sample

STD = np.array([0.1, 0.1, np.radians(0.1), 0.5, np.radians(0.5)])


def readings(v_air, gamma, alpha, w):
    """Ideal readings: ground velocity = air velocity along the air path + wind."""
    vg = np.array([v_air * np.cos(gamma) + w[0], v_air * np.sin(gamma) + w[1]])
    return we.AirData(np.hypot(*vg), vg[1], gamma + alpha, v_air, alpha)


def test_algebraic_estimate_returns_the_wind_exactly():
    rng = np.random.default_rng(0)
    for _ in range(20):
        w = rng.uniform(-8, 8, 2)
        d = readings(rng.uniform(15, 40), rng.uniform(-0.3, 0.3), rng.uniform(-0.1, 0.2), w)
        np.testing.assert_allclose(we.wind_from_air_data(d), w, atol=1e-12)
    # eq. (3): the paper's four directions in the flight plane
    expected = [-10 * np.cos(np.radians(30)), -5.0]
    np.testing.assert_allclose(we.wind_components(10.0, np.pi, np.radians(-30)), expected, atol=1e-12)


def test_measurement_cov_matches_a_monte_carlo_of_the_estimate():
    d = readings(25.0, 0.05, 0.07, np.array([6.0, -1.0]))
    r = np.asarray(we.measurement_cov(d, jnp.asarray(STD)))
    noise = np.random.default_rng(1).normal(size=(200_000, 5)) * STD
    noisy = we.AirData(*(np.asarray(x) + noise[:, i] for i, x in enumerate(d)))
    emp = np.cov(np.asarray(we.wind_from_air_data(noisy)).T)
    np.testing.assert_allclose(r, emp, rtol=0.02, atol=2e-4)


def test_filter_model_is_consistent_on_its_own_samples():
    """NEES of the filter run on data sampled from the same model, averaged over independent runs at the
    first, middle and last step, lies inside the χ²(4) band; the turbulence block's stationary variance
    is σ_t²."""
    t, runs = 100, 400
    r = jnp.broadcast_to(jnp.array([[0.2, 0.05], [0.05, 0.3]]), (t, 2, 2))
    model = we.wind_filter_model(0.1, 5.0, 1.5, 0.01, r)
    phi = np.exp(-0.1 / 5.0)
    np.testing.assert_allclose(model.Q[2:, 2:] / (1 - phi**2), 1.5**2 * np.eye(2), rtol=1e-12)

    def one(key):
        x, y = sample(model, key, t)
        res = kalman_filter(model, y)
        return jax.vmap(nees)(x, res.means, res.covs)[jnp.array([0, t // 2, t - 1])]

    per_run = jax.jit(jax.vmap(one))(jax.random.split(jax.random.PRNGKey(0), runs))
    lo, hi = chi2_bounds(4, runs, prob=0.99)  # runs are independent: one band per step
    for avg in np.asarray(jnp.mean(per_run, axis=0)):
        assert lo <= avg <= hi, (avg, lo, hi)
