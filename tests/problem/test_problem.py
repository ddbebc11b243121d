"""Problem: its loss against an independent fold of the same loop (``PIDTuning.loss``), evaluate()
against simulate() + core.metrics, robust() against explicit draws, sample() against the Monte-Carlo
engine's draws, monte_carlo(problem) against robust(), jitted functions compiled once."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxsim.montecarlo as mc
from jaxsim.core import costs, metrics
from jaxsim.montecarlo.kernel import run_one
from jaxsim.problem import Param, ParamSpace, Problem, Scenario, penalised
from optim import tune
from optim.problems import PIDTuning
from tests.jax_log import jax_messages
from tests.jaxpr_loops import loop_depths

TUNING = PIDTuning(t_final=1.0)
GAINS = jnp.asarray([6.0, 4.0, 0.3])


def _build(p, d):
    tuning = PIDTuning(K=d["K"], T1=d["T1"], T2=d["T2"], t_final=TUNING.t_final)
    return Scenario(tuning.closed_loop(p["gains"]), jnp.zeros(2), TUNING.timing)


def pid_problem(**kw):
    space = ParamSpace(gains=Param(lo=(0, 0, 0), hi=(20, 20, 2), init=(10, 10, 1), labels=("kp", "ki", "kd")))
    objective = costs.combine(ise=costs.ise(), energy=(TUNING.rho, costs.control_energy()))
    return Problem("pid", space, objective, _build, nominal={"K": 2.0, "T1": 0.1, "T2": 0.5}, **kw)


UNCERTAIN = {"K": mc.deviation(2.0, 0.2, relative=True), "T1": mc.deviation(0.1, 0.2, relative=True)}


@pytest.fixture(scope="module")
def problem():
    return pid_problem(uncertainty=UNCERTAIN)


def test_loss_equals_the_hand_written_fold_of_the_same_loop(problem):
    params = {"gains": GAINS}
    ours = float(problem.jitted.loss(params))
    assert ours == pytest.approx(float(jax.jit(TUNING.loss)(GAINS)), rel=1e-12)
    g_ours = jax.grad(problem.loss)(params)["gains"]
    np.testing.assert_allclose(g_ours, jax.grad(TUNING.loss)(GAINS), rtol=1e-10)


def test_evaluate_terms_equal_metrics_of_the_simulated_run(problem):
    params = {"gains": GAINS}
    b = problem.jitted.evaluate(params)
    tr = problem.jitted.simulate(params)
    e = tr.r[:, 0] - tr.y[:, 0]
    assert float(b.terms["ise"]) == pytest.approx(float(metrics.ise(tr.t, e)), rel=1e-12)
    assert float(b.terms["energy"]) == pytest.approx(float(metrics.control_energy(tr.t, tr.u)), rel=1e-12)
    assert float(b.total) == pytest.approx(float(b.terms["ise"] + TUNING.rho * b.terms["energy"]), rel=1e-14)


def test_robust_loss_is_the_mean_over_explicit_draws(problem):
    n = 5
    robust = problem.robust(n, jax.random.PRNGKey(3))
    assert robust.sims_per_eval == n
    draws = problem.sample(jax.random.PRNGKey(3), n)
    assert draws["K"].shape == (n,) and np.all(np.abs(draws["K"] / 2.0 - 1) <= 0.2)
    expected = np.mean(
        [float(PIDTuning(K=float(draws["K"][i]), T1=float(draws["T1"][i]), t_final=1.0).loss(GAINS)) for i in range(n)]
    )
    assert float(robust.jitted.loss({"gains": GAINS})) == pytest.approx(expected, rel=1e-12)
    worst = problem.robust(n, jax.random.PRNGKey(3), reducer=lambda v: jnp.max(v))
    totals = robust.scenario_totals({"gains": GAINS})
    assert float(worst.loss({"gains": GAINS})) == pytest.approx(float(jnp.max(totals)), rel=1e-14)


def test_robust_over_operating_points_takes_every_draw_at_every_point():
    base = pid_problem(uncertainty=UNCERTAIN, scenarios={"T2": jnp.asarray([0.5, 0.3])})
    robust = base.robust(3, 7)
    assert robust.n_scenarios == 6
    draws = base.sample(7, 3)
    np.testing.assert_array_equal(robust.scenarios["T2"], [0.5, 0.3] * 3)
    np.testing.assert_array_equal(robust.scenarios["K"], np.repeat(draws["K"], 2))
    totals = robust.scenario_totals({"gains": GAINS})
    i = 3  # draw 1 at the second operating point
    one = PIDTuning(K=float(draws["K"][1]), T1=float(draws["T1"][1]), T2=0.3, t_final=1.0).loss(GAINS)
    assert float(totals[i]) == pytest.approx(float(one), rel=1e-12)
    with pytest.raises(ValueError, match="K: is both a fixed scenario value and uncertain"):
        pid_problem(uncertainty=UNCERTAIN, scenarios={"K": jnp.asarray([1.0, 2.0])}).robust(2, 0)


def test_sample_is_the_monte_carlo_engines_draw_and_mc_of_a_problem_matches_robust(problem):
    key = jax.random.key(11)
    draws = problem.sample(key, 3)
    space = {**problem.nominal, **problem.uncertainty}
    for i in range(3):
        p, _ = run_one(lambda k, d: d["K"], space, {}, key, jnp.asarray(i))
        assert float(p["K"]) == float(draws["K"][i]) and float(p["T1"]) == float(draws["T1"][i])
    params = {"gains": GAINS}
    res = mc.monte_carlo(problem, params, 8, 11, block_size=4)
    assert set(res.by_name) == {"ise", "energy", "total"}
    assert float(res["total"].mean) == pytest.approx(float(problem.robust(8, 11).loss(params)), rel=1e-12)


def test_from_loss_constraints_and_the_search_loss():
    space = ParamSpace(x=Param(lo=-2.0, hi=2.0, init=(0.5, 0.5)))
    pb = Problem.from_loss(
        "quad",
        space,
        lambda p, d, k: jnp.sum((p["x"] - 1.0) ** 2),
        constraints=lambda p: p["x"][0] - 0.5,
        penalty_weight=10.0,
    )
    z = jnp.asarray([1.0, 1.0])
    assert float(pb.loss(space.from_search(z))) == 0.0
    assert float(pb.search_loss(z)) == pytest.approx(0.5 * 10.0 * 0.25, rel=1e-14)
    assert pb.evaluate(space.init).terms.keys() == {"loss"}
    with pytest.raises(ValueError, match="made with from_loss"):
        pb.simulate(space.init)


def _loops(fn, *args) -> int:
    """Top-level scan/while loops in ``fn``'s jaxpr (one per simulation)."""
    return loop_depths(jax.make_jaxpr(fn)(*args)).count(0)


def test_from_terms_simulates_once_for_loss_and_constraints_and_tunes_as_two_calls_do():
    space = ParamSpace(gains=Param(lo=(0, 0, 0), hi=(20, 20, 2), init=(6, 4, 0.3)))
    j0 = float(TUNING.loss(GAINS))

    def terms(p):  # ISE + energy of one rollout; constraints: kd ≤ 0.25, loss ≤ 0.9 × its start
        j = TUNING.loss(p["gains"])
        return j, jnp.stack([p["gains"][2] - 0.25, j - 0.9 * j0])

    joint = Problem.from_terms("pid_joint", space, terms, penalty_weight=50.0)
    split = Problem.from_loss(
        "pid_split", space, lambda p, d, k: terms(p)[0], constraints=lambda p: terms(p)[1], penalty_weight=50.0
    )
    x = space.init
    f, g = joint.loss_and_violation(x)
    np.testing.assert_allclose(f, split.loss(x), rtol=1e-14)
    np.testing.assert_allclose(g, split.violation(x), rtol=1e-14)
    np.testing.assert_allclose(joint.penalised_loss(x), split.penalised_loss(x), rtol=1e-14)
    assert float(g[0]) == pytest.approx(0.05) and float(joint.penalised_loss(x)) > float(f)
    w_half_sum = 25.0 * (0.05**2 + max(float(g[1]), 0.0) ** 2)  # (w/2)·Σ max(0, g)², w = 50
    np.testing.assert_allclose(joint.penalised_loss(x), float(f) + w_half_sum, rtol=1e-12)
    assert _loops(joint.penalised_loss, x) == 1 and _loops(split.penalised_loss, x) == 2
    kw = dict(steps=15, constraint_method="augmented_lagrangian", mode="forward")
    a, b = tune(joint, **kw), tune(split, **kw)
    np.testing.assert_allclose(a.params["gains"], b.params["gains"], rtol=1e-12)
    assert a.loss == pytest.approx(b.loss, rel=1e-12) and a.constraint_violation == b.constraint_violation
    with pytest.raises(ValueError, match="terms_fn: must be callable"):
        Problem.from_terms("bad", space, 1.0)


def test_jitted_functions_compile_once_per_problem(problem):
    pb = pid_problem()
    params = {"gains": GAINS}
    with jax_messages() as messages:
        for kp in (1.0, 2.0, 3.0):
            pb.jitted.loss({"gains": jnp.asarray([kp, 1.0, 0.1])})
        # draw/key left out, passed as None or by keyword: one signature (a study's response
        # table and its figure used to compile the same rollout twice)
        runs = [pb.jitted.simulate(params), pb.jitted.simulate(params, None), pb.jitted.simulate(params, key=None)]
        totals = [pb.jitted.evaluate(params).total, pb.jitted.evaluate(params, None, None).total]
    assert pb.jitted is pb.jitted
    for name in ("loss", "simulate", "evaluate"):
        assert len([m for m in messages if m.startswith(f"Compiling jit({name})")]) == 1, (name, messages)
    np.testing.assert_array_equal(runs[0].y, runs[1].y)
    np.testing.assert_array_equal(runs[0].y, runs[2].y)
    assert float(totals[0]) == float(totals[1])


def test_bad_problems_are_refused():
    space = ParamSpace(x=Param(lo=0.0, hi=1.0, init=0.5))
    obj = costs.combine(ise=costs.ise())
    with pytest.raises(ValueError, match="nominal: needs a nominal value .* missing K"):
        Problem("p", space, obj, _build, uncertainty={"K": mc.normal(2.0, 0.1)})
    with pytest.raises(ValueError, match="uncertainty: K must be jaxsim.montecarlo distributions"):
        Problem("p", space, obj, _build, nominal={"K": 2.0}, uncertainty={"K": 2.0})
    with pytest.raises(ValueError, match="scenarios: every leaf needs the same"):
        Problem("p", space, obj, _build, scenarios={"K": jnp.ones(2), "T1": jnp.ones(3)})
    with pytest.raises(ValueError, match="build/objective"):
        Problem("p", space, obj)
    with pytest.raises(ValueError, match="space: expected a ParamSpace"):
        Problem("p", {"x": 1.0}, obj, _build)
    with pytest.raises(ValueError, match="Normal.std: must be positive"):
        Problem("p", space, obj, _build, nominal={"K": 2.0}, uncertainty={"K": mc.Normal(2.0, -1.0)})
    with pytest.raises(ValueError, match="build: must return a Scenario"):
        Problem("p", space, obj, lambda p, d: None).loss(space.init)


def test_monte_carlo_of_a_problem_shows_a_progress_bar_on_request(problem, capsys):
    res = mc.monte_carlo(problem, {"gains": GAINS}, 8, 11, block_size=4, progress=True)
    assert res.runs == 8 and "problem:pid: 100%" in capsys.readouterr().err


def test_penalised_adds_half_the_weight_times_the_squared_violations_only():
    g = jnp.array([[-1.0, 0.5], [0.0, 2.0]])  # any shape; -1 and 0 are satisfied
    assert float(penalised(jnp.array(1.0), g, 4.0)) == pytest.approx(1.0 + 2.0 * (0.25 + 4.0), rel=1e-15)
    assert float(penalised(jnp.array(3.0), -(g**2), 4.0)) == 3.0
    assert jax.grad(lambda f: penalised(f, g, 4.0))(1.0) == 1.0
