"""Study ``gyro_carousel_heading`` through the CLI (tiny preset) against independent computations:
the closed form of every Table 1 cell, the Monte-Carlo RMS against it, and the design against the
analytic best rotation rate and the target."""

from __future__ import annotations

import math

import numpy as np
import pytest

from experiments.gyro_carousel_heading import STUDY
from tests.experiments.study_cli import run_quick_study

OMEGA_E = 7.292115e-5  # rad/s


@pytest.fixture(scope="module")
def study_output(tmp_path_factory):
    out = tmp_path_factory.mktemp("carousel")
    return out, run_quick_study("gyro_carousel_heading", out, preset="tiny")


def test_config_files_and_claims(study_output):
    out, res = study_output
    cfg = STUDY.resolve("tiny")[1]
    assert res["preset"] == "tiny" and res["config"]["runs"] == cfg.runs == 40
    assert res["config"]["durations_min"] == list(cfg.durations_min)
    for name in ("table1.png", "design.png", "table1.csv", "design.csv", "reproduction.csv"):
        assert (out / name).stat().st_size > 0, name
    verdicts = {r["metric"]: r["verdict"] for r in res["reproduction"]}
    assert len([m for m in verdicts if m.startswith("rms_deg_")]) == 25
    # tiny runs T = 1 and 10 min only: the other rows are "not computed", not silently passed
    assert verdicts["rms_deg_N0p001_T60"] == "not computed"
    assert verdicts["rms_deg_N0p001_T10"] != "not computed"
    for metric in ("design_time_over_grid", "nees_linear_cells_in_chi2_band"):
        assert verdicts[metric] == "reproduced", metric


def test_table_cells_against_the_closed_form(study_output):
    _, res = study_output
    cfg = STUDY.resolve("tiny")[1]
    rows = res["tables"]["table1"]
    assert len(rows) == len(cfg.durations_min) * (len(cfg.noise_densities) + 1)
    lat = math.radians(cfg.latitude_deg)
    for r in rows:
        n_rad = math.radians(r["N_deg_s_sqrtHz"])
        closed = math.degrees(n_rad * math.sqrt(2 / (r["T_min"] * 60)) / (OMEGA_E * math.cos(lat)))
        assert r["closed_form_deg"] == pytest.approx(closed, rel=1e-12)
        assert r["ci95_low"] < r["rms_deg"] < r["ci95_high"]
        if closed < 10:  # linear regime: 40 runs give an RMS within ≈ 3 standard errors (11 % each)
            assert r["rms_deg"] == pytest.approx(closed, rel=0.35), r
    # the header as printed (0.033) gives errors far beyond the column's values
    assert res["metrics"]["header_as_printed_rms_over_paper_min"] > 2.5


def test_design_meets_the_target_at_the_analytic_best_rate(study_output):
    _, res = study_output
    cfg = STUDY.resolve("tiny")[1]
    m = res["metrics"]
    assert m["design_budget_deg"] == pytest.approx(cfg.target_deg, rel=1e-6)
    lat = math.radians(cfg.latitude_deg)
    omega_h = OMEGA_E * math.cos(lat)
    k, eps, n = math.radians(cfg.rate_random_walk), cfg.table_rate_error, math.radians(cfg.design_noise)
    T = m["design_time_min"] * 60
    best = (16 * k**2 / (eps**2 * T**3 * omega_h**2)) ** 0.25
    assert math.radians(m["design_rate_deg_s"]) == pytest.approx(best, rel=1e-6)
    # σ² = (2N²/T + 4K²/(TΩ²))/Ω_H² + ε²(2Ω²T² + 1)/8 at the design equals the target² (independent formula)
    w = best
    var = (2 * n**2 / T + 4 * k**2 / (T * w**2)) / omega_h**2 + eps**2 * (2 * w**2 * T**2 + 1) / 8
    assert math.degrees(math.sqrt(var)) == pytest.approx(cfg.target_deg, rel=1e-6)
    assert m["design_time_min"] > m["design_white_only_time_min"]
    newton = res["tables"]["design_newton"]
    assert abs(newton[-1]["log_sigma_over_target"]) < 1e-8
    mc = next(r for r in res["tables"]["design"] if r["method"].startswith("Monte Carlo"))
    assert mc["ci95_low"] < mc["budget_deg"] < mc["ci95_high"]
    assert np.isfinite(m["design_mc_over_budget"])
