"""A loss that is not finite anywhere: every search and the gradient tuner raise the same error
(the swarm and the plain searches used to return ``loss = inf`` at an arbitrary point)."""

import jax.numpy as jnp
import pytest

from optim.pso import pso
from optim.search import grid_search, random_search
from optim.tune import tune

MESSAGE = r"^loss: not finite \(NaN/inf\) at any evaluated point"


def nan_everywhere(x):
    return jnp.nan * jnp.sum(x)


def test_pso_raises_when_the_loss_is_nan_everywhere():
    with pytest.raises(ValueError, match=MESSAGE + r" \(4 particles × 2 iterations"):
        pso(nan_everywhere, jnp.zeros(2), jnp.ones(2), n_particles=4, n_iters=2)


def test_plain_searches_raise_when_the_loss_is_nan_everywhere():
    with pytest.raises(ValueError, match=MESSAGE + r" \(random search: 8 points"):
        random_search(nan_everywhere, jnp.zeros(2), jnp.ones(2), n=8, batch_size=4)
    with pytest.raises(ValueError, match=MESSAGE + r" \(grid search: 4 points"):
        grid_search(nan_everywhere, jnp.zeros(2), jnp.ones(2), points_per_dim=2)


def test_tune_raises_the_same_error():
    with pytest.raises(ValueError, match=MESSAGE + r" \(the first point of each of the 1 start"):
        tune(nan_everywhere, jnp.ones(2), steps=2)


def test_one_finite_point_is_enough():
    res = pso(lambda x: jnp.where(x[0] < 0.5, jnp.nan, jnp.sum(x)), jnp.zeros(2), jnp.ones(2), n_particles=8, n_iters=2)
    assert 0.5 <= float(res.x[0]) and res.loss == pytest.approx(float(jnp.sum(res.x)))
