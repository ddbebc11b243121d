"""The smo_fault study through the CLI (quick mode)."""

import pytest

from tests.experiments.study_cli import run_quick_study

pytestmark = pytest.mark.slow  # a quick study run: about a minute of CPU


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    out = tmp_path_factory.mktemp("smo")
    return out, run_quick_study("smo_fault", out)


def test_contracted_keys_files_and_assumptions(result):
    out, res = result
    m = res["metrics"]
    for key in ("ident_err_rel_median", "ident_err_rel_p99", "ident_err_rel_max_after_3s"):
        assert isinstance(m[key], float)
    for key in ("drive_equations", "arm_coupling", "sensors", "sample_period", "width", "pid"):
        assert res["assumptions"][key]["why"]
    for name in ("integration.csv", "monte_carlo.csv", "tuning_history.csv", "identification.png", "monte_carlo.png"):
        assert (out / name).exists()


def test_noise_free_identification_meets_the_paper_and_the_bias_theory(result):
    m = result[1]["metrics"]
    assert m["ident_err_rel_median"] <= m["paper_claim_rel"] and m["ident_err_rel_p99"] <= m["paper_claim_rel"]
    # the error floor is the sliding-mode bias 1/(1 + k1/k3) = 0.1 %
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
    assert hist[-1]["loss_rms_rel"] < hist[0]["loss_rms_rel"]
    # tuned through the smooth surrogate, evaluated with exact switching on fresh noise
    assert m["noisy_tuned_ident_err_rel_median"] < 0.5 * m["noisy_paper_gains_ident_err_rel_median"]
