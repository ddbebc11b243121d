"""The linear_pid_accuracy study through the CLI, as a user runs it."""

import json
import math
import subprocess
import sys

import pytest

from tests.conftest import ROOT
from tests.experiments.study_cli import run_quick_study


@pytest.fixture(scope="module")
def study_output(tmp_path_factory):
    out = tmp_path_factory.mktemp("lpa")
    run_quick_study("linear_pid_accuracy", out, "--set", "t_final=12")
    return out


def test_results_json_has_the_contracted_keys(study_output):
    res = json.loads((study_output / "results.json").read_text())
    assert set(res) >= {"study", "config", "assumptions", "metrics", "tables"}
    assert res["study"] == "linear_pid_accuracy"
    # the quick preset (t_final 10 s) with --set t_final=12 on top: recorded, and what ran
    assert res["preset"] == "quick" and res["config"]["t_final"] == 12.0 and "quick" not in res["config"]
    assert any("horizon 12.0 s" in note for note in res["notes"])
    rows = {r["metric"]: r for r in res["reproduction"]}
    assert {r["verdict"] for r in rows.values()} == {"reproduced"} and rows["kp_mds_static"]["paper"] == 0.4
    for key in ("g_slope", "f_slope", "derivative_filter", "pi_pd_gains"):
        assert key in res["assumptions"] and res["assumptions"][key]["why"]
    assert (study_output / "steady_state_errors.csv").exists()
    assert (study_output / "transients_static.png").stat().st_size > 10_000
    assert (study_output / "stability_degree_vs_kp.png").exists()


def test_maximum_stability_gains_are_computed(study_output):
    m = json.loads((study_output / "results.json").read_text())["metrics"]
    assert m["kp_mds_static"] == pytest.approx(0.4, rel=1e-12)
    assert m["kp_mds_astatic"] == pytest.approx(1.25, rel=1e-12)
    assert m["pi_mds_astatic_kp"] == pytest.approx(5 / 3, rel=1e-12)
    assert m["pi_mds_astatic_ki"] == pytest.approx(1 / (27 * 0.1**2 * 2), rel=1e-12)


def test_every_finite_cell_matches_and_every_infinite_cell_diverges(study_output):
    rows = json.loads((study_output / "results.json").read_text())["tables"]["steady_state_errors"]
    assert len(rows) == 24
    for row in rows:
        if row["analytic_table"] in ("inf", "-inf"):
            assert row["status"].startswith("diverges"), row
            assert row["analytic_final_value"] == row["analytic_table"]
        else:
            assert row["status"] == "finite", row
            scale = max(abs(row["analytic_table"]), abs(row["magnitude"]))
            assert abs(row["simulated"] - row["analytic_table"]) <= 1e-6 * scale, row
            assert math.isclose(row["analytic_final_value"], row["analytic_table"], rel_tol=1e-12, abs_tol=1e-15)
    # Paper numbers: static plant, P at K_mds, g = 1 → 0.5556; astatic plant, f = 0.3 → 0.24
    cell = next(r for r in rows if r["plant"] == "static" and r["controller"] == "P" and r["input"] == "g = const")
    assert cell["simulated"] == pytest.approx(0.5556, abs=5e-5)


def test_cli_list_help_and_bad_override():
    run = lambda *a: subprocess.run(  # noqa: E731
        [sys.executable, "-m", "experiments", *a],  # noqa: E731
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=300,
    )
    listed = run("list")
    assert listed.returncode == 0 and "linear_pid_accuracy" in listed.stdout
    assert run("--help").returncode == 0
    bad = run("run", "linear_pid_accuracy", "--set", "no_such_key=1")
    assert bad.returncode == 2 and "no_such_key" in bad.stderr
    unknown = run("run", "no_such_study")
    assert unknown.returncode == 2 and "unknown study" in unknown.stderr


def test_config_overrides_convert_types():
    from experiments.config_overrides import apply_overrides
    from experiments.linear_pid_accuracy import Config

    cfg = apply_overrides(Config(), ["t_final=12", "drift_window=2", "g_slope=0.25"])
    assert cfg.t_final == 12.0 and cfg.drift_window == 2.0 and cfg.g_slope == 0.25
    with pytest.raises(ValueError, match="t_final"):
        apply_overrides(Config(), ["t_final=abc"])
