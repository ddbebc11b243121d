"""Study ``isoline_seeking`` through the CLI (tiny preset, one run): config and files, the Wilson intervals
recomputed from the per-run table, the metrics consistent with the runs, the start poses outside the obstacles."""

import dataclasses

import numpy as np
import pytest

from experiments.isoline_seeking import STUDY, draws
from jaxsim.montecarlo.events import wilson_interval
from tests.experiments.study_cli import run_quick_study


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    out = tmp_path_factory.mktemp("iso")
    return out, run_quick_study("isoline_seeking", out, preset="tiny")


def test_config_files_and_claims(study):
    out, res = study
    tiny = STUDY.resolve("tiny")[1]
    assert res["preset"] == "tiny" and res["config"] == dataclasses.asdict(tiny)
    for name in ("trajectories.png", "events.csv", "runs.csv", "success_by_start.csv"):
        assert (out / name).stat().st_size > 0, name
    assert {r["metric"] for r in res["reproduction"]} == {"success_rate", "collision_rate"}
    assert len(res["tables"]["runs"]) == tiny.n_runs


def test_events_and_metrics_from_the_runs(study):
    _, res = study
    runs = res["tables"]["runs"]
    n = len(runs)
    k = sum(r["success"] for r in runs)
    ev = {r["event"]: r for r in res["tables"]["events"]}
    lo, hi = wilson_interval(k, n)
    assert ev["success"]["count"] == k and ev["success"]["runs"] == n
    assert (ev["success"]["wilson_low"], ev["success"]["wilson_high"]) == pytest.approx((float(lo), float(hi)))
    m = res["metrics"]
    assert m["success_rate"] == pytest.approx(k / n)
    assert m["collision_rate"] == pytest.approx(np.mean([r["min_distance_m"] < 0 for r in runs]))
    assert m["min_distance_min_m"] == pytest.approx(min(r["min_distance_m"] for r in runs))
    # the per-band table partitions the runs
    assert sum(b["runs"] for b in res["tables"]["success_by_start"]) == n
    # every run that was not reached has an infinite reach time; the reached ones a positive one
    for r in runs:
        assert (r["t_reach_s"] == float("inf")) == (r["coverage"] == 0.0 and r["tracking_rms_m"] == 0.0)


def test_start_poses_are_clear_of_the_obstacles():
    cfg = STUDY.resolve("tiny")[1]
    d = draws(cfg)
    for p, discs in zip(d["pose0"], d["discs"]):
        clearance = np.min(np.hypot(p[0] - discs[:, 0], p[1] - discs[:, 1]) - discs[:, 2])
        assert clearance >= 0.4 - 1e-9
    # the obstacles sit on each run's isoline
    th = np.array([0.0, 2.2, 4.0])
    rho = np.hypot(d["discs"][..., 0], d["discs"][..., 1])
    assert rho == pytest.approx((d["a"][:, None] + d["b"][:, None] * np.cos(th)) / cfg.f0)
