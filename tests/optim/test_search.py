"""Random and grid search: brute-force oracles, padding of the last batch, bad input."""

import itertools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from optim.search import grid_search, random_search


def shifted(x):
    return jnp.sum((x - jnp.array([0.3, -0.7, 1.1])) ** 2) + 0.1 * jnp.sin(5 * x[0])


@pytest.mark.parametrize("points_per_dim,batch_size", [(7, 50), ((4, 9, 5), 1000), ((1, 3, 6), 7)])
def test_grid_search_equals_brute_force(points_per_dim, batch_size):
    lo, hi = np.array([-1.0, -2.0, 0.0]), np.array([1.0, 1.0, 2.0])
    res = grid_search(shifted, lo, hi, points_per_dim=points_per_dim, batch_size=batch_size)
    counts = np.broadcast_to(points_per_dim, (3,))
    axes = [np.linspace(a, b, c) if c > 1 else np.array([(a + b) / 2]) for a, b, c in zip(lo, hi, counts)]
    pts = np.array(list(itertools.product(*axes)))
    vals = np.asarray(jax.vmap(shifted)(jnp.asarray(pts)))
    assert res.n_sims == len(pts)
    assert res.loss == pytest.approx(vals.min(), rel=1e-14)
    np.testing.assert_allclose(res.x, pts[np.argmin(vals)], rtol=1e-14, atol=1e-14)
    assert res.history.sims[-1] == len(pts) and np.all(np.diff(res.history.best_loss) <= 0)


def test_random_search_is_uniform_in_the_box_and_keeps_the_best():
    # best of 1000 uniform points in [−1, 1]³ on the sphere: P(min |x|² ≥ 0.09) ≈ 7e-7
    res = random_search(
        lambda x: jnp.sum(x**2),
        -np.ones(3),
        np.ones(3),
        n=1000,
        batch_size=128,
        key=jax.random.PRNGKey(4),
        sims_per_eval=2,
    )
    assert res.loss < 0.09 and res.loss == pytest.approx(float(jnp.sum(res.x**2)))
    assert res.n_sims == 2000 and res.history.sims[-1] == 2000 and len(res.history.sims) == 8
    # points fill the box: the max of |x_i| over the best of a far-off target is near the corner
    far = random_search(lambda x: -jnp.sum(x), -np.ones(3), np.ones(3), n=1000, key=jax.random.PRNGKey(4))
    assert np.all(np.asarray(far.x) > 0.6) and np.all(np.asarray(far.x) <= 1.0)


def test_non_finite_losses_never_win():
    res = grid_search(lambda x: jnp.where(x[0] < 0, jnp.nan, x[0]), [-1.0], [1.0], points_per_dim=11)
    assert res.loss == 0.0 and float(res.x[0]) == 0.0


def test_bad_input_names_the_argument():
    f = lambda x: jnp.sum(x)  # noqa: E731
    with pytest.raises(ValueError, match="lo/hi"):
        random_search(f, [1.0, 0.0], [0.0, 1.0], n=10)
    with pytest.raises(ValueError, match="n"):
        random_search(f, [0.0], [1.0], n=0)
    with pytest.raises(ValueError, match="points_per_dim"):
        grid_search(f, [0.0, 0.0], [1.0, 1.0], points_per_dim=(3, 3, 3))
    with pytest.raises(ValueError, match=r"points_per_dim\[1\]"):
        grid_search(f, [0.0, 0.0], [1.0, 1.0], points_per_dim=(3, 0))
