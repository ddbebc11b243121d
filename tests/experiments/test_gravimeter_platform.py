"""The gravimeter_platform study through the CLI (tiny preset), and its plant: the exact stick–slip step
against a fine-step event-resolving NumPy reference, sticking under small torque, the delay shift, the
claims against their metrics."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from experiments.gravimeter_platform import ARCSEC, STUDY, delayed
from jaxsim.plants import gravimeter_gimbal as gg
from tests.experiments.study_cli import recorded_config, run_quick_study


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    out = tmp_path_factory.mktemp("grav")
    return out, run_quick_study("gravimeter_platform", out, preset="tiny")


def test_files_config_and_claims(result):
    out, res = result
    _, cfg = STUDY.resolve("tiny", [])
    assert res["config"] == recorded_config(cfg)
    for name in ("error_budget.csv", "bench_regimes.csv", "designs.csv", "stabilisation.png", "reproduction.csv"):
        assert (out / name).stat().st_size > 0, name
    m = res["metrics"]
    verdict = {r["metric"]: r["verdict"] for r in res["reproduction"]}
    below = max(m["relative_max_arcmin"], m["absolute_max_arcmin"]) < 1.0
    assert (verdict["both_below_1_arcmin"] == "reproduced") == below
    assert (verdict["bench_worst_max_arcsec"] == "reproduced") == (m["bench_worst_max_arcsec"] <= 40.0)
    tau = round(cfg.delay_s / cfg.dt) * cfg.dt
    w = 2 * np.pi / cfg.roll_period
    assert m["delay_closed_form_arcsec"] == pytest.approx(
        2 * np.radians(cfg.roll_amp_deg) * np.sin(w * tau / 2) / ARCSEC
    )
    rows = {(r["payload"], r["sources"]): r for r in res["tables"]["error_budget"]}
    assert rows[("relative 5 kg", "all")]["max_arcsec"] == pytest.approx(60 * m["relative_max_arcmin"], rel=1e-12)
    for key in ("plant", "controller", "ins", "bench"):
        assert res["assumptions"][key]["why"]


@pytest.mark.parametrize(("torque", "tol"), [(0.01, 1e-12), (0.05, 1e-12), (-0.08, 2e-3)])
def test_exact_friction_step_against_the_closed_form(torque, tol):
    """Relative speed 0.2 rad/s at first, constant torque, frame at 0.1 rad/s for 0.5 s: slip decelerates
    at (M − M_TR)/J, then sticks (|M| ≤ M_TR) or slips backwards at (M + M_TR)/J; or slips on forwards.
    The implicit step is exact except in the one step where the relative speed crosses zero (error
    ≤ 2·dt·M_TR/J)."""
    p = gg.RELATIVE_5KG
    x = jnp.array([0.0, 0.3])
    step = jax.jit(lambda x: gg.step(p, x, jnp.asarray(torque), jnp.asarray(0.1), 1e-3))
    for _ in range(500):
        x = step(x)
    s0, t = 0.2, 0.5
    if torque > p.M_TR:
        s = s0 + t * (torque - p.M_TR) / p.J
    else:
        t1 = s0 * p.J / (p.M_TR - torque)
        assert t1 < t
        s = 0.0 if abs(torque) <= p.M_TR else (t - t1) * (torque + p.M_TR) / p.J
    assert float(x[1]) - 0.1 == pytest.approx(s, abs=tol)


def test_smooth_step_is_close_to_the_exact_one_when_slipping():
    p = gg.RELATIVE_5KG
    x = jnp.array([0.0, 0.5])
    exact = gg.step(p, x, jnp.asarray(0.0), jnp.asarray(0.0), 1e-3)
    smooth = gg.step(p, x, jnp.asarray(0.0), jnp.asarray(0.0), 1e-3, exact=False)
    b = 1e-3 * p.M_TR / p.J
    assert abs(float(smooth[1] - exact[1])) < 1e-6 * b  # deep in slip: tanh(s/b) = 1 to 1e-6
    g = jax.grad(lambda w: gg.step(p, jnp.array([0.0, w]), 0.0, 0.0, 1e-3, exact=False)[1])(0.5)
    assert np.isfinite(float(g))


def test_delay_is_an_exact_shift():
    x = jnp.arange(10.0)
    np.testing.assert_array_equal(delayed(x, jnp.asarray(3)), [0, 0, 0, 0, 1, 2, 3, 4, 5, 6])
    np.testing.assert_array_equal(delayed(x, jnp.asarray(0)), x)
