"""Study ``tilt_rotor_failure`` (seed 004 #8, part 3) through the CLI, tiny preset: the trim and the
level-hover defect against SciPy on the independent NumPy plant, the design's controllability, the
claims' verdicts and the tuners' bookkeeping."""

import numpy as np
import pytest
from scipy.optimize import least_squares

from experiments.tilt_rotor_failure import STUDY
from tests.control.test_tilt_rotor import W, numpy_residual, scipy_trim
from tests.experiments.study_cli import recorded_config, run_quick_study


@pytest.fixture(scope="module")
def study_output(tmp_path_factory):
    out = tmp_path_factory.mktemp("tilt_rotor")
    return out, run_quick_study("tilt_rotor_failure", out, preset="tiny")


def test_config_files_and_claims(study_output):
    out, res = study_output
    tiny = STUDY.resolve("tiny")[1]
    assert res["preset"] == "tiny"
    cfg = recorded_config(tiny)
    assert res["config"] == cfg
    for name in ("trim.csv", "comparison.csv", "robustness.csv", "reproduction.csv", "loss_vs_budget.png"):
        assert (out / name).stat().st_size > 0, name
    rows = {r["metric"]: r for r in res["reproduction"]}
    assert set(rows) == {"return_error_m_p95_hand", "return_error_m_p95_gradient"}
    for r in rows.values():  # the verdict follows the number
        assert (r["verdict"] == "reproduced") == (0.0 <= res["metrics"][r["metric"]] <= 0.25)
    assert [r["runs"] for r in res["tables"]["robustness"]] == [tiny.mc_runs] * 3


def test_trim_and_level_defect_against_scipy(study_output):
    _, res = study_output
    m = res["metrics"]
    z, _ = scipy_trim()
    assert m["trim_omega_rad_s"] == pytest.approx(z[0], rel=1e-8)
    assert m["trim_tilt1_deg"] == pytest.approx(np.rad2deg(z[2]), abs=1e-6)
    assert m["trim_tilt4_deg"] == pytest.approx(np.rad2deg(z[3]), abs=1e-6)
    assert m["trim_pitch_deg"] == pytest.approx(np.rad2deg(z[5]), abs=1e-6)
    assert m["trim_residual"] < 1e-15
    rng = np.random.default_rng(3)
    starts = np.column_stack([W * rng.uniform(0.7, 1.5, (8, 2)), rng.uniform(-1.6, 1.6, (8, 2))])
    level = min(2 * least_squares(lambda u: numpy_residual(np.r_[u, 0.0, 0.0]), s, xtol=1e-15).cost for s in starts)
    assert m["level_hover_least_residual"] == pytest.approx(level, rel=1e-6)
    assert level > 1.0  # no level hover
    assert m["controllability_rank"] == 15


def test_tuners_spent_equal_budgets_and_gradient_beats_the_hand_design(study_output):
    _, res = study_output
    tiny = STUDY.resolve("tiny")[1]
    rows = {r["tuner"]: r for r in res["tables"]["comparison"]}
    assert set(rows) == {"gradient", "pso"}
    assert all(r["sims"] <= tiny.budget for r in rows.values())
    assert res["metrics"]["loss_ratio_gradient_to_hand"] < 1.0
