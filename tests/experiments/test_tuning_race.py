"""Tuning-race benchmark: time-to-target arithmetic, the summary's medians and ratios, a tiny race end to end."""

import csv
import json

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import experiments.benchmarks.tuning_race as tr
from experiments.benchmarks.tuning_race import (
    BUDGETS,
    Budget,
    race,
    step_times,
    summarise,
    target_of,
    time_to,
    with_overrides,
    write_outputs,
)
from jaxsim.problem import Param, ParamSpace, Problem
from optim.results import History, TuneResult


def test_time_to_target_reads_the_first_step_at_or_below_it():
    best = np.array([5.0, 2.0, 1.01, 1.0005, 1.0])
    times = np.array([1.0, 2.0, 3.0, 4.0, 5.0])
    assert target_of(1.0, 0.01) == pytest.approx(1.01) and target_of(-2.0, 0.01) == pytest.approx(-1.98)
    assert time_to(best, times, target_of(1.0, 0.01)) == 3.0
    assert time_to(best, times, target_of(1.0, 0.001)) == 4.0
    assert time_to(best, times, 0.5) == float("inf")
    res = TuneResult(None, 1.0, History(best, np.arange(1, 6), np.array([0.1, 0.2, 0.3, 0.4, 0.5])), 5, 0.5)
    # the call took 2.5 s of which 0.5 s stepping: the other 2 s are charged before the first step
    np.testing.assert_allclose(step_times(res, 2.5), [2.1, 2.2, 2.3, 2.4, 2.5])


def _rec(tuner, r, loss_curve, times, warm_scale=0.5):
    run = lambda s: {  # noqa: E731
        "loss": float(loss_curve[-1]),
        "total_s": float(times[-1] * s),
        "compile_s": 0.0,
        "n_sims": len(times),
        "best_loss": np.asarray(loss_curve, float),
        "times": np.asarray(times, float) * s,
    }
    return {"problem": "p", "tuner": tuner, "round": r, "cold": run(1.0), "warm": run(warm_scale)}


def test_summary_medians_and_ratios_against_pso():
    recs = []
    for r, hit in enumerate([3.0, 1.0, 2.0]):  # pso reaches 0.1 % at 3, 1, 2 s: median 2 s
        recs.append(_rec("pso", r, [2.0, 1.0], [hit - 0.5, hit]))
        recs.append(_rec("fast", r, [1.5, 1.0], [0.25, 0.5]))  # reaches it at 0.5 s every round
        recs.append(_rec("slow", r, [1.5, 1.2], [1.0, 2.0]))  # never within 1 %
    recs.append({"problem": "p", "tuner": "broken", "round": 0, "cold": {"error": "E: no"}, "warm": {"error": "E: no"}})
    rows = {row["tuner"]: row for row in summarise(recs)}
    assert rows["pso"]["best_known"] == 1.0 and rows["pso"]["t_0.001_cold_s"] == 2.0
    assert rows["pso"]["t_0.001_warm_s"] == 1.0
    assert rows["fast"]["ratio_0.001_cold"] == pytest.approx(0.25) and rows["fast"]["reached_0.001_cold"] == 3
    assert rows["slow"]["ratio_0.01_cold"] == float("inf") and rows["slow"]["reached_0.01_warm"] == 0
    assert rows["broken"]["error"] == "E: no"


def test_a_tiny_race_end_to_end(tmp_path):
    space = ParamSpace(x=Param(lo=-1.0, hi=1.0, init=(0.5, 0.5)))
    pb = Problem.from_loss("bowl", space, lambda p, d, k: 1.0 + jnp.sum((p["x"] - 0.3) ** 2))
    before = jax.config.jax_enable_compilation_cache
    budget = Budget(particles=8, iters=20, random_n=64)
    records = race({"bowl": pb}, ["pso", "random"], rounds=1, budgets={"bowl": budget}, log=lambda _: None)
    assert jax.config.jax_enable_compilation_cache == before
    rows = summarise(records)
    pso_row = next(r for r in rows if r["tuner"] == "pso")
    assert pso_row["final_loss"] == pytest.approx(1.0, abs=1e-3) and pso_row["ratio_0.01_cold"] == 1.0
    assert pso_row["t_0.01_cold_s"] <= pso_row["cold_total_s"]
    for rec in records:  # same key: the warm call repeats the cold one's iterates
        np.testing.assert_array_equal(rec["cold"]["best_loss"], rec["warm"]["best_loss"])
    write_outputs(tmp_path, {"problems": ["bowl"]}, records, rows)
    assert json.loads((tmp_path / "tuning_race.json").read_text())["summary"][0]["problem"] == "bowl"
    assert [r["tuner"] for r in csv.DictReader(open(tmp_path / "tuning_race.csv"))] == ["pso", "random"]
    assert (tmp_path / "tuning_race.png").stat().st_size > 0


def test_every_race_problem_builds_from_the_studies_and_the_library():
    """The race imports its problems from the studies and ``jaxsim.problem``: a moved name fails here,
    not in a long benchmark run."""
    problems = tr.build_problems(["pid", "fuzzy", "trms"], trms_t_final=2.0)
    assert {n: p.space.dim for n, p in problems.items()} == {"pid": 3, "fuzzy": 4, "trms": 16}
    assert problems["fuzzy"].name == "fuzzy_p_smooth_penalised"


def test_budget_overrides_name_the_problem_and_field():
    out = with_overrides(BUDGETS, ["fuzzy.particles=16", "fuzzy.iters=20", "pid.adam_lr=0.1"])
    assert (out["fuzzy"].particles, out["fuzzy"].iters, out["fuzzy"].random_n) == (16, 20, BUDGETS["fuzzy"].random_n)
    assert out["pid"].adam_lr == 0.1 and out["trms"] == BUDGETS["trms"] and BUDGETS["fuzzy"].particles == 64
    for bad, match in [("fuzzy.nope=3", "FIELD in"), ("ship.iters=3", "PROBLEM in"), ("fuzzy.iters=-3", "positive")]:
        with pytest.raises(ValueError, match=match):
            with_overrides(BUDGETS, [bad])
    with pytest.raises(ValueError, match="not a valid int"):
        with_overrides(BUDGETS, ["fuzzy.iters=1.5"])
