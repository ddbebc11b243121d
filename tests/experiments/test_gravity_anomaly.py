"""The gravity_anomaly study through the CLI (tiny preset): model identities against closed forms and
SciPy, χ²(4) rejection rates, the gated smoother, maximum likelihood, and the paper's real-data numbers
reported as not computed."""

import math

import numpy as np
import pytest
import scipy.stats

from experiments.gravity_anomaly import STUDY
from tests.experiments.study_cli import run_quick_study

pytestmark = pytest.mark.slow  # a short study run through the CLI: a few compilations


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    out = tmp_path_factory.mktemp("grav")
    return out, run_quick_study("gravity_anomaly", out, preset="tiny")


def test_config_files_and_verdicts(result):
    out, res = result
    _, tiny = STUDY.resolve("tiny")
    assert res["preset"] == "tiny" and res["config"]["line_steps"] == tiny.line_steps and res["config"]["n_lines"] == 2
    for name in ("identities.csv", "survey_lines.csv", "max_likelihood.csv", "survey_line.png", "reproduction.csv"):
        assert (out / name).exists(), name
    rows = {r["metric"]: r for r in res["reproduction"]}
    for name in ("jordan_variance_ratio", "heave_variance_ratio", "chi2_threshold", "fourier_pair_max_abs_err_rel"):
        assert rows[name]["verdict"] == "reproduced", name
    for name in ("crossover_rms_ungated_real_line", "crossover_rms_gated_real_survey"):
        assert rows[name]["verdict"] == "not computed"  # the paper's real data are not available
    assert any("not reproducible" in n for n in res["notes"])


def test_identities_against_independent_closed_forms(result):
    res = result[1]
    cfg, m = res["config"], res["metrics"]
    beta = cfg["speed"] * cfg["sigma_gradient"] / (math.sqrt(2) * cfg["sigma_g"])
    assert m["beta_per_s"] == pytest.approx(beta, rel=1e-14)
    assert m["chi2_threshold"] == pytest.approx(scipy.stats.chi2.ppf(0.99, 4), rel=1e-14)
    for row in res["tables"]["identities"]:
        bt = beta * row["tau_s"]
        k = cfg["sigma_g"] ** 2 * math.exp(-bt) * (1 + bt - bt**2 / 2)
        assert row["K_quadrature_mgal2"] == pytest.approx(k, abs=1e-5 * cfg["sigma_g"] ** 2)
        assert row["K_state_space_mgal2"] == pytest.approx(k, abs=1e-5)
    assert abs(m["jordan_variance_ratio"] - 1) < 1e-7 and abs(m["heave_variance_ratio"] - 1) < 1e-9


def test_rejection_rates_and_gated_smoother(result):
    res = result[1]
    m = res["metrics"]
    assert 0.003 < m["false_alarm_rate"] < 0.03 and m["false_alarm_ci_low"] < m["false_alarm_rate"]
    assert m["detection_rate_epochs"] > 0.5
    lines = res["tables"]["survey_lines"]
    det = sum(r[f"detected_epochs_{p}"] for r in lines for p in "ab")
    man = sum(r[f"manoeuvre_epochs_{p}"] for r in lines for p in "ab")
    assert m["detection_rate_epochs"] == pytest.approx(det / man, rel=1e-12)
    pooled = np.sqrt(np.mean([r["crossover_rms_gated"] ** 2 for r in lines]))
    assert m["crossover_rms_gated"] == pytest.approx(pooled, rel=1e-12)
    assert m["crossover_rms_gated"] < m["crossover_rms_ungated"] and m["rms_error_gated"] < m["rms_error_ungated"]
    assert 0.5 < m["gated_normalised_error_ms"] < 2.0  # the smoother's σ is honest, gaps included


def test_maximum_likelihood_descends(result):
    res = result[1]
    hist = res["tables"]["max_likelihood"]
    assert [r["step"] for r in hist] == list(range(res["config"]["ml_steps"] + 1))
    assert hist[-1]["neg_loglik"] < hist[0]["neg_loglik"]
    assert hist[0]["beta"] == pytest.approx(2.0 * res["metrics"]["beta_per_s"], rel=1e-12)
