"""Every tuner on a Problem: the space's box and reparametrisation are used, results carry the params
dict, ``converged`` tells convergence from a spent budget, the optax-like pair reproduces ``tune``."""

import jax
import jax.numpy as jnp
import numpy as np
import optax
import pytest

from jaxsim.problem import Param, ParamSpace, Problem, Sorted
from optim import compare, gradient_tuner, grid_search, pso, random_search, robust_loss, tune

# minimum at kp = 2, ki = 0.3 (log-scaled), breakpoints (0.4, 1.0): every coordinate kind once
TARGET = {"kp": 2.0, "ki": 0.3, "e": np.array([0.4, 1.0])}
SPACE = ParamSpace(
    kp=Param(lo=0.0, hi=5.0, init=1.0),
    ki=Param(lo=0.01, hi=10.0, init=1.0, log=True),
    e=Sorted(lo=0.1, hi=1.0, init=(0.5, 0.8)),
)


def _loss(p, draw, key):
    return (p["kp"] - 2.0) ** 2 + jnp.log(p["ki"] / 0.3) ** 2 + jnp.sum((p["e"] - jnp.asarray([0.4, 1.0])) ** 2)


PROBLEM = Problem.from_loss("bowl", SPACE, _loss)


def test_tune_on_a_problem_converges_and_says_so():
    res = tune(PROBLEM, optimizer=optax.adam(0.05), steps=3000, gtol=1e-7)
    assert res.converged and "gradient norm ≤ gtol" in res.message and "last gradient norm" in res.message
    assert float(res.params["kp"]) == pytest.approx(2.0, abs=1e-5)
    assert float(res.params["ki"]) == pytest.approx(0.3, rel=1e-5)
    np.testing.assert_allclose(res.params["e"], [0.4, 1.0], atol=1e-5)
    short = tune(PROBLEM, optimizer=optax.adam(0.05), steps=5)
    assert not short.converged and short.message.startswith("ran out of steps: 5 steps")
    assert f"last gradient norm {short.history.grad_norm_per_start[-1, 0]:.3g}" in short.message
    assert short.x is short.params  # the deprecated alias


def test_patience_converges_and_a_plain_loss_keeps_working():
    res = tune(PROBLEM, optimizer=optax.adam(0.05), steps=5000, patience=20, rtol=1e-10)
    assert res.converged and "no relative improvement" in res.message and res.n_steps < 5000
    plain = tune(lambda x: jnp.sum((x - 1.0) ** 2), jnp.zeros(2), optimizer=optax.adam(0.1), steps=50)
    assert plain.params.shape == (2,) and not plain.converged


def test_the_optax_like_pair_is_what_tune_runs():
    tuner = gradient_tuner(PROBLEM, optax.adam(0.05), n_starts=3, init_spread=0.3)
    state = tuner.init(key=jax.random.PRNGKey(1))
    for _ in range(40):
        state, info = tuner.step(state)
    assert info.f.shape == (3,) and info.x["e"].shape == (3, 2)
    params, loss, start = tuner.best(state)
    res = tune(PROBLEM, optimizer=optax.adam(0.05), steps=40, n_starts=3, init_spread=0.3, key=jax.random.PRNGKey(1))
    assert loss == res.loss and start == res.start_index
    for k in SPACE.keys:
        np.testing.assert_array_equal(params[k], res.params[k])


def test_searches_on_the_problems_box():
    swarm = pso(PROBLEM, n_particles=24, n_iters=150, key=jax.random.PRNGKey(0))
    assert swarm.loss < 1e-6 and swarm.converged and "collapsed" in swarm.message
    assert float(swarm.params["kp"]) == pytest.approx(2.0, abs=1e-3)
    np.testing.assert_allclose(SPACE.to_search(swarm.params), swarm.u, rtol=1e-12)
    assert swarm.history.loss.shape == (150,) and np.all(swarm.history.loss >= swarm.history.best_loss - 1e-15)
    few = pso(PROBLEM, n_particles=8, n_iters=3)
    assert not few.converged and "not converged" in few.message
    stuck = pso(PROBLEM, n_particles=8, n_iters=40, patience=5, tol=1e-12)
    assert stuck.converged == (stuck.history.best_loss[-1] >= stuck.history.best_loss[-6] * (1 - 1e-12))

    rnd = random_search(PROBLEM, 500, key=jax.random.PRNGKey(2), batch_size=100)
    assert rnd.n_sims == 500 and not rnd.converged and set(rnd.params) == {"kp", "ki", "e"}
    lo, hi = SPACE.box
    assert np.all(rnd.u >= lo) and np.all(rnd.u <= hi)
    grid = grid_search(PROBLEM, 3)
    assert grid.n_sims == 3**4
    # the grid's best point, recomputed by brute force on the box
    axes = [np.linspace(a, b, 3) for a, b in zip(lo, hi)]
    pts = np.array(np.meshgrid(*axes, indexing="ij")).reshape(4, -1).T
    vals = [float(PROBLEM.search_loss(jnp.asarray(z))) for z in pts]
    assert grid.loss == pytest.approx(min(vals), rel=1e-14)


def test_compare_gives_each_standard_tuner_the_same_budget():
    comp = compare(PROBLEM, tuners=("gradient", "pso", "random"), budget=256, n_particles=16, n_starts=4)
    sims = {r["tuner"]: r["sims"] for r in comp.rows}
    assert sims["pso"] == 256 and sims["random"] == 256 and sims["gradient"] == 256  # an evaluation is one
    assert comp.results["gradient"].n_steps == 64 and comp.results["gradient"].grad_cost == 1.0
    # a stated cost: the gradient tuner's steps are the budget over what 4 starts' gradient evaluations cost
    comp = compare(PROBLEM, tuners=("gradient",), budget=256, n_starts=4, grad_cost=2.5)
    grad, sims = comp.results["gradient"], {r["tuner"]: r["sims"] for r in comp.rows}
    assert grad.n_steps == 25 and sims["gradient"] == 250 and grad.n_evals == 100
    # a measured cost (a wall-clock ratio, at least 1): the same arithmetic
    comp = compare(PROBLEM, tuners=("gradient",), budget=256, n_starts=4, grad_cost="measure")
    sims = {r["tuner"]: r["sims"] for r in comp.rows}
    grad = comp.results["gradient"]
    assert grad.grad_cost >= 1.0
    assert grad.n_steps == 256 // (4 * grad.grad_cost) and sims["gradient"] == round(4 * grad.n_steps * grad.grad_cost)
    spent = 4 * grad.n_steps * grad.grad_cost  # the row's sims is this, rounded
    assert 256 - 4 * grad.grad_cost < spent <= 256
    row = next(r for r in comp.rows if r["tuner"] == "gradient")
    assert set(row["params"]) == {"kp", "ki", "e[0]", "e[1]"} and "converged" in row
    with pytest.raises(ValueError, match="budget: required"):
        compare(PROBLEM, tuners=("pso",))
    with pytest.raises(ValueError, match="too small for pso"):
        compare(PROBLEM, tuners=("pso",), budget=8, n_particles=16)


def test_a_problem_with_scenarios_counts_every_scenario_as_a_simulation():
    pb = Problem.from_loss(
        "shifted", SPACE, lambda p, d, k: (p["kp"] - d["c"]) ** 2, scenarios={"c": jnp.asarray([1.0, 2.0, 3.0])}
    )
    assert pb.sims_per_eval == 3
    res = tune(pb, optimizer=optax.adam(0.1), steps=10)
    assert res.n_evals == 30 == res.n_sims and res.grad_cost == 1.0
    res = tune(pb, optimizer=optax.adam(0.1), steps=10, grad_cost="measure")
    assert res.n_evals == 30 and res.grad_cost >= 1.0 and res.n_sims == round(30 * res.grad_cost)
    assert tune(pb, optimizer=optax.adam(0.1), steps=10, grad_cost=2.5).n_sims == 75
    assert pso(pb, n_particles=4, n_iters=5).n_sims == 60
    worst = robust_loss(pb, {"c": jnp.asarray([0.0, 4.0])}, reducer=lambda v: jnp.max(v))
    assert float(worst.loss({"kp": jnp.asarray(1.0), "ki": 1.0, "e": jnp.asarray([0.5, 0.8])})) == 9.0


def test_progress_bar_on_request(capsys):
    tune(PROBLEM, steps=3, progress=True)
    pso(PROBLEM, n_particles=4, n_iters=2, progress=True)
    err = capsys.readouterr().err
    assert "tune bowl" in err and "pso bowl" in err
