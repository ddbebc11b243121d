"""Study ``zupt_alignment`` through the CLI (tiny preset): files and config, the final RMS of both filters
recomputed by an independent NumPy covariance recursion, and the FLOP table."""

from __future__ import annotations

import math

import numpy as np
import pytest

from experiments.zupt_alignment import GRADES, STUDY
from jaxsim.inertial import zupt
from tests.experiments.study_cli import run_quick_study


@pytest.fixture(scope="module")
def study_output(tmp_path_factory):
    out = tmp_path_factory.mktemp("zupt")
    return out, run_quick_study("zupt_alignment", out, preset="tiny")


def test_config_files_and_computation(study_output):
    out, res = study_output
    cfg = STUDY.resolve("tiny")[1]
    assert res["preset"] == "tiny" and res["config"]["duration"] == cfg.duration
    for name in ("accuracy.csv", "computation.csv", "rms_vs_time.png", "reproduction.csv"):
        assert (out / name).stat().st_size > 0, name
    comp = {r["filter"]: r for r in res["tables"]["computation"]}
    assert comp["15-state"]["dense_flops_per_step"] == zupt.dense_flops(15, 6)
    assert comp["9-state"]["dense_flops_per_step"] == zupt.dense_flops(9, 3)
    assert res["metrics"]["flop_saving_dense"] == pytest.approx(1 - zupt.dense_flops(9, 3) / zupt.dense_flops(15, 6))
    assert comp["9-state"]["time_per_step_us"] > 0 and comp["15-state"]["time_per_step_us"] > 0


def test_final_rms_against_numpy_recursion(study_output):
    """The 9-state filter's final σ (azimuth, tilts) by a NumPy Kalman covariance recursion with the
    discrete matrices from SciPy's expm (Van Loan), independent of the kernel's scan."""
    import scipy.linalg

    _, res = study_output
    cfg = STUDY.resolve("tiny")[1]
    grade = cfg.grades[0]
    ng, na, eps, da = GRADES[grade]
    deg, g = math.pi / 180, zupt.GRAVITY
    ng, na, eps, da = ng * deg, na * g, eps * deg / 3600, da * g
    lat, U = math.radians(cfg.latitude_deg), zupt.EARTH_RATE
    a = np.zeros((9, 9))
    s, c = U * math.sin(lat), U * math.cos(lat)
    a[:3, :3] = [[0, s, -c], [-s, 0, 0], [c, 0, 0]]
    a[:3, 3:6] = np.eye(3)
    qc = np.zeros((9, 9))
    qc[:3, :3] = np.eye(3) * ng**2
    vl = scipy.linalg.expm(np.block([[-a, qc], [np.zeros((9, 9)), a.T]]) * cfg.dt)
    F = vl[9:, 9:].T
    Q = F @ vl[:9, 9:]
    H = np.zeros((3, 9))
    H[0, 1], H[1, 0] = -g, g
    H[:, 6:] = np.eye(3)
    R = np.eye(3) * na**2 / cfg.dt
    att = np.array([cfg.tilt0_arcmin / 60 * deg, cfg.tilt0_arcmin / 60 * deg, cfg.azimuth0_deg * deg])
    P = np.diag(np.concatenate([att**2, np.full(3, eps**2), np.full(3, da**2)]))
    for _ in range(int(round(cfg.duration / cfg.dt))):
        S = H @ P @ H.T + R
        K = P @ H.T @ np.linalg.inv(S)
        post = P - K @ S @ K.T
        P = F @ post @ F.T + Q
    sig = np.sqrt(np.diag(post)[:3]) / (deg / 60)
    rows = {r["channel"]: r for r in res["tables"]["accuracy"] if r["grade"] == grade}
    for j, ch in enumerate(("tilt_east", "tilt_north", "azimuth")):
        assert rows[ch]["rms_final_9_arcmin"] == pytest.approx(sig[j], rel=1e-6), ch
        assert rows[ch]["rel_diff_final"] < 0.01  # the 15-state filter ends within 1 %
