"""Study ``attitude_algorithms`` through the CLI (tiny preset): the error orders, and the closed-form
drift of every table row recomputed independently in NumPy from the increments' cross products."""

from __future__ import annotations

import math

import numpy as np
import pytest

from experiments.attitude_algorithms import STUDY
from tests.experiments.study_cli import run_quick_study

M = {"first_order": 1, "two_sample_previous": 1, "two_sample": 2, "three_sample": 3}


@pytest.fixture(scope="module")
def study_output(tmp_path_factory):
    out = tmp_path_factory.mktemp("attitude")
    return out, run_quick_study("attitude_algorithms", out, preset="tiny")


def numpy_drift(alpha: float, omega: float, h: float, alg: str) -> float:
    """(coning term of the rule − true coning rotation) per update, from NumPy increments of the y, z
    axes over one update interval starting at t = 0.4 s (the rule's correction is the same for every interval)."""
    m = M[alg]
    t = 0.4 + np.arange(-1, m + 1) * h  # one interval before, for the previous-interval rule
    yz = np.sin(alpha) * np.stack([np.diff(np.cos(omega * t)), np.diff(np.sin(omega * t))], axis=1)
    d = [np.r_[0.0, v] for v in yz]  # the x increments do not enter the x component of a cross product
    if alg == "first_order":
        corr = 0.0
    elif alg == "two_sample_previous":
        corr = np.cross(d[0], d[1])[0] / 12
    elif alg == "two_sample":
        corr = 2 / 3 * np.cross(d[1], d[2])[0]
    else:
        corr = 9 / 20 * np.cross(d[1], d[3])[0] + 27 / 40 * np.cross(d[2], d[3] - d[1])[0]
    lam = omega * h
    true = 0.5 * np.sin(alpha) ** 2 * (m * lam - np.sin(m * lam))
    return (corr - true) / (m * h)


def test_config_files_and_orders(study_output):
    out, res = study_output
    cfg = STUDY.resolve("tiny")[1]
    assert res["preset"] == "tiny" and res["config"]["updates"] == cfg.updates
    for name in ("drift_vs_rate.png", "order_sweep.csv", "paper_setting.csv", "reproduction.csv"):
        assert (out / name).stat().st_size > 0, name
    verdicts = {r["metric"]: r["verdict"] for r in res["reproduction"]}
    for alg in M:
        assert verdicts[f"order_{alg}"] == "reproduced", alg
    m = res["metrics"]
    assert m["order_three_sample"] > m["order_two_sample"] > m["order_first_order"]


def test_rows_against_an_independent_numpy_closed_form(study_output):
    _, res = study_output
    cfg = STUDY.resolve("tiny")[1]
    alpha, omega = math.radians(cfg.cone_half_angle_deg), 2 * math.pi * cfg.cone_frequency_hz
    rows = res["tables"]["order_sweep"]
    assert len(rows) == 4 * len(cfg.sample_rates_hz)
    for r in rows:
        ref = numpy_drift(alpha, omega, 1 / r["sample_rate_hz"], r["algorithm"])
        assert r["closed_form_rad_s"] == pytest.approx(ref, rel=1e-7, abs=1e-18)
        if r["fitted"]:
            assert r["drift_x_rad_s"] == pytest.approx(ref, rel=0.05)
    # the paper setting: first-order error ∝ h² and the ranking of the rules
    assert res["metrics"]["paper_setting_first_order_slope_vs_step"] == pytest.approx(2.0, abs=0.1)
    assert res["metrics"]["paper_setting_ranking_holds"] == 1.0
