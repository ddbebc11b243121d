"""The noisy_pid_mc study through the CLI (quick preset, sizes cut by --set): the config that ran is the
one recorded, the closed-form gains and the engine-vs-simulate oracle reproduce, and the noise-free ITAE
matches the continuous-time loop computed by SciPy."""

import numpy as np
import pytest
import scipy.signal

from tests.experiments.study_cli import run_quick_study


@pytest.fixture(scope="module")
def study_output(tmp_path_factory):
    out = tmp_path_factory.mktemp("npm")
    return out, run_quick_study(
        "noisy_pid_mc", out, "--set", "runs=300", "--set", "t_final=3.0", "--set", "kp_sweep=[0.4, 1.2, 3]"
    )


def test_quick_preset_and_overrides_are_what_ran(study_output):
    out, res = study_output
    cfg, m = res["config"], res["metrics"]
    assert res["preset"] == "quick" and "quick" not in cfg
    assert cfg["runs"] == 300 and cfg["t_final"] == 3.0 and cfg["dt"] == 5e-3  # --set, --set, preset
    assert m["runs"] == 300 and res["tables"]["nominal"][0]["runs"] == 300
    assert [r["kp"] for r in res["tables"]["kp_sweep"]] == pytest.approx([0.4, 0.8, 1.2], rel=1e-12)
    assert all(r["runs"] == 300 for r in res["tables"]["kp_sweep"])
    assert (out / "distribution_nominal.png").exists() and (out / "sweep_itae.png").exists()


def test_claims_and_invariants(study_output):
    _, res = study_output
    m = res["metrics"]
    rows = {r["metric"]: r for r in res["reproduction"]}
    assert set(rows) == {"kp_nominal", "ki_nominal", "engine_vs_simulate_itae_rel_diff", "engine_noise_free_itae_std"}
    assert all(r["verdict"] == "reproduced" and r["source"] for r in rows.values())
    assert m["p_overshoot_exceeded_wilson_low"] <= m["p_overshoot_exceeded"] <= m["p_overshoot_exceeded_wilson_high"]
    assert 0 < m["itae_p50"] <= m["itae_p95"] and m["overshoot_mean"] > 0
    assert m["best_kp_by_mean_itae"] in (0.4, 0.8, 1.2)


def test_noise_free_itae_matches_the_continuous_loop(study_output):
    """The sampled PI at 5 ms against the continuous loop (s+4)³ of the same gains (SciPy): O(ts) apart."""
    _, res = study_output
    cfg, m = res["config"], res["metrics"]
    kp, ki = m["kp_nominal"], m["ki_nominal"]
    a = cfg["T1"] * cfg["T2"]
    den = [a, cfg["T1"] + cfg["T2"], 1.0 + cfg["K"] * kp, cfg["K"] * ki]
    t = np.linspace(0.0, cfg["t_final"], 30001)
    _, y = scipy.signal.step(([cfg["K"] * kp, cfg["K"] * ki], den), T=t)
    itae = np.trapezoid(t * np.abs(1.0 - y), t)
    assert m["deterministic_itae"] == pytest.approx(itae, rel=0.05)
