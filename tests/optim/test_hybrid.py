"""Hybrid tuner: the global phase finds the basin gradient descent alone misses; one history; harness entry."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.problem import Param, ParamSpace, Problem
from jaxsim.problem.reparam import Interval
from optim.compare import compare
from optim.hybrid import default_polisher, hybrid, join_histories
from optim.problems import rastrigin
from optim.results import History
from optim.tune import tune

LO, HI = -5.12 * np.ones(2), 5.12 * np.ones(2)


@pytest.mark.parametrize("method", ["cmaes", "pso"])
def test_rastrigin_global_minimum_where_gradient_alone_stalls(method):
    """Seeded: with 32 candidates × 30 iterations about 8 keys in 10 find the global basin (the
    others the ring of minima at distance 1); key 0 is one of them for both methods."""
    popsize, iters = 32, 30
    alone = tune(rastrigin, jnp.array([3.2, -2.9]), optimizer=default_polisher(), steps=100, reparam=Interval(LO, HI))
    assert alone.loss > 17.0  # the local minimum near (3, −3): Rastrigin ≈ 17.9
    res = hybrid(rastrigin, LO, HI, method=method, popsize=popsize, iters=iters, steps=60, key=jax.random.PRNGKey(0))
    assert res.loss < 1e-10
    np.testing.assert_allclose(res.params, [0.0, 0.0], atol=1e-5)
    assert res.mode.startswith(f"{method}+")
    h = res.history
    first = popsize * iters
    np.testing.assert_array_equal(h.sims[:iters], popsize * np.arange(1, iters + 1))
    assert h.sims[-1] == res.n_sims and res.n_sims > first
    assert len(h.best_loss) == res.n_steps and h.best_loss[-1] == res.loss
    assert np.all(np.diff(h.best_loss) <= 0) and np.all(np.diff(h.wall_s) >= 0)


def test_join_histories_continues_counts_and_never_raises_the_best():
    a = History(np.array([5.0, 3.0]), np.array([10, 20]), np.array([0.1, 0.2]), loss=np.array([5.0, 3.0]))
    b = History(np.array([4.0, 1.0]), np.array([1, 2]), np.array([0.05, 0.1]), loss=np.array([4.0, 1.0]))
    h = join_histories(a, b)
    np.testing.assert_array_equal(h.best_loss, [5.0, 3.0, 3.0, 1.0])
    np.testing.assert_array_equal(h.sims, [10, 20, 21, 22])
    np.testing.assert_allclose(h.wall_s, [0.1, 0.2, 0.25, 0.3])
    np.testing.assert_array_equal(h.loss, [5.0, 3.0, 4.0, 1.0])


def test_harness_runs_cmaes_and_hybrid_on_a_problem():
    space = ParamSpace(kp=Param(lo=0.0, hi=4.0, init=1.0), ki=Param(lo=0.01, hi=10.0, init=1.0, log=True))
    pb = Problem.from_loss("bowl", space, lambda p, d, k: (p["kp"] - 2.0) ** 2 + jnp.log(p["ki"] / 0.3) ** 2)
    comp = compare(pb, tuners=("cmaes", "hybrid"), budget=400, n_particles=8)
    rows = {r["tuner"]: r for r in comp.rows}
    assert rows["cmaes"]["sims"] == 400  # 8 candidates × 50 generations
    hyb = comp.results["hybrid"]
    assert rows["hybrid"]["sims"] == hyb.n_sims == hyb.history.sims[-1] and hyb.history.sims[11] == 8 * 12
    for name in ("cmaes", "hybrid"):
        assert rows[name]["best_loss"] < 1e-8, name
        assert rows[name]["params"]["kp"] == pytest.approx(2.0, abs=1e-4)


@pytest.mark.parametrize(
    "kwargs,match", [(dict(method="de"), "method"), (dict(lo=None), "lo/hi"), (dict(hi=[1.0, np.nan]), "hi")]
)
def test_bad_input_is_named(kwargs, match):
    args = dict(lo=[-1.0, -1.0], hi=[1.0, 1.0], popsize=4, iters=2, steps=2) | kwargs
    with pytest.raises(ValueError, match=match):
        hybrid(rastrigin, **args)
