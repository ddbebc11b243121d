"""The orientation_system_accuracy study through the CLI (tiny preset): files, verdicts against the
computed metrics, kernel checks, and the Monte-Carlo statistics re-computed with NumPy from the per-run
table."""

import math

import numpy as np
import pytest

from experiments.orientation_system_accuracy import ANGLES, STUDY
from tests.experiments.study_cli import assert_verdicts_follow_the_tolerances, run_quick_study

pytestmark = pytest.mark.slow  # a short study run through the CLI: a few compilations


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    out = tmp_path_factory.mktemp("osa")
    return out, run_quick_study("orientation_system_accuracy", out, preset="tiny")


def test_config_files_and_verdicts(result):
    out, res = result
    _, tiny = STUDY.resolve("tiny")
    assert res["preset"] == "tiny" and res["config"]["n_runs"] == tiny.n_runs == 3
    for name in (
        "gauss_markov.csv",
        "runs.csv",
        "nees.csv",
        "errors.png",
        "flight.png",
        "cf_tuning.csv",
        "reproduction.csv",
    ):
        assert (out / name).exists(), name
    assert_verdicts_follow_the_tolerances(res, STUDY.claims)
    rows = {r["metric"]: r for r in res["reproduction"]}
    for name in ("attitude_update_max_err_deg", "attitude_update_order", "gm_autocorr_at_tau_ratio"):
        assert rows[name]["verdict"] == "reproduced", name
    assert any("TAMCAL" in n for n in res["notes"])


def test_gauss_markov_table_against_closed_form(result):
    res = result[1]
    sigma, tau = 0.05 * math.pi / 180.0, 300.0
    for row in res["tables"]["gauss_markov"]:
        assert row["autocov_closed_form"] == pytest.approx(sigma**2 * math.exp(-row["lag_s"] / tau), rel=1e-12)
    lag0 = res["tables"]["gauss_markov"][0]
    assert lag0["ci_low"] < lag0["autocov_closed_form"] * 1.3 and lag0["ci_high"] > lag0["autocov_closed_form"] * 0.7


def test_statistics_recomputed_from_runs(result):
    res = result[1]
    m, runs = res["metrics"], res["tables"]["runs"]
    n = len(runs)
    for a in ANGLES:
        s = np.array([r[f"sigma_after_{a}_deg"] for r in runs])
        half = 1.96 * s.std(ddof=1) / math.sqrt(n)
        assert m[f"after_sigma_{a}_deg"] == pytest.approx(s.mean(), rel=1e-12)
        assert m[f"after_sigma_{a}_ci_high"] == pytest.approx(s.mean() + half, rel=1e-12)
        b = np.array([r[f"bias_after_{a}_deg"] for r in runs])
        assert m[f"after_bias_{a}_rms_deg"] == pytest.approx(np.sqrt(np.mean(b**2)), rel=1e-12)
        d = np.abs([r[f"drift_before_{a}_deg_h"] for r in runs])
        assert m[f"before_drift_{a}_deg_h"] == pytest.approx(d.mean(), rel=1e-12)
    # the fusion beats the raw sensors by orders of magnitude
    for a in ("roll", "heading"):
        assert m[f"after_sigma_{a}_deg"] < 0.1 * m[f"before_sigma_{a}_deg"]
    hist = res["tables"]["cf_tuning"]
    assert [r["step"] for r in hist] == list(range(len(hist))) and len(hist) >= res["config"]["tune_steps"]
    assert hist[0]["crossover"] == pytest.approx(res["config"]["cf_crossover"], rel=1e-9)
    assert m["cf_tune_loss_end"] <= m["cf_tune_loss_start"]
    nees = res["tables"]["nees"]
    assert all(r["bound_low"] < 3.0 < r["bound_high"] for r in nees)
