"""The path_following_allocation study through the CLI (tiny preset): files, verdicts against bands, and
the per-segment statistics recomputed from the written run-0 trace and the exact track geometry."""

import math

import numpy as np
import pytest

from experiments.path_following_allocation import STUDY
from tests.experiments.study_cli import assert_verdicts_follow_the_tolerances, run_quick_study


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    out = tmp_path_factory.mktemp("pfa")
    return out, run_quick_study("path_following_allocation", out, preset="tiny")


def test_files_and_verdicts(result):
    out, res = result
    _, tiny = STUDY.resolve("tiny")
    assert res["preset"] == "tiny" and res["config"]["n_runs"] == tiny.n_runs
    for name in ("segments.csv", "run0.csv", "path_following.png", "reproduction.csv"):
        assert (out / name).exists(), name
    assert_verdicts_follow_the_tolerances(res, STUDY.claims)


def test_numbers_recomputed(result):
    res = result[1]
    m = res["metrics"]
    assert m["track_length_m"] == pytest.approx(475 + 100 * math.pi, rel=1e-13)
    run0 = res["tables"]["run0"]
    s = np.array([r["s_m"] for r in run0])
    e = np.abs([r["e_y_m"] for r in run0])
    a, b = 200 + 75 * math.pi + 100, 200 + 75 * math.pi + 100 + 12.5 * math.pi
    mask = (s >= a) & (s < b)
    seg = {r["segment"]: r for r in res["tables"]["segments"]}
    # run 0's peak in the first R 25 curve (segment from the exact geometry) lies in the runs' range
    r25 = seg["curve_90_r25_a"]
    assert r25["peak_min_m"] - 1e-12 <= e[mask].max() <= r25["peak_max_m"] + 1e-12
    assert r25["peak_min_m"] <= m["peak_r25_first_m"] <= r25["peak_max_m"]
    assert m["rms_all_m"] > 0 and m["allocation_error_rms_run"] < 1e-2
    assert m["straight_rms_max_m"] == pytest.approx(
        max(r["rms_mean_m"] for k, r in seg.items() if k.startswith("straight"))
    )


def test_tuned_designs_rescored_on_the_monte_carlo(result):
    """Gradient and PSO designs (equal budgets) in the designs table, inside the search box, the hand
    design's RMS equal to the segment statistics' overall RMS (same draws, same gains)."""
    res = result[1]
    rows = {r["design"]: r for r in res["tables"]["designs"]}
    assert set(rows) == {"hand", "gradient", "pso"}
    m = res["metrics"]
    assert rows["hand"]["rms_all_m"] == pytest.approx(m["rms_all_m"], rel=1e-9)
    assert m["gradient_over_hand_rms"] == pytest.approx(rows["gradient"]["rms_all_m"] / rows["hand"]["rms_all_m"])
    for r in rows.values():
        assert 2.0 <= r["delta_max"] <= 30.0 and 0.3 <= r["k_course"] <= 6.0
    assert res["metrics"]["sims_gradient"] == res["metrics"]["sims_pso"]  # equal budgets
