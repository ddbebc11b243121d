"""The ship_prediction study through the CLI (quick preset + a --set override)."""

import pytest

from tests.experiments.study_cli import run_quick_study


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    out = tmp_path_factory.mktemp("ship")
    return out, run_quick_study("ship_prediction", out, "--set", "n_noise_runs=4")


def test_metrics_against_the_paper_and_exactness(result):
    out, res = result
    m = res["metrics"]
    assert m["lti_max_abs_error"] <= 1e-8 and m["lti_max_order"] == 4
    assert m["pred_err_noise_free"] <= 1e-4  # paper: errors below the 4th decimal place
    assert m["pred_err_noise_free"] < m["pred_err_noise_1e-4"] < 1e-2
    assert m["warmup_samples"] == 20
    assert "vessel_model" in res["assumptions"] and res["assumptions"]["rank_tol"]["why"]
    assert (out / "null_space_choice.csv").exists() and (out / "prediction_errors.png").exists()


def test_config_is_the_quick_preset_with_the_override_and_is_what_ran(result):
    _, res = result
    cfg = res["config"]
    assert res["preset"] == "quick" and "quick" not in cfg
    assert cfg["n_noise_runs"] == 4 and len(res["tables"]["noise_runs"]) == 4  # the override ran
    assert cfg["t_final"] == 60.0 and cfg["n_lti_systems"] == 20 == len(res["tables"]["random_lti"])  # quick's


def test_reproduction_table(result):
    _, res = result
    rows = {r["metric"]: r for r in res["reproduction"]}
    assert set(rows) == {"pred_err_noise_free", "hankel_rank_vessel", "lti_max_abs_error"}
    for name, r in rows.items():
        assert r["verdict"] == "reproduced" and r["ours"] == res["metrics"][name] and r["source"], name
