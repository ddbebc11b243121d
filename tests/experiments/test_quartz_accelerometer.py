"""Study ``quartz_accelerometer`` (seed 004 B6) through the CLI, tiny preset: config and files, the
claims' verdicts, the designs' bandwidths against a NumPy resolvent of the ZOH loop's linear model,
the Monte-Carlo intervals around the linear noise prediction."""

import numpy as np
import pytest

from experiments.quartz_accelerometer import STUDY
from jaxsim.control import force_rebalance as fr
from jaxsim.plants import quartz_accelerometer as qa
from tests.experiments.study_cli import recorded_config, run_quick_study


@pytest.fixture(scope="module")
def study_output(tmp_path_factory):
    out = tmp_path_factory.mktemp("quartz")
    return out, run_quick_study("quartz_accelerometer", out, preset="tiny")


def test_config_files_and_verdicts(study_output):
    out, res = study_output
    tiny = STUDY.resolve("tiny")[1]
    cfg = recorded_config(tiny)
    assert res["config"] == cfg
    for name in ("designs.csv", "noise_vs_bits_rate.csv", "bandwidth.png", "noise_vs_bits.png", "comparison.csv"):
        assert (out / name).stat().st_size > 0, name
    verdicts = {r["metric"]: r["verdict"] for r in res["reproduction"]}
    assert len(verdicts) == 5 and all(v == "reproduced" for v in verdicts.values()), verdicts


def test_bandwidth_against_scipy_dlti(study_output):
    res = study_output[1]
    tiny = STUDY.resolve("tiny")[1]
    p = qa.Params()
    sf = float(qa.scale_factor(p))
    for row in res["tables"]["designs"]:
        g = fr.Gains(kp=row["kp"], ki=row["ki"], kd=row["kd"])
        A, B, C, D = fr.closed_loop_matrices(p, g, tiny.dt)
        z = np.exp(2j * np.pi * row["bandwidth_hz"] * tiny.dt)
        h = (C @ np.linalg.solve(z * np.eye(4) - A, B[:, :1]) + D[:, :1])[0, 0] * qa.G0 / sf  # NumPy resolvent
        assert abs(h) == pytest.approx(1 / np.sqrt(2), rel=2e-3), row["design"]


def test_noise_table_intervals(study_output):
    rows = study_output[1]["tables"]["noise_vs_bits_rate"]
    tiny = STUDY.resolve("tiny")[1]
    assert len(rows) == len(tiny.mc_bits) * len(tiny.mc_rates)
    for r in rows:
        assert r["noise_mg_ci_lo"] < r["noise_mg_mean"] < r["noise_mg_ci_hi"]
    top = [r for r in rows if r["adc_bits"] == max(tiny.mc_bits)]
    for r in top:  # fine ADC: the white-quantisation linear prediction lies near the interval
        assert r["noise_mg_ci_lo"] * 0.85 < r["linear_prediction_mg"] < r["noise_mg_ci_hi"] * 1.15
