"""The gravity_map_slam study through the CLI (tiny preset): files, claims against their metrics, the
loop-closure step against the geometry, the NEES band against SciPy's χ² quantiles, and the study's
Monte Carlo against one run of the step-by-step NumPy EKF-SLAM of the kernel test."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.stats

from experiments.gravity_map_slam import STUDY, commands, landmarks, monte_carlo_fn, start_pose
from tests.experiments.study_cli import recorded_config, run_quick_study


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    out = tmp_path_factory.mktemp("slam")
    return out, run_quick_study("gravity_map_slam", out, preset="tiny")


def test_files_config_and_claims(result):
    out, res = result
    _, cfg = STUDY.resolve("tiny", [])
    assert res["config"] == recorded_config(cfg)
    for name in ("variants.csv", "slam.png", "reproduction.csv"):
        assert (out / name).stat().st_size > 0, name
    m = res["metrics"]
    verdict = {r["metric"]: r["verdict"] for r in res["reproduction"]}
    sharp = all(m[f"{v}_closure_sigma_ratio"] <= cfg.closure_drop_max for v in ("same", "reverse"))
    assert m["closure_drop_sharp"] == float(sharp)
    assert (verdict["closure_drop_sharp"] == "reproduced") == sharp
    ratio = m["reverse_sigma_lap2_mean_m"] / m["reverse_sigma_lap1_mean_m"]
    assert m["reverse_lap2_over_lap1_sigma"] == pytest.approx(ratio, rel=1e-12)
    assert (verdict["reverse_lap2_over_lap1_sigma"] == "reproduced") == (ratio <= 1.0)
    for key in ("track", "landmarks", "noise", "sharp_drop"):
        assert res["assumptions"][key]["why"]


def test_closure_time_matches_the_geometry(result):
    """Landmark 0 (at 45°, radius 14 m) comes back into the 7 m range when the track angle φ reaches
    45° − arccos((R² + ρ² − r²)/(2Rρ)) on lap 2's approach, i.e. at t = (360° + φ − start)·R/v."""
    _, res = result
    _, cfg = STUDY.resolve("tiny", [])
    R, rho, r = cfg.radius, cfg.landmark_radius, cfg.max_range
    phi = 45.0 - np.degrees(np.arccos((R * R + rho * rho - r * r) / (2 * R * rho)))
    t = np.radians(360.0 + phi - cfg.start_deg) * R / cfg.speed
    for v in ("same", "reverse"):
        assert abs(res["metrics"][f"{v}_closure_step_s"] - t) <= 2 * cfg.dt


def test_nees_band_and_consistency(result):
    _, res = result
    _, cfg = STUDY.resolve("tiny", [])
    lo, hi = scipy.stats.chi2.ppf([0.025, 0.975], 3 * cfg.n_runs) / cfg.n_runs
    assert lo < 3 < hi
    for v in ("same", "reverse"):
        assert res["metrics"][f"{v}_nees_fraction_in_band"] >= 0.9  # consistent over two laps
        assert 2.0 < res["metrics"][f"{v}_nees_mean"] < 4.5


def test_monte_carlo_run_equals_the_numpy_filter():
    """Run 0 of the study's batched program, its odometry and scans re-drawn from the same keys, filtered
    by the NumPy EKF-SLAM of the kernel test: the same pose estimate at the end of lap 1."""
    from tests.estimation import test_ekf_slam as ref

    _, cfg = STUDY.resolve("tiny", [])
    cmds = commands(cfg, "same direction")[:120]
    keys = jax.random.split(jax.random.PRNGKey(5), 2)
    out = jax.tree_util.tree_map(np.asarray, monte_carlo_fn(cfg)(keys, jnp.asarray(cmds)))
    # re-create run 0's noise exactly as monte_carlo_fn draws it
    k0, k1 = jax.random.split(keys[0])
    q = np.array([cfg.sigma_v, np.radians(cfg.sigma_w_deg)])
    rs = np.array([cfg.sigma_range, np.radians(cfg.sigma_bearing_deg)])
    odo, scans, seen = [], [], []
    for u, k in zip(cmds, jax.random.split(k1, len(cmds))):
        ku, kz = jax.random.split(k)
        odo.append(u + q * np.asarray(jax.random.normal(ku, (2,))))
        truth = out["truth"][0, len(odo) - 1]
        d = landmarks(cfg) - truth[:2]
        z = np.stack([np.hypot(d[:, 0], d[:, 1]), ref.wrap(np.arctan2(d[:, 1], d[:, 0]) - truth[2])], 1)
        seen.append(z[:, 0] <= cfg.max_range)
        scans.append(z + rs * np.asarray(jax.random.normal(kz, z.shape)))
    p0 = np.diag([cfg.sigma0_pos, cfg.sigma0_pos, np.radians(cfg.sigma0_heading_deg)]) ** 2
    x, P, _ = ref.numpy_slam(
        start_pose(cfg), p0, np.array(odo), np.array(scans), np.array(seen), cfg.dt, np.diag(q**2), np.diag(rs**2)
    )
    np.testing.assert_allclose(out["mean"][0, -1], x[:3], rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(out["cov"][0, -1], P[:3, :3], rtol=1e-7, atol=1e-14)
