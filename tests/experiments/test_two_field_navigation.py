"""The two_field_navigation study through the CLI (tiny preset): config recorded, files written, the
reductions recomputed from the comparison table, and the Monte-Carlo posterior against the linearised one."""

import pytest

from experiments.two_field_navigation import STUDY
from tests.experiments.study_cli import run_quick_study

pytestmark = pytest.mark.slow  # one short CLI run


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    out = tmp_path_factory.mktemp("tfn")
    return out, run_quick_study("two_field_navigation", out, preset="tiny")


def test_config_files_and_claims(result):
    out, res = result
    _, cfg = STUDY.resolve("tiny", [])
    assert res["config"]["n_particles"] == cfg.n_particles and res["config"]["n_trials"] == cfg.n_trials
    for name in ("comparison.csv", "reductions.csv", "maps_and_ellipses.png", "reproduction.csv"):
        assert (out / name).exists(), name
    rows = {r["metric"]: r for r in res["reproduction"]}
    assert rows["traj1_area_reduction_vs_echo_pct"]["paper"] == 33.8
    assert rows["traj2_radial_reduction_vs_gravimeter_pct"]["paper"] == 45.5
    assert rows["traj1_two_field_best"]["verdict"] == rows["traj2_two_field_best"]["verdict"] == "reproduced"
    for key in ("field_model", "trajectories", "estimator"):
        assert res["assumptions"][key]["why"]


def test_numbers_are_consistent(result):
    res = result[1]
    m = res["metrics"]
    assert m["map_mean_gradient_gravimeter_per_km"] == pytest.approx(0.72, rel=1e-9)
    assert m["map_mean_gradient_echo_per_km"] == pytest.approx(4.05, rel=1e-9)
    comp = {(r["trajectory"], r["fields"]): r for r in res["tables"]["comparison"]}
    for t in (1, 2):
        tr = f"trajectory {t}"
        both, grav = comp[(tr, "both")], comp[(tr, "gravimeter")]
        assert m[f"traj{t}_area_reduction_vs_gravimeter_pct"] == pytest.approx(
            100 * (1 - both["area_km2"] / grav["area_km2"]), rel=1e-9
        )
        for r in (comp[(tr, f)] for f in ("gravimeter", "echo sounder", "both")):
            # Monte-Carlo posterior (few particles in tiny) near the linearised Kalman covariance
            assert 0.5 < r["area_km2"] / r["linearised_area_km2"] < 2.0
            assert r["radial_rms_m"] < 1000 * 2**0.5  # better than the prior
    for r in res["tables"]["reductions"]:
        assert r["ci95_lo"] <= r["ours_pct"] <= r["ci95_hi"]
