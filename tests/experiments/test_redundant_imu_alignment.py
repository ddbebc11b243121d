"""Study ``redundant_imu_alignment`` through the CLI (tiny preset): files and config, table A's bias column
against the first-order closed form (e_E·h) δω / (2U), and the FDI table's intervals and exact probabilities
recomputed with SciPy."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.stats

from experiments.redundant_imu_alignment import STUDY
from tests.experiments.study_cli import run_quick_study

U = 7.292115e-5  # rad/s
PHI = (1 + math.sqrt(5)) / 2


@pytest.fixture(scope="module")
def study_output(tmp_path_factory):
    out = tmp_path_factory.mktemp("redundant_imu")
    return out, run_quick_study("redundant_imu_alignment", out, preset="tiny")


def test_config_files_and_table_a(study_output):
    out, res = study_output
    cfg = STUDY.resolve("tiny")[1]
    assert res["preset"] == "tiny" and res["config"]["runs"] == cfg.runs
    for name in ("table_a.csv", "fdi.csv", "detection.png", "reproduction.csv"):
        assert (out / name).stat().st_size > 0, name
    east = {1: 0.0, 2: PHI, 3: 1.0, 4: -1.0, 5: PHI, 6: 0.0}  # East components before normalisation
    b = cfg.gyro_bias_dph * math.pi / 180 / 3600
    for r in res["tables"]["table_a"]:
        i = int(r["sensor"][3:])
        ref = abs(east[i]) / math.sqrt(1 + PHI**2) * b / (2 * U) * 180 * 60 / math.pi
        assert r["bias_arcmin"] == pytest.approx(ref, rel=2e-3, abs=1e-9), r["sensor"]
    verdicts = {c["metric"]: c["verdict"] for c in res["reproduction"]}
    for k in ("bias_azimuth_dus2_arcmin", "bias_azimuth_dus3_arcmin", "horizontal_error_rss_six_arcmin"):
        assert verdicts[k] == "reproduced", k
    assert res["metrics"]["horizontal_error_rss_six_arcmin"] == pytest.approx(
        cfg.accel_bias / 9.78 * 180 * 60 / math.pi, rel=1e-3
    )


def test_fdi_rows_against_scipy(study_output):
    _, res = study_output
    cfg = STUDY.resolve("tiny")[1]
    rows = res["tables"]["fdi"]
    assert len(rows) == 1 + 6 * sum(b > 0 for b in cfg.bias_sigmas)
    thr = scipy.stats.chi2.isf(cfg.false_alarm, 3)
    for r in rows:
        assert r["runs"] == cfg.runs
        assert r["p_detect_ci95_low"] <= r["p_detect_mc"] <= r["p_detect_ci95_high"]
        if r["bias_sigmas"] > 0:  # a bias b σ on one gyro: ‖p‖²/σ² ~ χ²(3, b²/2)
            assert r["p_detect_exact"] == pytest.approx(scipy.stats.ncx2.sf(thr, 3, r["bias_sigmas"] ** 2 / 2))
    big = [r for r in rows if r["bias_sigmas"] == max(cfg.bias_sigmas)]
    assert np.mean([r["p_isolate_given_detect"] for r in big]) > 0.95
    dus2 = next(r for r in big if r["sensor"] == "DUS2")
    assert dus2["azimuth_rms_after_arcmin"] < 0.5 * dus2["azimuth_rms_before_arcmin"]
