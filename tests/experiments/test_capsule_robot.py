"""The capsule_robot study through the CLI (tiny preset): files, recorded config, the closed-form
optimum, the verdicts against their tolerances, the tuned gaits' admissibility."""

import numpy as np
import pytest

from experiments.capsule_robot import CLAIMS, STUDY
from tests.experiments.study_cli import assert_verdicts_follow_the_tolerances, recorded_config, run_quick_study


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    out = tmp_path_factory.mktemp("capsule")
    return out, run_quick_study("capsule_robot", out, preset="tiny")


def test_files_config_and_claims(result):
    out, res = result
    _, cfg = STUDY.resolve("tiny", [])
    assert res["config"] == recorded_config(cfg)
    for name in (
        "grid_convergence.csv",
        "mass_ratio.csv",
        "gaits.csv",
        "velocity_control.csv",
        "gaits.png",
        "velocity_control.png",
        "reproduction.csv",
    ):
        assert (out / name).stat().st_size > 0, name
    m = res["metrics"]
    assert m["v2_closed_form_over_unit"] == pytest.approx(np.sqrt(0.5), rel=1e-12)
    assert m["speed_exponent_in_mu"] == pytest.approx(0.5, abs=1e-3)
    assert m["v1_resting_two_phase_over_unit"] == pytest.approx(0.5, abs=1e-3)
    assert m["symmetric_gait_growth"] > 3
    assert_verdicts_follow_the_tolerances(res, CLAIMS)
    for key in ("plant", "units", "constraints_v1", "constraints_v2"):
        assert res["assumptions"][key]["why"]


def test_tuned_gaits_are_admissible_and_not_faster_than_the_optimum(result):
    _, res = result
    m = res["metrics"]
    for row in res["tables"]["gaits"]:
        assert row["stroke_over_L"] <= 1 + 1e-9
        assert row["max_accel_over_kg_mu"] <= 1 + 1e-9
        assert row["min_body_velocity_m_s"] >= -1e-12
        assert row["v_over_unit"] <= m["v2_closed_form_over_unit"]
    conv = [r["v_over_unit"] for r in res["tables"]["grid_convergence"]]
    assert conv == sorted(conv) and conv[-1] < m["v2_closed_form_over_unit"]
