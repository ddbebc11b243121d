"""The glider_course study through the CLI (tiny preset), and its plant and autopilot: the plant against
SciPy's ``solve_ivp`` and the steady-turn closed form, the mission's gradient against finite
differences, the closed forms of the out-and-back geometry."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from experiments.glider_course import GAIN_NAMES, STUDY, closed_forms, draw_errors, mission, mission_loss
from jaxsim.control import glider_autopilot as ap
from jaxsim.core.integrators import RK4
from jaxsim.plants import glider_course as gc
from tests.experiments.study_cli import recorded_config, run_quick_study


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    out = tmp_path_factory.mktemp("glider")
    return out, run_quick_study("glider_course", out, preset="tiny")


def test_files_config_and_claims(result):
    out, res = result
    _, cfg = STUDY.resolve("tiny", [])
    assert res["config"] == recorded_config(cfg)
    for name in ("error_budget.csv", "designs.csv", "missions.png", "reproduction.csv"):
        assert (out / name).stat().st_size > 0, name
    m = res["metrics"]
    verdict = {r["metric"]: r["verdict"] for r in res["reproduction"]}
    assert (verdict["deviation_miss_over_closed_form"] == "reproduced") == (
        abs(m["deviation_miss_over_closed_form"] - 1.0) <= 0.25
    )
    assert (verdict["compass_bias_cancellation_ratio"] == "reproduced") == (
        m["compass_bias_cancellation_ratio"] <= 0.15
    )
    rows = {r["errors"]: r for r in res["tables"]["error_budget"]}
    assert all(r["returned_fraction"] == 1.0 for r in rows.values())
    ref = closed_forms(cfg)
    assert m["deviation_mean_miss_m"] == pytest.approx(
        2 * cfg.leg * np.radians(cfg.compass_deviation_deg) * np.sqrt(2 / np.pi)
    )
    assert ref["deviation_mean_miss_m"] == pytest.approx(m["deviation_mean_miss_m"], rel=1e-12)
    assert m["deviation_miss_vs_2legB_corr"] < -0.95  # the miss is −2·leg·B across the track, draw by draw
    for key in ("course_model", "mission", "sensors", "autopilot"):
        assert res["assumptions"][key]["why"]


def test_plant_against_solve_ivp_and_the_steady_turn():
    p = gc.Params()
    delta = 0.2
    u = jnp.array([delta])
    f = jax.jit(lambda t, x: gc.dynamics(p, x, u, t))
    sol = solve_ivp(lambda t, x: np.asarray(f(t, jnp.asarray(x))), (0, 300), np.zeros(6), rtol=1e-11, atol=1e-12)
    x = jnp.zeros(6)
    step = jax.jit(lambda x, t: RK4.step(f, t, x, 0.5))
    for k in range(600):
        x = step(x, 0.5 * k)
    np.testing.assert_allclose(np.asarray(x), sol.y[:, -1], rtol=1e-6, atol=1e-6)
    turn = gc.steady_turn(p, delta)
    assert sol.y[1, -1] == pytest.approx(float(turn["r"]), rel=1e-9)
    assert sol.y[3, -1] == pytest.approx(float(turn["beta"]), rel=1e-9)
    # the steady track is a circle of radius V/(Kδ): speed over turn rate
    dense = solve_ivp(lambda t, x: np.asarray(f(t, jnp.asarray(x))), (200, 300), sol.y[:, -1], rtol=1e-11, atol=1e-12)
    xy = dense.y[4:6]
    centre = xy[:, 0] + float(turn["radius"]) * np.array(
        [-np.sin(sol.y[0, -1] - sol.y[3, -1]), np.cos(sol.y[0, -1] - sol.y[3, -1])]
    )
    np.testing.assert_allclose(np.linalg.norm(xy - centre[:, None], axis=0), float(turn["radius"]), rtol=1e-6)


def test_heading_filter_steady_error_is_gyro_bias_over_crossover():
    gains = ap.Gains(kc=0.05)
    p = gc.Params()
    nav = ap.NavState(*(jnp.zeros(()) for _ in range(4)))
    step = jax.jit(lambda nav: ap.nav_step(nav, jnp.asarray(1e-3), jnp.asarray(0.0), gains, p, 0.5))
    for _ in range(2000):
        nav = step(nav)
    assert float(nav.psi) == pytest.approx(1e-3 / 0.05, rel=1e-6)


def test_mission_gradient_against_finite_differences():
    _, cfg = STUDY.resolve("tiny", [])
    err = jax.tree_util.tree_map(lambda a: a[0], draw_errors(cfg, jax.random.PRNGKey(3), 1))
    d0 = {n: jnp.float64(v) for n, v in zip(GAIN_NAMES, cfg.gains0)}
    f = jax.jit(lambda d: mission_loss(cfg, d, err))
    g = jax.jit(jax.grad(lambda d: mission_loss(cfg, d, err)))(d0)
    for name in ("kc", "lookahead"):
        h = 1e-5 * float(d0[name])
        fd = (float(f({**d0, name: d0[name] + h})) - float(f({**d0, name: d0[name] - h}))) / (2 * h)
        assert float(g[name]) == pytest.approx(fd, rel=2e-3, abs=1e-6)


def test_error_free_mission_returns_to_the_start():
    _, cfg = STUDY.resolve("tiny", [])
    err = jax.tree_util.tree_map(lambda a: a[0], draw_errors(cfg, jax.random.PRNGKey(0), 1))
    out = mission(cfg, ap.Gains(*cfg.gains0), err, jnp.zeros(6))
    assert bool(out["returned"]) and float(out["miss"]) < 0.01 * cfg.leg  # dead reckoning alone: < 1 % of the leg
