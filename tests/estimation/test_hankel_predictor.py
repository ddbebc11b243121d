"""Hankel-matrix predictor: exact on noise-free LTI data, honest under noise, checked inputs."""

import jax.numpy as jnp
import numpy as np
import pytest

from experiments.ship_prediction import random_lti
from jaxsim.estimation import hankel_predictor as hp


def test_exact_on_random_noise_free_systems_of_order_up_to_four():
    rng = np.random.default_rng(2024)
    orders = set()
    for _ in range(30):
        ys, n, p = random_lti(rng, 0.05, 60)  # closed form y_k = C A^k x0, max |y| = 1
        orders.add(n)
        pred = np.asarray(hp.predict_series(jnp.asarray(ys), window=15, nu=4))
        assert np.all(np.isnan(pred[:20])) and np.all(np.isfinite(pred[20:]))
        assert np.max(np.abs(pred[20:] - ys[20:])) <= 1e-8, (n, p)
        assert 1 <= hp.numerical_rank(ys) <= n  # directions with σ < 1e-10·σ_max count as null
    assert orders == {1, 2, 3, 4}


def test_exact_for_linear_plant_driven_by_ramp_and_sine():
    """Augmented order 4 + 2 + 1 = 7 (paper: rank ≤ 7): a 2nd-order plant driven by a ramp and a sinusoid."""
    dt, N = 0.05, 80
    t = np.arange(N) * dt
    # y'' + 0.6 y' + 4 y = 2 + 0.5 t + sin(1.3 t): exact solution = particular + homogeneous part
    w, z = 2.0, 0.15
    wd = w * np.sqrt(1 - z**2)
    a = 1.3
    denom = (4 - a**2) ** 2 + (0.6 * a) ** 2
    part = (2 - 0.5 * 0.6 / 4) / 4 + 0.5 * t / 4 + ((4 - a**2) * np.sin(a * t) - 0.6 * a * np.cos(a * t)) / denom
    y = part + np.exp(-z * w * t) * (0.7 * np.cos(wd * t) - 0.2 * np.sin(wd * t))
    pred = np.asarray(hp.predict_series(jnp.asarray(y[:, None])))
    assert np.max(np.abs(pred[20:, 0] - y[20:])) <= 1e-8
    assert (
        hp.numerical_rank(y[:, None]) <= 6
    )  # 1 and t (2) + sine (2) + plant (2); small σ may fall under the tolerance


def test_noise_raises_the_error_to_the_noise_level():
    rng = np.random.default_rng(5)
    ys, n, _ = random_lti(rng, 0.05, 200)
    noisy = ys + 1e-4 * rng.normal(size=ys.shape)
    pred = np.asarray(hp.predict_series(jnp.asarray(noisy), rank=n))
    err = np.abs(pred[20:] - ys[20:])
    assert 1e-5 < np.median(err) < 2e-3  # noise-level, not exact, not divergent


def test_bad_inputs():
    ys = jnp.ones((50, 1))
    with pytest.raises(ValueError, match="window"):
        hp.predict_series(ys, window=3, nu=4)
    with pytest.raises(ValueError, match="nu"):
        hp.predict_series(ys, window=15, nu=0)
    with pytest.raises(ValueError, match="ys"):
        hp.predict_series(jnp.ones((20, 1)))
    with pytest.raises(ValueError, match="rank"):
        hp.predict_series(ys, rank=16)
