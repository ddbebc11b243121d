"""Study auv_formation: the paper's study 1 numbers (seed 002) from one exact-pose rollout each."""

import jax
import numpy as np
import pytest

import experiments.auv_formation as af


@pytest.fixture(scope="module")
def paper_runs():
    cfg = af.Config()
    plant = af.true_plant(cfg)
    key = jax.random.PRNGKey(0)
    metrics_of = jax.jit(lambda loop: af.run_metrics(cfg, loop, key))
    return cfg, {mode: {k: float(v) for k, v in metrics_of(af.build_loop(cfg, plant, mode=mode)).items()}
                 for mode in ("kalman", "hold")}


def test_paper_reproduction(paper_runs):
    cfg, runs = paper_runs
    m = runs["kalman"]
    # 7.8 m at the follower's start: target (1.5 + 1.2·4, −6, 1.2) m, follower (−1.5, −6, 1.2) m
    np.testing.assert_allclose(m["err0_m"], 1.5 + 1.2 * cfg.t_follower_start + 1.5, rtol=1e-9)
    # paper: below 0.2 m by t = 28 s; we measure ≈ 29 s (README: documented difference)
    assert 26.0 <= m["t_to_0p2m_s"] <= 30.5
    # paper's steady-state bands over cfg.ss_window
    assert m["ss_err_x_m"] <= 0.02 and m["ss_err_y_m"] <= 0.002 and m["ss_err_z_m"] <= 0.01
    # paper: relative velocity swings from +1.2 to about −1.1 m/s
    assert -1.3 <= m["rel_vel_x_min_mps"] <= -0.8
    # paper: ≈ 6 s of bad estimates while the zero-filled 51-frame window fills (from t = 0)
    assert 5.0 <= cfg.t_follower_start + m["startup_est_settled_s"] <= 7.0
    # the t = 32 s manoeuvre disturbs the formation, then it recovers
    assert m["t32_peak_err_m"] > 0.05 and m["t32_est_recovery_s"] < 10.0


def test_prediction_between_frames_matters(paper_runs):
    """The paper's claim: without prediction between frames the steady-state error is far larger."""
    _, runs = paper_runs
    assert runs["hold"]["ss_err_m"] > 10.0 * runs["kalman"]["ss_err_m"]
    assert runs["hold"]["ss_err_x_m"] > 0.02  # outside the paper's x band
