"""Study ``wind_estimation`` (seed 004 #11, part 3) through the CLI, tiny preset: exactness with ideal
sensors, the raw estimate's Monte-Carlo RMS against the sensor noise propagated by NumPy central
differences, the maximum-likelihood turbulence against the generating values."""

import numpy as np
import pytest

from experiments.wind_estimation import STUDY, flight
from tests.experiments.study_cli import recorded_config, run_quick_study


@pytest.fixture(scope="module")
def study_output(tmp_path_factory):
    out = tmp_path_factory.mktemp("wind")
    return out, run_quick_study("wind_estimation", out, preset="tiny")


def numpy_wind(v_ground, h_dot, pitch, v_air, alpha):
    alpha_k = pitch - np.arcsin(h_dot / v_ground)
    return np.array(
        [
            v_ground * np.cos(pitch - alpha_k) - v_air * np.cos(pitch - alpha),
            v_ground * np.sin(pitch - alpha_k) - v_air * np.sin(pitch - alpha),
        ]
    )


def test_config_files_and_claim(study_output):
    out, res = study_output
    tiny = STUDY.resolve("tiny")[1]
    cfg = recorded_config(tiny)
    assert res["config"] == cfg
    for name in ("ideal_sensors.csv", "accuracy_vs_turbulence.csv", "accuracy_vs_turbulence.png", "reproduction.csv"):
        assert (out / name).stat().st_size > 0, name
    (claim,) = res["reproduction"]
    assert claim["verdict"] == "reproduced" and res["metrics"]["ideal_sensors_max_abs_error"] < 1e-12


def test_raw_estimate_rms_equals_the_propagated_sensor_noise(study_output):
    """The algebraic estimate's error is sensor noise through eqs. (1)–(2): its RMS per component over
    the runs equals √(mean trace(J Σ Jᵀ)/2), J by central differences at the (noise-free) readings of
    the zero-turbulence flight (the wind's effect on J is second order)."""
    _, res = study_output
    cfg = STUDY.resolve("tiny")[1]
    fl = {k: np.asarray(v) for k, v in flight(cfg).items()}
    std = np.asarray(cfg.sensor_std)
    skip = int(round(30.0 / cfg.dt))
    traces = []
    for i in range(skip, len(fl["t"]), 25):
        speed = cfg.w_ref * (fl["h"][i] / cfg.h_ref) ** (1 / 7)
        vg = fl["v"][i] * np.array([np.cos(fl["gamma"][i]), np.sin(fl["gamma"][i])]) + [speed, 0.0]
        x = np.array([np.hypot(*vg), vg[1], fl["pitch"][i], fl["v"][i], fl["alpha"][i]])
        jac = np.stack([(numpy_wind(*(x + h)) - numpy_wind(*(x - h))) / (2e-6) for h in np.eye(5) * 1e-6], axis=1)
        traces.append(np.trace(jac @ np.diag(std**2) @ jac.T))
    predicted = np.sqrt(np.mean(traces) / 2)
    for row in res["tables"]["accuracy_vs_turbulence"]:
        assert row["rms_algebraic_m_s"] == pytest.approx(predicted, rel=0.05)
        assert row["rms_filter_m_s"] < row["rms_algebraic_m_s"]  # the filter removes part of the noise


def test_maximum_likelihood_recovers_the_turbulence(study_output):
    m = study_output[1]["metrics"]
    assert abs(m["ml_tau_z"]) < 3 and abs(m["ml_sigma_z"]) < 3
    assert abs(m["ml_sigma_rel_error"]) < 0.3 and abs(m["ml_tau_rel_error"]) < 0.4
