"""The trms_lqr_tuning study through the CLI in quick mode, as CI runs it."""

import json
import math

import pytest

from tests.experiments.study_cli import run_quick_study

REQUIRED = ("loss_gradient", "loss_pso", "loss_random", "sims_gradient", "sims_pso", "wall_gradient_s",
            "wall_pso_s", "mc_loss_p95_gradient", "mc_loss_p95_pso")


@pytest.fixture(scope="module")
def study_output(tmp_path_factory):
    out = tmp_path_factory.mktemp("trms")
    run_quick_study("trms_lqr_tuning", out)
    return out


@pytest.mark.slow
def test_metrics_assumptions_and_outputs(study_output):
    res = json.loads((study_output / "results.json").read_text())
    m = res["metrics"]
    for key in REQUIRED:
        assert isinstance(m[key], (int, float)) and math.isfinite(m[key]), key
    cfg = res["tables"]["effective_config"][0]
    budget = cfg["pso_particles"] * cfg["pso_iters"]
    assert m["sims_pso"] == budget and m["sims_random"] == budget and m["sims_pyswarms"] == budget
    assert m["sims_gradient"] == cfg["gradient_steps"]
    # every tuner improved on Bryson's-rule start point, and the gradient tuner descended from it
    for name in ("gradient", "pso", "pyswarms", "random"):
        assert m[f"loss_{name}"] < m["loss_start"], name
    designs = {row["design"]: row for row in res["tables"]["designs"]}
    assert designs["gradient"]["loss"] == pytest.approx(m["loss_gradient"], rel=1e-9)
    assert designs["pso"]["loss"] == pytest.approx(m["loss_pso"], rel=1e-9)
    for name in ("gradient", "pso"):
        assert m[f"mc_loss_p95_{name}"] >= m[f"mc_loss_median_{name}"] > 0
    for key in ("parameter_set", "u_max", "references", "sensor_noise", "loss", "pso", "monte_carlo"):
        assert res["assumptions"][key]["why"], key
    for png in ("convergence", "responses", "monte_carlo"):
        assert (study_output / f"{png}.png").stat().st_size > 10_000
    assert (study_output / "monte_carlo_samples.csv").exists()


@pytest.mark.slow
def test_ppo_baseline_row(study_output):
    """The brax PPO baseline ran with its stated budget and was scored with the study's loss."""
    pytest.importorskip("brax")
    res = json.loads((study_output / "results.json").read_text())
    m, cfg = res["metrics"], res["tables"]["effective_config"][0]
    n_ticks = round(cfg["t_final"] / cfg["ts"])
    assert m["env_steps_rl_ppo"] >= cfg["ppo_timesteps"]
    assert m["sims_rl_ppo"] == pytest.approx(m["env_steps_rl_ppo"] / n_ticks)
    assert m["wall_rl_ppo_s"] > 0
    for key in ("loss_rl_ppo", "loss_exact_friction_rl_ppo"):
        assert math.isfinite(m[key]) and m[key] > 0, key
    # the env's rewards along the policy rollout sum to minus the study's loss of the replayed inputs
    assert m["return_rl_ppo"] == pytest.approx(-m["loss_rl_ppo"], rel=1e-9)
    row = next(r for r in res["tables"]["tuners"] if r["tuner"] == "brax_ppo")
    assert row["best_loss"] == m["loss_rl_ppo"] and row["sims"] == m["sims_rl_ppo"]
    design = next(r for r in res["tables"]["designs"] if r["design"] == "brax_ppo")
    # the loss is the study's: its terms recombine with the scenario's weights (no stability term)
    total = design["itae"] + cfg["rho_energy"] * design["energy"] + cfg["kappa_saturation"] * design["saturation"]
    assert design["loss"] == pytest.approx(total, rel=1e-12)
    assert design["saturation"] == 0.0  # actions are mapped inside ±u_max
    assert res["assumptions"]["ppo"]["why"]
