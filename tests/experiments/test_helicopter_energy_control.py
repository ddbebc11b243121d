"""Study ``helicopter_energy_control`` (seed 004 #15) through the CLI, tiny preset: config and files,
the invariant claims' verdicts, and the hand design's reduced-model energy error against an independent
SciPy (solve_ivp) integration of model (1)–(2) with laws (7)–(10) written in NumPy."""

import numpy as np
import pytest
import scipy.integrate

from experiments.helicopter_energy_control import STUDY
from tests.experiments.study_cli import recorded_config, run_quick_study


@pytest.fixture(scope="module")
def study_output(tmp_path_factory):
    out = tmp_path_factory.mktemp("heli")
    return out, run_quick_study("helicopter_energy_control", out, preset="tiny")


def test_config_files_and_verdicts(study_output):
    out, res = study_output
    tiny = STUDY.resolve("tiny")[1]
    cfg = recorded_config(tiny)
    assert res["config"] == cfg
    for name in ("designs.csv", "robustness.csv", "responses.png", "lyapunov.png"):
        assert (out / name).stat().st_size > 0, name
    verdicts = {r["metric"]: r["verdict"] for r in res["reproduction"]}
    for metric in ("energy_drift_order", "energy_drift_rel", "lyap_max_increase_rel", "lyap_final_over_initial"):
        assert verdicts[metric] == "reproduced", (metric, verdicts)
    m = res["metrics"]
    assert m["energy_drift_rel_half_step"] < m["energy_drift_rel"]
    rob = res["tables"]["robustness"]
    assert {r["design"] for r in rob} == {"hand", "gradient"}
    assert all(r["ci95_lo"] <= r["mean_rel_err"] <= r["ci95_hi"] and r["runs"] == tiny.mc_runs for r in rob)


def test_hand_design_against_scipy(study_output):
    res = study_output[1]
    c = STUDY.resolve("tiny")[1]
    la, lh, kf, je, jp, hp = 0.66, 0.177, 0.5, 0.91, 0.0364, 0.005
    a0 = np.array([9.81 * hp / lh**2, c.a_elev0])
    b = np.array([kf * lh / jp, kf * la / je])
    a1 = np.array([0.2, 0.2])
    v_star = a0 * (1 - np.cos(np.radians([c.amp_pitch_deg, c.amp_elev_deg])))
    g1, g2 = np.array(c.gains0[:2]), np.array(c.gains0[2:])

    def rhs(t, x):
        q, qd, ah = x[:2], x[2:4], x[4:]
        err = 0.5 * qd**2 + a0 * (1 - np.cos(q)) - v_star
        w = (ah * qd - g1 * err * qd) / np.cos(q)
        return np.concatenate([qd, -a1 * qd - a0 * np.sin(q) + b * w * np.cos(q), -g2 * err * qd**2])

    n = round(c.t_final / c.dt)
    t = np.arange(n + 1) * c.dt
    x0 = np.concatenate([np.radians([c.pitch0_deg, c.elev0_deg]), np.zeros(4)])
    sol = scipy.integrate.solve_ivp(rhs, (0, t[-1]), x0, method="DOP853", rtol=1e-10, atol=1e-12, t_eval=t)
    x = sol.y.T
    err = 0.5 * x[:, 2:4] ** 2 + a0 * (1 - np.cos(x[:, :2])) - v_star
    n_tail = round(c.tail / c.dt)
    rel = np.sqrt(np.mean(err[-n_tail:] ** 2, axis=0)) / v_star
    hand = next(r for r in res["tables"]["designs"] if r["design"] == "hand")
    assert hand["reduced_final_rel_err_pitch"] == pytest.approx(rel[0], rel=1e-3, abs=1e-6)
    assert hand["reduced_final_rel_err_elev"] == pytest.approx(rel[1], rel=1e-3, abs=1e-6)
