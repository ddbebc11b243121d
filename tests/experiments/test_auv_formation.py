"""Study auv_formation: the paper's study 1 numbers (seed 002) from one exact-pose rollout each."""

import jax
import numpy as np
import pytest

import experiments.auv_formation as af
import jaxsim.problem.auv_formation as afp
from tests.experiments.study_cli import run_quick_study


@pytest.fixture(scope="module")
def paper_runs():
    cfg = af.Config()
    plant = afp.true_plant(cfg)
    key = jax.random.PRNGKey(0)
    metrics_of = jax.jit(lambda loop: afp.run_metrics(cfg, loop, key))
    return cfg, {
        mode: {k: float(v) for k, v in metrics_of(afp.build_loop(cfg, plant, mode=mode)).items()}
        for mode in ("kalman", "hold")
    }


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


def test_tuning_gradient_matches_finite_differences():
    """Reverse-mode gradient of the tuning loss (through predictor, controller and RK4 rollout)
    against central differences, on a short horizon."""
    import dataclasses

    import jax.numpy as jnp

    cfg = dataclasses.replace(af.Config(), tune_t_final=7.0, tune_loss_start=4.0)
    sample = jax.tree_util.tree_map(lambda a: a[0], afp.draw_samples(cfg, 1, 5))
    key = sample.pop("key")
    theta = afp.tuning_space(cfg).init
    loss = jax.jit(lambda th: afp.tuning_loss(cfg, th, sample, key))
    grad = jax.jit(jax.grad(lambda th: afp.tuning_loss(cfg, th, sample, key)))(theta)
    for name, idx, eps in (("lam", 0, 1e-5), ("k_s", 1, 1e-3), ("log10_accel_psd", None, 1e-4)):

        def shifted(d):
            v = theta[name]
            v = v + d if idx is None else v.at[idx].add(d)
            return {**theta, name: v}

        fd = (loss(shifted(eps)) - loss(shifted(-eps))) / (2 * eps)
        g = grad[name] if idx is None else grad[name][idx]
        assert abs(float(g)) > 0
        np.testing.assert_allclose(float(g), float(fd), rtol=1e-4, atol=1e-9 * max(1.0, abs(float(fd))))
    assert jnp.isfinite(loss(theta))


SHORT = {"tune_steps": 2}  # over the tiny preset's 1


@pytest.mark.slow  # a 12 s study run through the CLI: a few compilations
def test_tiny_preset_with_an_override_through_the_cli(tmp_path):
    """``--preset tiny --set …``: the recorded config is the tiny preset plus the override, and it is
    what ran (horizon, Monte-Carlo runs, tuning steps); the reproduction table checks the paper's claims."""
    args = [a for k, v in SHORT.items() for a in ("--set", f"{k}={v}")]
    res = run_quick_study("auv_formation", tmp_path, *args, preset="tiny")
    cfg, m = res["config"], res["metrics"]
    assert res["preset"] == "tiny" and cfg == {**cfg, **SHORT} and cfg["tune_samples"] == 2  # tiny's value
    assert cfg["t_final"] == 12.0 and cfg["ss_window"] == [8.0, 12.0]
    assert m["mc_runs"] == 2 and m["tune_steps"] == 2 and len(res["tables"]["tuning_history"]) == 2
    assert res["tables"]["error_bands"] == []  # its windows start at 32 s, after this 12 s run
    rows = {r["metric"]: r for r in res["reproduction"]}
    assert rows["err0_m"]["verdict"] == "reproduced" and rows["err0_m"]["ours"] == pytest.approx(7.8, rel=1e-9)
    assert {r["verdict"] for r in rows.values()} <= {"reproduced", "differs"}
    assert m["tune_train_cvar_tuned"] <= m["tune_train_cvar_paper"]  # the best evaluated point is kept
