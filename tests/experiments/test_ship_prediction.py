"""The ship_prediction study through the CLI (quick mode)."""

import pytest

from tests.experiments.study_cli import run_quick_study


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    out = tmp_path_factory.mktemp("ship")
    return out, run_quick_study("ship_prediction", out)


def test_metrics_against_the_paper_and_exactness(result):
    out, res = result
    m = res["metrics"]
    assert m["lti_max_abs_error"] <= 1e-8 and m["lti_max_order"] == 4
    assert m["pred_err_noise_free"] <= 1e-4  # paper: errors below the 4th decimal place
    assert m["pred_err_noise_free"] < m["pred_err_noise_1e-4"] < 1e-2
    assert m["warmup_samples"] == 20
    assert "vessel_model" in res["assumptions"] and res["assumptions"]["rank_tol"]["why"]
    assert (out / "null_space_choice.csv").exists() and (out / "prediction_errors.png").exists()
