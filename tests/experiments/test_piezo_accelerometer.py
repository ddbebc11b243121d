"""Study ``piezo_accelerometer`` (seed 004 #25/#26) through the CLI, tiny preset, against independent
computations: the bench numbers from the component values in plain Python, the Table-1 resonator
fit by SciPy's least_squares, the stepped-sine peak by scipy.signal.freqs."""

import dataclasses
import math

import numpy as np
import pytest
import scipy.optimize
import scipy.signal

from experiments.piezo_accelerometer import STUDY, TABLE1_HZ, TABLE1_V
from tests.experiments.study_cli import run_quick_study


@pytest.fixture(scope="module")
def study_output(tmp_path_factory):
    out = tmp_path_factory.mktemp("piezo")
    return out, run_quick_study("piezo_accelerometer", out, preset="tiny")


def test_config_files_and_verdicts(study_output):
    out, res = study_output
    tiny = STUDY.resolve("tiny")[1]
    assert res["preset"] == "tiny"
    assert res["config"] == {**dataclasses.asdict(tiny), "bench_freqs": list(tiny.bench_freqs)}
    for name in ("bench.csv", "table1.csv", "white_noise_runs.csv", "resonance.png", "bench_response.png"):
        assert (out / name).stat().st_size > 0, name
    assert len(res["tables"]["white_noise_runs"]) == tiny.n_runs
    verdicts = {r["metric"]: r["verdict"] for r in res["reproduction"]}
    assert all(v == "reproduced" for v in verdicts.values()), verdicts


def test_bench_from_component_values(study_output):
    m = study_output[1]["metrics"]
    tau = 1.2e-9 * (5.5e6 * 6e11) / (5.5e6 + 6e11)
    assert m["bench_tau_ms"] == pytest.approx(1e3 * tau, rel=1e-12)
    assert m["bench_fc_hz"] == pytest.approx(1 / (2 * math.pi * tau), rel=1e-12)
    wt = 2 * math.pi * tau
    assert m["bench_mag_10hz"] == pytest.approx(10 * wt / math.hypot(1, 10 * wt), rel=1e-12)
    # the simulated bench sweep recovers the model (RK4 at 0.1 ms, sine fit over whole periods)
    assert m["bench_fit_tau_ms"] == pytest.approx(1e3 * tau, rel=1e-4)
    assert m["bench_fit_kp_mv_per_g"] == pytest.approx(10.0, rel=1e-4)


def test_table_fit_against_scipy_least_squares(study_output):
    m = study_output[1]["metrics"]
    f, v = np.asarray(TABLE1_HZ, float), np.asarray(TABLE1_V, float)

    def resid(th):
        g, fn, q = th
        w, wn = 2 * np.pi * f, 2 * np.pi * fn
        return np.log(np.abs(g * wn**2 / (wn**2 - w**2 + 1j * w * wn / q))) - np.log(v)

    sol = scipy.optimize.least_squares(resid, [0.3, 807.0, 36.0], xtol=1e-14, ftol=1e-14, gtol=1e-14)
    g, fn, q = sol.x
    assert m["table_fit_q"] == pytest.approx(q, rel=1e-5)
    assert m["table_fit_f_r_hz"] == pytest.approx(fn * math.sqrt(1 - 0.5 / q**2), abs=1e-4)
    assert m["table_fit_rms_log"] == pytest.approx(math.sqrt(np.mean(sol.fun**2)), rel=1e-6)
    assert m["table_fit_rms_log"] > 0.2  # the table is not a linear resonance


def test_white_noise_and_stepped_sine(study_output):
    res = study_output[1]
    m, cfg = res["metrics"], STUDY.resolve("tiny")[1]
    runs = [r["f_r_fit_hz"] for r in res["tables"]["white_noise_runs"]]
    assert m["wn_f_r_abs_err_max_hz"] == pytest.approx(max(abs(x - cfg.f_r) for x in runs), rel=1e-12)
    assert m["wn_f_r_abs_err_max_hz"] < 0.1
    fn = cfg.f_r / math.sqrt(1 - 0.5 / cfg.q**2)
    wn = 2 * math.pi * fn
    grid = np.arange(cfg.step_lo, cfg.step_hi + 0.5)
    _, h = scipy.signal.freqs([cfg.gain * wn**2], [1, wn / cfg.q, wn**2], worN=2 * np.pi * grid)
    assert m["stepped_sine_peak_hz"] == grid[np.argmax(np.abs(h))]
