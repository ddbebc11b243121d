"""Study ``heating_gramians`` (seed 004 #11) through the CLI, tiny preset: gramians against SciPy's
Lyapunov solver, the tuned PI's loss against an exact-ZOH NumPy simulation of the same loop."""

import dataclasses

import numpy as np
import pytest
import scipy.linalg

from experiments.heating_gramians import STUDY
from tests.experiments.study_cli import run_quick_study


@pytest.fixture(scope="module")
def study_output(tmp_path_factory):
    out = tmp_path_factory.mktemp("heating")
    return out, run_quick_study("heating_gramians", out, preset="tiny")


def oracle_loss(cfg, kp, ki, t_out):
    """ITAE + ρ·∫(Q − Q_ss)² of the sampled PI (clamping anti-windup, 0 ≤ Q ≤ Q_max) on the exact
    ZOH discretisation of the scalar room."""
    k, h, m = cfg.envelope, cfg.ventilation, cfg.capacity
    a = -(k + h) / m
    ad = np.exp(a * cfg.ts)
    q_ss = k * (cfg.t_set - cfg.t_out) + h * (cfg.t_set - cfg.t_vent)
    x, z, itae, heat = cfg.t_start, 0.0, 0.0, 0.0
    for i in range(int(round(cfg.t_final / cfg.ts))):
        e = cfg.t_set - x
        v = kp * e + z
        u = min(max(v, 0.0), cfg.q_max)
        itae += i * cfg.ts * abs(e) * cfg.ts
        heat += (u - q_ss) ** 2 * cfg.ts
        pushing = v != u and np.sign(ki * e) == np.sign(v - u)
        z += 0.0 if pushing else cfg.ts * ki * e
        forcing = (u + k * t_out + h * cfg.t_vent) / m
        x = ad * x + (ad - 1.0) / a * forcing
    return itae + cfg.rho * heat


def test_config_files_and_claims(study_output):
    out, res = study_output
    tiny = STUDY.resolve("tiny")[1]
    assert res["preset"] == "tiny"
    assert res["config"] == {**dataclasses.asdict(tiny), "paper_gramians": list(tiny.paper_gramians)}
    for name in ("gramians.csv", "reproduction.csv", "loss_vs_budget.png", "mc_bands.png", "robustness.csv"):
        assert (out / name).stat().st_size > 0, name
    verdicts = {r["metric"]: r["verdict"] for r in res["reproduction"]}
    gram = [m for m in verdicts if m.startswith(("gramian_", "backsolve_"))]
    assert len(gram) == 13 and all(verdicts[m] == "reproduced" for m in gram)
    assert [r["runs"] for r in res["tables"]["robustness"]] == [tiny.mc_runs] * 2


def test_gramians_against_scipy(study_output):
    _, res = study_output
    cfg = STUDY.resolve("tiny")[1]
    k, h, m = cfg.envelope, cfg.ventilation, cfg.capacity
    a = np.array([[-(k + h) / m]])
    for ch, b in zip(("heater", "outdoor", "vent"), (1 / m, k / m, h / m)):
        ref = scipy.linalg.solve_continuous_lyapunov(a, -np.array([[b * b]]))[0, 0]
        for route in ("exact", "lyapunov"):
            assert res["metrics"][f"gramian_{ch}_{route}"] == pytest.approx(ref, rel=1e-12)
        assert res["metrics"][f"gramian_{ch}_impulse"] == pytest.approx(ref, rel=1e-8)


def test_tuned_pi_loss_against_exact_zoh(study_output):
    _, res = study_output
    cfg = STUDY.resolve("tiny")[1]
    for row in res["tables"]["comparison"]:
        assert row["best_loss"] == pytest.approx(oracle_loss(cfg, row["kp"], row["ki"], cfg.t_out), rel=1e-6)
