"""The fuzzy_pid_tuning study through the CLI (quick mode): equal budgets, feasible tuned
controllers that beat the paper's and the linear one on the same loss, tuned fuzzy systems."""

import pytest

from tests.experiments.study_cli import run_quick_study


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    out = tmp_path_factory.mktemp("fpt")
    return out, run_quick_study("fuzzy_pid_tuning", out)


@pytest.mark.slow
def test_methods_share_the_budget_and_beat_the_references(results):
    out, res = results
    m = res["metrics"]
    for key in ("tuned_loss_gradient", "tuned_loss_pso", "tuned_loss_paper", "sims_gradient", "sims_pso"):
        assert key in m
    assert m["sims_gradient"] == m["sims_pso"] == m["sims_grid"] == m["budget_evals"] * m["operating_points"]
    rows = {r["method"]: r for r in res["tables"]["three_section"]}
    # the paper's controller overshoots 6.4 % at f = 0.3 (the 2 % bound is violated); tuned ones do not
    assert not rows["paper"]["feasible"] and rows["paper"]["overshoot_max_pct"] > 6.0
    for name in ("gradient", "pso", "grid"):
        r = rows[name]
        assert r["feasible"], r
        assert r["overshoot_max_pct"] <= 2.0 + 1e-9 and r["e_ss_over_linear_max"] <= 1.0 + 1e-9
        assert r["u_peak"] <= 1.5 + 1e-9 and 0 < r["a"] < r["c"] and 0 < r["b"] <= r["d"]
        assert r["loss_J"] < rows["linear K_mds"]["loss_J"] < rows["paper"]["loss_J"]
        assert r["settling_max_s"] < rows["linear K_mds"]["settling_max_s"]
    assert (out / "tuning_comparison.png").exists() and (out / "tuned_characteristics.png").exists()


@pytest.mark.slow
def test_fuzzy_systems_tuned_directly(results):
    _, res = results
    m = res["metrics"]
    rows = {r["method"]: r for r in res["tables"]["fuzzy_systems"]}
    # the zero-order Sugeno template starts exactly on the paper's characteristic
    assert m["initial_loss_sugeno"] == pytest.approx(m["tuned_loss_paper"], rel=1e-9)
    for kind in ("mamdani", "sugeno"):
        assert m[f"tuned_loss_{kind}"] < 0.1 * m[f"initial_loss_{kind}"]
        tuned = rows[f"{kind} (gradient)"]
        assert tuned["sims"] == m["fis_steps"] * m["operating_points"]
        assert 0 < tuned["fit_a"] < tuned["fit_c"] and 0 < tuned["fit_b"] <= tuned["fit_d"]
        assert tuned["breakpoints_e"] == sorted(tuned["breakpoints_e"])
    # three sections still describe the tuned characteristics closely
    assert rows["sugeno (gradient)"]["fit_rms"] < 0.05 and rows["mamdani (gradient)"]["fit_rms"] < 0.05
