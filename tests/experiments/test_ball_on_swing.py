"""The ball_on_swing study through the CLI (tiny preset): files and verdicts, and the numbers re-checked
independently (the unforced plant by a hand-written NumPy RK4 on the (θ, s) equations, the Floquet
multipliers from the written table, the Monte Carlo fraction from its rows)."""

import math

import numpy as np
import pytest

from experiments.ball_on_swing import STUDY
from tests.experiments.study_cli import assert_verdicts_follow_the_tolerances, run_quick_study
from tests.plants.test_ball_on_swing import oracle_accel

pytestmark = pytest.mark.slow  # a short study run through the CLI: a few compilations


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    out = tmp_path_factory.mktemp("bos")
    return out, run_quick_study("ball_on_swing", out, preset="tiny")


def test_config_files_and_verdicts(result):
    out, res = result
    _, tiny = STUDY.resolve("tiny")
    assert res["preset"] == "tiny" and res["config"]["samples"] == tiny.samples
    for name in ("orbit.csv", "floquet.csv", "monte_carlo.csv", "closed_loop.png", "reproduction.csv"):
        assert (out / name).exists(), name
    m = res["metrics"]
    assert_verdicts_follow_the_tolerances(res, STUDY.claims)
    assert m["phi0_final_transverse_err"] < 1e-3 < m["phi0_initial_transverse_err"]
    assert any("tuning skipped" in n for n in res["notes"])  # tiny: tune_budget = 0


def test_floquet_and_monte_carlo_tables(result):
    res = result[1]
    m, rows = res["metrics"], res["tables"]["floquet"]
    closed = [r["modulus"] for r in rows if r["source"] == "transverse_closed"]
    full = sorted(r["modulus"] for r in rows if r["source"] == "full_fd")
    assert m["floquet_max_modulus"] == pytest.approx(max(closed), rel=1e-12) and max(closed) < 1
    assert full[-1] == pytest.approx(1.0, abs=1e-3)  # the direction along the orbit
    np.testing.assert_allclose(full[:3], sorted(closed), atol=1e-3)
    for r in rows:
        assert r["modulus"] == pytest.approx(math.hypot(r["re"], r["im"]), rel=1e-12)
    mc = res["tables"]["monte_carlo"]
    assert m["mc_converged_fraction"] == pytest.approx(np.mean([r["converged"] for r in mc]), rel=1e-12)
    orbit = res["tables"]["orbit"]
    i = np.array([r["I"] for r in orbit])
    assert np.ptp(i) / abs(i[0]) == pytest.approx(m["orbit_integral_spread_rel"], rel=1e-6, abs=1e-12)
    assert orbit[-1]["t_s"] == pytest.approx(m["period_s"], rel=1e-12)


def test_energy_drift_recomputed_with_numpy(result):
    cfg, m = result[1]["config"], result[1]["metrics"]
    x, h = np.array([0.1, -0.3, 0.0, 0.0]), 1e-3

    def f(x):
        return np.concatenate([x[2:], oracle_accel(x, 0.0, m=cfg["m"], r=cfg["r"], j_f=cfg["j_f"], g=cfg["g"])])

    def energy(x):
        th, ph, thd, phd = x
        mb, r, d = cfg["m"], cfg["r"], cfg["r"]
        s, sd = d * math.tan(ph), d / math.cos(ph) ** 2 * phd
        t = 0.5 * cfg["j_f"] * thd**2 + 0.5 * mb * ((sd - d * thd) ** 2 + (s * thd) ** 2)
        t += 0.5 * 0.4 * mb * r**2 * (thd - sd / r) ** 2
        return t + mb * cfg["g"] * (s * math.sin(th) + d * math.cos(th))

    es = [energy(x)]
    for _ in range(cfg["check_steps"]):
        k1 = f(x)
        k2 = f(x + h / 2 * k1)
        k3 = f(x + h / 2 * k2)
        k4 = f(x + h * k3)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        es.append(energy(x))
    es = np.array(es)
    drift = np.max(np.abs(es - es[0])) / np.max(np.abs(es))
    assert drift < 1e-9 and m["energy_drift_rel"] < 1e-9
