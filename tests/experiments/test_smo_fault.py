"""The smo_fault study through the CLI: the tiny preset (0.3 s after the fault at 1e-4 s) with a --set
override; the config recorded is the one that ran."""

import csv

import pytest

from experiments.smo_fault import STUDY
from tests.experiments.study_cli import run_quick_study

pytestmark = pytest.mark.slow  # a short study run through the CLI: a few compilations

SHORT = {"tune_steps": 2}  # over the tiny preset's 1


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    out = tmp_path_factory.mktemp("smo")
    extra = [a for k, v in SHORT.items() for a in ("--set", f"{k}={v}")]
    return out, run_quick_study("smo_fault", out, *extra, preset="tiny")


def test_config_is_the_quick_preset_with_the_overrides_and_is_what_ran(result):
    out, res = result
    _, expected = STUDY.resolve("tiny", [f"{k}={v}" for k, v in SHORT.items()])
    assert res["preset"] == "tiny" and res["config"] == {**res["config"], **SHORT} and expected.tune_steps == 2
    assert res["config"]["mc_cases"] == list(expected.mc_cases) == ["noise level 2", "parameter spread"]
    integ = res["tables"]["integration"]
    assert [r["step_s"] for r in integ[:3]] == [1e-4, 1e-4, 5e-5]  # sample_period and reference_step_ratio
    assert integ[0]["horizon_s"] == pytest.approx(3.3) and integ[2]["horizon_s"] == pytest.approx(3.2)
    mc = res["tables"]["monte_carlo"]
    assert [(r["case"], r["sample"]) for r in mc] == [(c, i) for c in expected.mc_cases for i in range(2)]
    assert [r["step"] for r in res["tables"]["tuning_history"]] == [0, 1]
    for key in ("drive_equations", "arm_coupling", "sensors", "sample_period", "width", "pid"):
        assert res["assumptions"][key]["why"]
    for name in (
        "integration.csv",
        "monte_carlo.csv",
        "tuning_history.csv",
        "identification.png",
        "monte_carlo.png",
        "tuning.png",
        "reproduction.csv",
    ):
        assert (out / name).exists(), name


def test_reproduction_table_against_the_paper_and_the_bias_theory(result):
    out, res = result
    m = res["metrics"]
    rows = {r["metric"]: r for r in res["reproduction"]}
    assert [r["metric"] for r in csv.DictReader(open(out / "reproduction.csv"))] == list(rows)
    for name in ("ident_err_rel_median", "ident_err_rel_p99", "ident_bias_theory"):
        assert rows[name]["verdict"] == "reproduced" and rows[name]["ours"] == m[name], name
    assert rows["ident_err_rel_p99"]["paper"] == 0.0035 and "line 1931" in rows["ident_err_rel_p99"]["source"]
    # the error floor is the sliding-mode bias 1/(1 + k1/k3) = 0.1 %
    assert m["ident_bias_theory"] == pytest.approx(1 / 1001, rel=1e-15)
    assert 0.5 * m["ident_bias_theory"] < m["ident_err_rel_median"] < 1.5 * m["ident_bias_theory"]
    assert m["ident_err_rel_pre_fault_max"] < 0.01  # no false alarm before the onset


def test_integration_is_stable_and_agrees_with_the_small_step_reference(result):
    m = result[1]["metrics"]
    assert abs(m["reference_ident_err_rel_median"] - m["ident_err_rel_median"]) < 3e-4
    assert abs(m["smooth_ident_err_rel_median"] - m["ident_err_rel_median"]) < 3e-4
    assert m["explicit_rk4_ident_err_rel_max"] > 1e3  # explicit RK4 cannot step over −k3/ε
    assert m["unreachable_gains_rejected"] == 1.0 and m["sliding_k3_min"] < 1e4


def test_monte_carlo_and_tuning(result):
    res = result[1]
    m = res["metrics"]
    assert m["mc_noise_level_2_median"] > 5 * m["ident_err_rel_median"]  # noise is differentiated twice
    assert m["mc_parameter_spread_median"] > m["ident_err_rel_median"]  # the observer keeps the nominal model
    hist = res["tables"]["tuning_history"]
    assert hist[-1]["loss"] < hist[0]["loss"]
    assert hist[0]["k1"] == pytest.approx(1e7, rel=1e-12) and hist[0]["k3"] == pytest.approx(1e4, rel=1e-12)
    assert m["tuned_k1"] == hist[-1]["k1"] or m["tuned_k1"] == hist[0]["k1"]  # the best evaluated point
    # tuned through the smooth surrogate, evaluated with exact switching on fresh noise
    assert m["noisy_tuned_ident_err_rel_median"] < m["noisy_paper_gains_ident_err_rel_median"]
