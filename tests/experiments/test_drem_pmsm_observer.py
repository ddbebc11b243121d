"""The drem_pmsm_observer study through the CLI (tiny preset): files, the claims against their metrics,
the tables against each other."""

import numpy as np
import pytest

from experiments.drem_pmsm_observer import STUDY
from tests.experiments.study_cli import recorded_config, run_quick_study


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    out = tmp_path_factory.mktemp("drem")
    return out, run_quick_study("drem_pmsm_observer", out, preset="tiny")


def test_files_config_and_claims(result):
    out, res = result
    _, cfg = STUDY.resolve("tiny", [])
    assert res["config"] == recorded_config(cfg)
    for name in ("drives.csv", "designs.csv", "observers.png", "reproduction.csv"):
        assert (out / name).stat().st_size > 0, name
    m = res["metrics"]
    verdict = {r["metric"]: r["verdict"] for r in res["reproduction"]}
    assert (verdict["monotone_violation"] == "reproduced") == (m["monotone_violation"] <= 1e-6)
    assert (verdict["rotating_tuned_gamma_final_flux_err_pct"] == "reproduced") == (
        m["rotating_tuned_gamma_final_flux_err_pct"] <= 1.0
    )
    for key in ("motor", "sensors", "drive", "observer", "ekf"):
        assert res["assumptions"][key]["why"]


def test_excitation_orders_the_drives(result):
    """Δ is a product of 7 regressor entries that scale with the speed: rotating ≫ slow ≫ standstill."""
    rows = {r["drive"]: r for r in result[1]["tables"]["drives"]}
    assert rows["rotating"]["delta_rms"] > 1e3 * rows["slow"]["delta_rms"] > 1e6 * rows["standstill"]["delta_rms"]
    m = result[1]["metrics"]
    assert m["standstill_over_rotating_delta_rms"] == pytest.approx(
        rows["standstill"]["delta_rms"] / rows["rotating"]["delta_rms"], rel=1e-12
    )
    # the rotor angle is not observable at standstill: neither observer finds it
    assert rows["standstill"]["drem_final_angle_err_deg"] > 10 and rows["standstill"]["ekf_final_angle_err_deg"] > 10


def test_designs_table(result):
    rows = {r["design"]: r for r in result[1]["tables"]["designs"]}
    assert set(rows) == {"hand", "gradient", "pso"}
    m = result[1]["metrics"]
    assert m["gradient_over_hand_itse"] == pytest.approx(
        rows["gradient"]["itse_s2"] / rows["hand"]["itse_s2"], rel=1e-12
    )
    assert all(np.isfinite(r["itse_s2"]) and r["itse_s2"] > 0 for r in rows.values())
