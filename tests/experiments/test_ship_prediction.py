"""The ship_prediction study through the CLI (quick mode)."""

import json
import subprocess
import sys

import pytest

from tests.conftest import ROOT


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    out = tmp_path_factory.mktemp("ship")
    proc = subprocess.run([sys.executable, "-m", "experiments", "run", "ship_prediction", "--quick", "--out", str(out)],
                          capture_output=True, text=True, cwd=ROOT, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return out, json.loads((out / "results.json").read_text())


def test_metrics_against_the_paper_and_exactness(result):
    out, res = result
    m = res["metrics"]
    assert m["lti_max_abs_error"] <= 1e-8 and m["lti_max_order"] == 4
    assert m["pred_err_noise_free"] <= 1e-4  # paper: errors below the 4th decimal place
    assert m["pred_err_noise_free"] < m["pred_err_noise_1e-4"] < 1e-2
    assert m["warmup_samples"] == 20
    assert "vessel_model" in res["assumptions"] and res["assumptions"]["rank_tol"]["why"]
    assert (out / "null_space_choice.csv").exists() and (out / "prediction_errors.png").exists()
