"""The fuzzy_pid_accuracy study through the CLI (quick preset + a --set override): the paper's eight
steady-state errors, analytic vs simulated over the (g, f, K_g, K_f) grid, figures and assumptions."""

import numpy as np
import pytest

from tests.experiments.study_cli import run_quick_study

PAPER = {  # the paper's values, spec §1.4 (linear astatic f = 0.7 is f/K_mds, the paper's line is lost)
    "ess_static_f0_fuzzy": 0.5556,
    "ess_static_f0_linear": 0.5556,
    "ess_static_f03_fuzzy": 0.8108,
    "ess_static_f03_linear": 0.8889,
    "ess_astatic_f02_fuzzy": 0.16,
    "ess_astatic_f02_linear": 0.16,
    "ess_astatic_f07_fuzzy": 0.4571,
    "ess_astatic_f07_linear": 0.56,
}


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    out = tmp_path_factory.mktemp("fpa")
    return out, run_quick_study("fuzzy_pid_accuracy", out, "--set", "mamdani_fit_steps=80")


def test_config_is_the_quick_preset_with_the_override_and_is_what_ran(results):
    _, res = results
    cfg = res["config"]
    assert res["preset"] == "quick" and cfg["mamdani_fit_steps"] == 80 and "quick" not in cfg
    assert cfg["grid_g"] == [1.5] and cfg["grid_f"] == [0.3, 2.5]  # the quick grid
    assert len(res["tables"]["mamdani_fit_history"]) == 81  # 80 Adam updates, the last point evaluated
    assert len(res["tables"]["steady_state_grid"]) == 2 * 4 * 1 * 2 * 2 * 3


def test_reproduction_table(results):
    _, res = results
    rows = {r["metric"]: r for r in res["reproduction"]}
    assert set(rows) == {"kp_mds_static", "kp_mds_astatic", *PAPER}
    for name, r in rows.items():
        assert r["verdict"] == "reproduced" and r["ours"] == res["metrics"][name] and r["source"], name
    assert rows["ess_static_f03_linear"]["paper"] == 0.89  # the paper's printed value (two decimals)


def test_the_eight_paper_values_analytic_and_simulated(results):
    _, res = results
    m = res["metrics"]
    for key, value in PAPER.items():
        assert round(m[key], 4) == value, key
        assert round(m[key + "_analytic"], 4) == value, key
        assert abs(m[key] - m[key + "_analytic"]) < 1e-9, key
        assert m[f"settling_{key[4:]}"] > 0 and m[f"overshoot_{key[4:]}"] >= 0
    # the linear gains are designed, not typed in
    assert m["kp_mds_static"] == pytest.approx(0.4, rel=1e-12)
    assert m["kp_mds_astatic"] == pytest.approx(1.25, rel=1e-12)
    # the fuzzy controller is faster than the linear one in every case (the paper's claim)
    for case in ("static_f0", "static_f03", "astatic_f02", "astatic_f07"):
        assert m[f"settling_{case}_fuzzy"] < m[f"settling_{case}_linear"]
    rows = res["tables"]["paper_cases"]
    static_f03 = next(r for r in rows if r["plant"] == "static" and r["f"] == 0.3 and r["controller"] == "fuzzy P")
    assert (static_f03["section"], static_f03["equation"]) == (2, "(2)")
    assert static_f03["domain_section1_upper"] == pytest.approx(0.675)
    assert static_f03["domain_section2_upper"] == pytest.approx(1.6)


def test_grid_analytic_equals_simulated_and_missing_steady_states_are_detected(results):
    _, res = results
    rows = res["tables"]["steady_state_grid"]
    assert {r["controller"] for r in rows} == {"linear P", "fuzzy P", "linear PI", "fuzzy PI"}
    assert {r["section"] for r in rows if r["steady_state_analytic"]} >= {1, 2, 3}
    finite = [r for r in rows if r["steady_state_analytic"]]
    none = [r for r in rows if not r["steady_state_analytic"]]
    assert len(finite) >= 20 and len(none) >= 20
    for r in finite:
        assert r["steady_state_simulated"], r
        assert r["relative_error"] <= 1e-6, r
    for r in none:
        assert not r["steady_state_simulated"], r
        assert r["e_analytic"] in ("inf", "-inf")


def test_figures_tables_and_assumptions(results):
    out, res = results
    for name in (
        "fig2_static_characteristic",
        "fig3_fc1_fc2_kmds",
        "fig4_static_transients",
        "fig5_astatic_transients",
        "fig6_pi_astatic",
        "steady_state_grid",
    ):
        assert (out / f"{name}.png").stat().st_size > 10_000, name
    assert (out / "paper_cases.csv").exists() and (out / "steady_state_grid.csv").exists()
    for key in ("fc1_static", "fuzzy_pi", "fig6_scenario", "fig2_mamdani", "disturbance_sign"):
        assert res["assumptions"][key]["why"], key
    m = res["metrics"]
    # Fig. 2: the Mamdani controller's three-section approximation is close to the paper's FC
    fitted = [m[f"fig2_fit_{k}"] for k in "abcd"]
    np.testing.assert_allclose(fitted, [0.75, 0.3, 1.2, 1.0], atol=0.05)
    # Fig. 6: the fuzzy PI settles faster than the maximum-stability linear PI, both without error
    assert m["fig6_settling_fuzzy_pi"] < m["fig6_settling_linear_pi"]
    assert abs(m["fig6_ess_fuzzy_pi"]) < 1e-9 and abs(m["fig6_ess_linear_pi"]) < 1e-9
