"""The trms_lqr_tuning study through the CLI: the tiny preset with a --set override (the config
recorded is the one that ran), equal budgets, consistent tables, the reproduction table and the brax
PPO baseline — all from one run (a study run costs about a minute of compilation)."""

import math

import pytest

from tests.experiments.study_cli import run_quick_study


def _run(out, *settings):
    return run_quick_study("trms_lqr_tuning", out, *[a for kv in settings for a in ("--set", kv)], preset="tiny")


@pytest.fixture(scope="module")
def study_output(tmp_path_factory):
    out = tmp_path_factory.mktemp("trms")
    return out, _run(out, "gradient_steps=3", "ppo_timesteps=51200")  # one PPO training step


def test_config_is_what_ran_and_budgets_are_equal(study_output):
    out, res = study_output
    cfg, m = res["config"], res["metrics"]
    assert res["preset"] == "tiny" and "quick" not in cfg
    assert cfg["t_final"] == 2.0 and cfg["search_seeds"] == 1 and not cfg["measure_gradient_cost"]  # --set, preset
    assert m["sims_pso"] == m["sims_random"] == m["sims_pyswarms"] == 4 * 2 and m["sims_gradient"] == 3
    assert math.isnan(float(m["gradient_eval_cost_in_loss_evals"]))  # JSON writes NaN as "nan"
    assert [r["seed"] for r in res["tables"]["search_seeds"]] == [0, 0, 0]
    for png in ("convergence", "responses_pitch", "responses_yaw", "mc_bands"):
        assert (out / f"{png}.png").stat().st_size > 10_000


def test_tables_agree_and_claims_are_checked(study_output):
    _, res = study_output
    m = res["metrics"]
    designs = {row["design"]: row for row in res["tables"]["designs"]}
    for name in ("gradient", "pso", "pyswarms", "random"):
        assert designs[name]["loss"] == pytest.approx(m[f"loss_{name}"], rel=1e-9), name
    # Adam from Bryson's rule keeps its best point: never above the start
    assert m["loss_gradient"] <= m["loss_start"] == designs["bryson_start"]["loss"]
    total = (
        designs["gradient"]["itae"]
        + 0.01 * designs["gradient"]["energy"]
        + 10.0 * designs["gradient"]["saturation"]
        + designs["gradient"]["stability_penalty"]
    )
    assert designs["gradient"]["loss"] == pytest.approx(total, rel=1e-12)
    mc_rows = {r["design"]: r for r in res["tables"]["monte_carlo"]}
    for name in ("gradient", "pso"):
        assert mc_rows[name]["runs"] == 4
        assert m[f"mc_loss_p95_{name}"] >= m[f"mc_loss_median_{name}"] > 0 and m[f"mc_nonfinite_{name}"] == 0
    rows = {r["metric"]: r for r in res["reproduction"]}
    assert set(rows) == {"gradient_vs_start_loss_ratio", "gradient_vs_pso_loss_ratio"}
    assert rows["gradient_vs_start_loss_ratio"]["verdict"] == "reproduced"
    assert all(r["verdict"] in ("reproduced", "differs") and r["source"] for r in rows.values())
    for key in ("parameter_set", "u_max", "references", "sensor_noise", "loss", "pso", "monte_carlo"):
        assert res["assumptions"][key]["why"], key


def test_ppo_baseline_row(study_output):
    """The brax PPO baseline ran with its stated budget and was scored with the study's loss."""
    _, res = study_output
    m, cfg = res["metrics"], res["config"]
    n_ticks = round(cfg["t_final"] / cfg["ts"])
    assert m["env_steps_rl_ppo"] == cfg["ppo_timesteps"] == 51_200  # 64 × 20 × 8 × 5: one whole step
    assert m["sims_rl_ppo"] == pytest.approx(m["env_steps_rl_ppo"] / n_ticks)
    for key in ("loss_rl_ppo", "loss_exact_friction_rl_ppo"):
        assert math.isfinite(m[key]) and m[key] > 0, key
    # the env's rewards along the policy rollout sum to minus the study's loss of the replayed inputs
    assert m["return_rl_ppo"] == pytest.approx(-m["loss_rl_ppo"], rel=1e-9)
    row = next(r for r in res["tables"]["tuners"] if r["tuner"] == "brax_ppo")
    assert row["best_loss"] == m["loss_rl_ppo"] and row["sims"] == m["sims_rl_ppo"]
    design = next(r for r in res["tables"]["designs"] if r["design"] == "brax_ppo")
    total = design["itae"] + cfg["rho_energy"] * design["energy"] + cfg["kappa_saturation"] * design["saturation"]
    assert design["loss"] == pytest.approx(total, rel=1e-12)
    assert design["saturation"] == 0.0  # actions are mapped inside ±u_max
