"""CMA-ES baseline: converges on known minima, stays in the box, matches evosax's own ask/tell loop,
compiles its generations once, and names bad input."""

import evosax.algorithms
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.problem import Param, ParamSpace, Problem
from optim.cmaes import _jitted_generations, cmaes
from optim.problems import rosenbrock, sphere

LO, HI = -5.0 * np.ones(4), 5.0 * np.ones(4)


def test_rosenbrock_converges_to_its_minimum_with_honest_accounting():
    res = cmaes(rosenbrock, LO, HI, popsize=16, iters=300, key=jax.random.PRNGKey(1))
    assert res.loss < 1e-12
    np.testing.assert_allclose(res.params, np.ones(4), atol=1e-6)
    assert res.n_sims == 16 * 300
    np.testing.assert_array_equal(res.history.sims, 16 * np.arange(1, 301))
    assert np.all(np.diff(res.history.best_loss) <= 0) and res.history.best_loss[-1] == res.loss
    assert np.all(res.history.loss >= res.history.best_loss)
    assert np.all(np.diff(res.history.wall_s) > 0)
    assert res.converged and "collapsed" in res.message


def test_every_evaluated_point_lies_in_the_box():
    """The unconstrained minimum (3, 3) lies outside [-1, 1]²: the answer is the corner (1, 1), loss 8.
    Any evaluation outside the box would return −1e9 and win."""

    def loss(x):
        inside = jnp.all((x >= -1.0) & (x <= 1.0))
        return jnp.where(inside, jnp.sum((x - 3.0) ** 2), -1e9)

    res = cmaes(loss, -np.ones(2), np.ones(2), popsize=8, iters=120)  # clipped onto the bound
    assert res.loss == pytest.approx(8.0, abs=1e-12)
    np.testing.assert_allclose(res.params, [1.0, 1.0], atol=1e-12)
    mirrored = cmaes(loss, -np.ones(2), np.ones(2), popsize=8, iters=120, bounds="reflect")
    assert 8.0 <= mirrored.loss < 8.5 and np.all(np.abs(np.asarray(mirrored.params)) <= 1.0)


def _reference_loop(key, z0, sigma0, popsize, iters, lo, hi):
    """evosax's CMA_ES driven by its own ask/tell, one generation per Python step, with the key split
    and the reflection into the unit box the module docstring states."""
    es = evosax.algorithms.CMA_ES(population_size=popsize, solution=jnp.zeros(z0.shape[0]))
    params = es.default_params.replace(std_init=jnp.asarray(sigma0))
    k_init, key = jax.random.split(key)
    state = es.init(k_init, jnp.asarray(z0), params)
    for _ in range(iters):
        key, k_ask, k_tell = jax.random.split(key, 3)
        z, state = es.ask(k_ask, state, params)
        y = np.mod(np.asarray(z), 2.0)
        z = jnp.asarray(np.where(y > 1.0, 2.0 - y, y))
        state, _ = es.tell(k_tell, z, jax.vmap(sphere)(lo + (hi - lo) * z), state, params)
    return state


def test_same_key_same_result_as_evosax_own_loop():
    lo, hi = np.array([-2.0, -1.0, 0.5]), np.array([2.0, 3.0, 4.0])
    key = jax.random.PRNGKey(7)
    res = cmaes(
        sphere, lo, hi, popsize=6, iters=12, key=key, sigma0=0.4, bounds="reflect", iters_per_call=5
    )  # chunks of 4
    ref = _reference_loop(key, np.full(3, 0.5), 0.4, 6, 12, lo, hi)
    assert res.loss == pytest.approx(float(ref.best_fitness), rel=1e-12)
    np.testing.assert_allclose(res.params, lo + (hi - lo) * np.asarray(ref.best_solution), rtol=1e-12)


def test_a_problem_is_searched_in_its_box_and_a_second_call_compiles_nothing():
    space = ParamSpace(kp=Param(lo=0.0, hi=4.0, init=1.0), ki=Param(lo=0.01, hi=10.0, init=1.0, log=True))
    pb = Problem.from_loss("bowl", space, lambda p, d, k: (p["kp"] - 2.0) ** 2 + jnp.log(p["ki"] / 0.3) ** 2)
    res = cmaes(pb, popsize=8, iters=60, key=jax.random.PRNGKey(3))
    assert float(res.params["kp"]) == pytest.approx(2.0, abs=1e-5)
    assert float(res.params["ki"]) == pytest.approx(0.3, rel=1e-5)
    size = _jitted_generations._cache_size()
    again = cmaes(pb, popsize=8, iters=60, key=jax.random.PRNGKey(3))
    assert _jitted_generations._cache_size() == size
    assert again.loss == res.loss


@pytest.mark.parametrize(
    "kwargs,match",
    [
        (dict(popsize=1), "popsize"),
        (dict(lo=[np.nan, -1.0]), "lo"),
        (dict(hi=[1.0, np.inf]), "hi"),
        (dict(sigma0=0.0), "sigma0"),
        (dict(x0=[0.0, 2.0]), "x0"),
        (dict(iters=0), "iters"),
        (dict(bounds="absorb"), "bounds"),
    ],
)
def test_bad_input_is_named(kwargs, match):
    args = dict(lo=[-1.0, -1.0], hi=[1.0, 1.0], popsize=4, iters=2) | kwargs
    with pytest.raises(ValueError, match=match):
        cmaes(sphere, **args)


def test_a_loss_never_finite_is_an_error():
    with pytest.raises(ValueError, match="loss: not finite"):
        cmaes(lambda x: jnp.nan * jnp.sum(x), [-1.0, -1.0], [1.0, 1.0], popsize=4, iters=2)
