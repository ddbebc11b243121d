"""Study ``sail_constellation`` (seed 004 #6/#18) through the CLI, tiny preset: the light-pressure
numbers in plain Python, the uncontrolled Monte-Carlo runs against an exact (matrix-exponential,
first-order-hold) propagation of the HCW equations with the same random draws."""

import dataclasses
import math

import jax
import numpy as np
import pytest
import scipy.linalg

from experiments import sail_constellation as study
from tests.experiments.study_cli import run_quick_study


@pytest.fixture(scope="module")
def study_output(tmp_path_factory):
    out = tmp_path_factory.mktemp("sail")
    return out, run_quick_study("sail_constellation", out, preset="tiny")


def test_config_files_and_scale_claims(study_output):
    out, res = study_output
    tiny = study.STUDY.resolve("tiny")[1]
    assert res["preset"] == "tiny" and res["config"] == dataclasses.asdict(tiny)
    for name in ("keeping.csv", "acceleration_scale.csv", "centre_error.png", "reproduction.csv"):
        assert (out / name).stat().st_size > 0, name
    verdicts = {r["metric"]: r["verdict"] for r in res["reproduction"]}
    for m in ("a_max", "area_pi_r2", "p18_char_acc", "p18_light_pressure", "geo_max_visible_lat_deg"):
        assert verdicts[m] == "reproduced", m
    m = res["metrics"]
    assert m["a_max"] == pytest.approx(2 * 1370 * 7850 / (3e8 * 500), rel=1e-13)
    assert m["a_max_no_reflection"] == pytest.approx(m["a_max"] / 2, rel=1e-13)
    assert m["p18_char_acc"] == pytest.approx(2 * 1370 / 3e8 * 500 / 600, rel=1e-13)
    assert m["geo_max_visible_lat_deg"] == pytest.approx(math.degrees(math.acos(6378.137 / 42164)), rel=1e-12)


def oracle_uncontrolled(cfg):
    """Max |e| over the second half per run, HCW propagated exactly over each control period with the
    disturbance linear between samples (augmented matrix exponential) and the mirror at α = 0."""
    n = math.sqrt(3.986004418e14 / (6378.137e3 + cfg.altitude) ** 3)
    a_max = 2 * cfg.solar_constant * cfg.area / (cfg.light_speed * cfg.mass)
    n_ticks = int(round(cfg.orbits * 2 * math.pi / n / cfg.ts))
    a = np.zeros((6, 6))
    a[:3, 3:] = np.eye(3)
    a[3, 0], a[3, 4], a[4, 3], a[5, 2] = 3 * n * n, 2 * n, -2 * n, -n * n
    m = np.zeros((12, 12))
    m[:6, :6], m[3:6, 6:9], m[6:9, 9:12] = a, np.eye(3), np.eye(3)
    step = scipy.linalg.expm(m * cfg.ts)
    out = []
    for key in jax.random.split(jax.random.PRNGKey(cfg.seed), cfg.mc_runs):
        k_e, k_ph, k_d = jax.random.split(key, 3)
        e0 = jax.random.uniform(k_e, (), minval=-cfg.e0_max, maxval=cfg.e0_max)
        phase = jax.random.uniform(k_ph, (), maxval=2 * np.pi)
        x = np.asarray(study.initial_state(cfg, n, e0, phase))
        d = np.asarray(study.disturbance(cfg, k_d, n_ticks).values) + np.array([0.0, 0.0, a_max])
        e = []
        for k in range(n_ticks):
            e.append(x[1] - 2 * x[3] / n - cfg.y_target)
            slope = (d[k + 1] - d[k]) / cfg.ts if k + 1 < n_ticks else np.zeros(3)
            x = (step @ np.concatenate([x, d[k], slope]))[:6]
        out.append(np.max(np.abs(e[n_ticks // 2 :])))
    return np.array(out)


def test_uncontrolled_runs_against_exact_propagation(study_output):
    _, res = study_output
    cfg = study.STUDY.resolve("tiny")[1]
    ref = oracle_uncontrolled(cfg)
    assert res["metrics"]["e_max_late_mean_m_uncontrolled"] == pytest.approx(ref.mean(), rel=1e-6)


def test_control_keeps_the_centre(study_output):
    m = study_output[1]["metrics"]
    assert m["e_max_late_mean_m_sail"] < 0.1 * m["e_max_late_mean_m_uncontrolled"]
    assert m["e_max_late_mean_m_sail"] < study.STUDY.resolve("tiny")[1].keep_bound
