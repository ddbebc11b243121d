"""Study ``dual_mode_integrators`` (seed 004 #31) through the CLI, tiny preset: files and verdicts,
the LQR set against the Riccati equation (NumPy), the designs against constraints (7), the Monte-Carlo
summary against its own table."""

import dataclasses

import numpy as np
import pytest

from experiments.dual_mode_integrators import STUDY
from tests.experiments.study_cli import run_quick_study


@pytest.fixture(scope="module")
def study_output(tmp_path_factory):
    out = tmp_path_factory.mktemp("dual")
    return out, run_quick_study("dual_mode_integrators", out, preset="tiny")


def _as_json(v):
    return [_as_json(x) for x in v] if isinstance(v, tuple) else v


def test_config_files_and_verdicts(study_output):
    out, res = study_output
    tiny = STUDY.resolve("tiny")[1]
    assert res["config"] == {k: _as_json(v) for k, v in dataclasses.asdict(tiny).items()}
    for name in ("designs.csv", "monte_carlo.csv", "tuning.png", "fig1_norm_and_input.png"):
        assert (out / name).stat().st_size > 0, name
    verdicts = {r["metric"]: r["verdict"] for r in res["reproduction"]}
    assert all(v == "reproduced" for v in verdicts.values()), verdicts


def test_linear_mode_against_riccati(study_output):
    m = study_output[1]["metrics"]
    k = np.array([m["lqr_k1"], m["lqr_k2"], m["lqr_k3"]])
    a, b = np.eye(3, k=1), np.array([[0.0], [0.0], [1.0]])
    # triple integrator, Q = I, R = 1: K = [1, 1 + √2, 1 + √2] (closed form)
    np.testing.assert_allclose(k, [1.0, 1 + np.sqrt(2), 1 + np.sqrt(2)], rtol=1e-10)
    # c = (u_m − d_m)²/(K P⁻¹ Kᵀ) with the closed-form P (checked against the CARE residual)
    s = 1 + np.sqrt(2)
    p = np.array([[s, s, 1.0], [s, 2 * s, s], [1.0, s, s]])
    np.testing.assert_allclose(a.T @ p + p @ a - p @ b @ b.T @ p + np.eye(3), 0.0, atol=1e-12)
    np.testing.assert_allclose((b.T @ p)[0], k, rtol=1e-10)
    assert m["set_level"] == pytest.approx(0.8**2 / (k @ np.linalg.solve(p, k)), rel=1e-10)


def test_designs_and_monte_carlo_table(study_output):
    res = study_output[1]
    m, tiny = res["metrics"], STUDY.resolve("tiny")[1]
    for row in res["tables"]["designs"]:
        assert row["k3"] * row["L3"] == pytest.approx(tiny.u_m - tiny.d_m, rel=1e-12)
        assert tiny.f * row["k2"] * row["L2"] == pytest.approx(row["L3"], rel=1e-12)
        assert tiny.f * row["k1"] * row["L1"] == pytest.approx(row["L2"], rel=1e-12)
        assert tiny.wo_lo <= row["omega_o"] <= tiny.wo_hi
    rows = res["tables"]["monte_carlo"]
    assert len(rows) == tiny.n_mc
    diff = np.array([r["ts_nsf_s"] - r["ts_dual_s"] for r in rows])
    assert m["mc_speedup_mean_s"] == pytest.approx(diff.mean(), rel=1e-12)
    half = 1.96 * diff.std(ddof=1) / np.sqrt(len(diff))
    assert m["mc_speedup_ci95_lo_s"] == pytest.approx(diff.mean() - half, rel=1e-12)
    assert all(0 <= r["ts_dual_s"] <= tiny.t_final for r in rows)
    assert m["tune_gradient_smooth_s"] < m["tune_hand_smooth_s"]
