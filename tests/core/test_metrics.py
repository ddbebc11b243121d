"""Step metrics against python-control's step_info; integral criteria; smooth surrogates."""

import dataclasses

import control
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.control.pid import PIDParams, pid
from jaxsim.core import metrics
from jaxsim.core.rollout import ClosedLoop, Timing, simulate
from jaxsim.core.signals import Step
from jaxsim.plants.second_order import astatic_plant, static_plant

DT = 1e-3
CASES = [  # (plant factory, plant tf, kp)
    (static_plant, ([2.0], [0.05, 0.6, 1.0]), 0.4),  # double pole at -6 (paper's K_mds)
    (static_plant, ([2.0], [0.05, 0.6, 1.0]), 3.0),  # oscillatory
    (astatic_plant, ([2.0], [0.1, 1.0, 0.0]), 1.25),  # double pole at -5 (paper's K_mds)
    (astatic_plant, ([2.0], [0.1, 1.0, 0.0]), 6.0),  # oscillatory
]


def _closed_loop_response(make, kp, t_final=4.0, dt=DT):
    loop = ClosedLoop(make(), pid(kp=kp), reference=Step(1.0))
    tr = simulate(loop, jnp.zeros(2), Timing(t_final=t_final, dt=dt))
    return np.asarray(tr.t), np.asarray(tr.y[:, 0])


@pytest.mark.parametrize("make, tf, kp", CASES)
def test_step_metrics_of_our_rollout_match_control_step_info(make, tf, kp):
    dt = 1e-4  # sampled-data loop: ZOH adds ~dt/2 delay, so overshoot differs by O(dt)
    t, y = _closed_loop_response(make, kp, dt=dt)
    plant_tf = control.tf(*tf)
    closed = control.feedback(kp * plant_tf, 1)
    ref = control.step_info(closed, T=t)
    ours = metrics.step_info(jnp.asarray(t), jnp.asarray(y), y_final=ref["SteadyStateValue"])
    # Our loop is sampled-data (ZOH): timings agree within a few controller periods.
    assert abs(float(ours.rise_time) - ref["RiseTime"]) <= 3 * dt
    assert abs(float(ours.settling_time) - ref["SettlingTime"]) <= 5 * dt
    assert abs(float(ours.overshoot) - ref["Overshoot"]) <= 0.05  # percentage points
    np.testing.assert_allclose(float(ours.final_value), ref["SteadyStateValue"], rtol=1e-12)


@pytest.mark.parametrize("make, tf, kp", CASES)
def test_step_info_definitions_equal_control_on_the_same_samples(make, tf, kp):
    t, y = _closed_loop_response(make, kp)
    ref = control.step_info(y, T=t)
    ours = metrics.step_info(jnp.asarray(t), jnp.asarray(y))
    assert float(ours.rise_time) == pytest.approx(ref["RiseTime"], abs=1e-15)
    assert float(ours.settling_time) == pytest.approx(ref["SettlingTime"], abs=1e-15)
    assert float(ours.overshoot) == pytest.approx(ref["Overshoot"], rel=1e-12, abs=1e-12)
    assert float(ours.peak) == pytest.approx(ref["Peak"], rel=1e-14)
    assert float(ours.peak_time) == pytest.approx(ref["PeakTime"], abs=1e-15)


def test_integral_criteria_closed_forms():
    # e(t) = exp(-a t): IAE = 1/a, ISE = 1/(2a), ITAE = 1/a^2; the left rectangle rule over-estimates
    # by about dt·e(0)/2, i.e. a relative 1e-5 here.
    a, dt = 2.0, 1e-5
    t = jnp.arange(0.0, 20.0, dt)
    e = jnp.exp(-a * t)
    np.testing.assert_allclose(metrics.iae(t, e), 1 / a, rtol=3e-5)
    np.testing.assert_allclose(metrics.ise(t, e), 1 / (2 * a), rtol=3e-5)
    np.testing.assert_allclose(metrics.itae(t, e), 1 / a**2, rtol=3e-5)
    u = jnp.stack([e, 2 * e], axis=1)
    np.testing.assert_allclose(metrics.control_energy(t, u), 5 / (2 * a), rtol=3e-5)


def test_steady_state_detects_drift():
    t = jnp.linspace(0, 10, 1001)
    conv = metrics.steady_state(1.0 + jnp.exp(-5 * t), tail=100)
    ramp = metrics.steady_state(0.1 * t, tail=100)
    assert bool(conv.converged) and not bool(ramp.converged)
    assert not bool(metrics.steady_state(jnp.full(10, jnp.nan), tail=5).converged)


def test_smooth_surrogates_approach_the_hard_metrics():
    t, y = _closed_loop_response(static_plant, 3.0)
    t, y = jnp.asarray(t), jnp.asarray(y)
    hard = metrics.step_info(t, y)
    prev_err = np.inf
    for temp in (2.0, 0.5, 0.05):
        err = abs(float(metrics.soft_overshoot(y, temperature=temp)) - float(hard.overshoot))
        assert err < prev_err
        prev_err = err
    assert prev_err < 0.05 * float(hard.overshoot)
    soft_ts = metrics.soft_settling_time(t, y, band_temperature=1e-4, time_temperature=1e-3)
    assert abs(float(soft_ts) - float(hard.settling_time)) < 0.02


def test_smooth_surrogates_have_finite_gradients():
    controller = pid(kp=1.0)

    def loss(kp):
        ctrl = dataclasses.replace(controller, params=PIDParams(kp=kp))
        loop = ClosedLoop(static_plant(), ctrl, reference=Step(1.0))
        tr = simulate(loop, jnp.zeros(2), Timing(t_final=3.0, dt=1e-2))
        return metrics.soft_overshoot(tr.y[:, 0]) + metrics.soft_settling_time(tr.t, tr.y[:, 0])

    g = jax.grad(loss)(3.0)
    assert np.isfinite(float(g)) and float(g) != 0.0


def _central_differences(fn, x: np.ndarray, rel_step: float = 1e-6) -> np.ndarray:
    """Central differences of a scalar ``fn`` along every coordinate of ``x`` (step relative to max|x|)."""
    h = rel_step * max(float(np.max(np.abs(x))), 1e-3)
    out = np.empty(x.size)
    for i in range(x.size):
        e = np.zeros(x.size)
        e[i] = h
        e = e.reshape(x.shape)
        out[i] = (float(fn(x + e)) - float(fn(x - e))) / (2 * h)
    return out.reshape(x.shape)


def _underdamped_step(n: int = 60, zeta: float = 0.35, wn: float = 6.0, t_final: float = 3.0):
    """Unit-step response of ``wn²/(s² + 2ζwn s + wn²)`` sampled on ``n`` points (overshoots ~30 %)."""
    t = np.linspace(0.0, t_final, n)
    wd = wn * np.sqrt(1 - zeta**2)
    y = 1 - np.exp(-zeta * wn * t) * (np.cos(wd * t) + zeta / np.sqrt(1 - zeta**2) * np.sin(wd * t))
    return t, y


def test_soft_overshoot_gradient_matches_finite_differences():
    _, y = _underdamped_step()
    for y_final in (None, 1.0):  # y_final from the last sample (a gradient path of its own) or given
        f = jax.jit(lambda v, yf=y_final: metrics.soft_overshoot(v, yf, temperature=0.5))
        g = np.asarray(jax.grad(f)(jnp.asarray(y)))
        fd = _central_differences(f, y)
        assert np.max(np.abs(fd)) > 1.0
        np.testing.assert_allclose(g, fd, rtol=1e-6, atol=1e-6 * np.max(np.abs(fd)))
    f_final = jax.jit(lambda yf: metrics.soft_overshoot(jnp.asarray(y), yf, temperature=0.5))
    fd = _central_differences(f_final, np.array(1.0))
    np.testing.assert_allclose(jax.grad(f_final)(1.0), fd, rtol=1e-6)
    # a flat response has no overshoot: every v is 0, so the surrogate is exactly τ·log 2
    np.testing.assert_allclose(metrics.soft_overshoot(jnp.ones(10), temperature=0.5), 0.5 * np.log(2.0), rtol=1e-15)


def test_soft_settling_time_gradient_matches_finite_differences():
    t, y = _underdamped_step()
    # wider temperatures than the defaults: with the defaults (τ_b = 0.002) the third derivative is
    # so large that the central difference's own truncation error reaches ~3e-7 of the gradient
    kw = {"band": 0.05, "band_temperature": 0.02, "time_temperature": 0.1}
    f = jax.jit(lambda v: metrics.soft_settling_time(jnp.asarray(t), v, **kw))
    g = np.asarray(jax.grad(f)(jnp.asarray(y)))
    fd = _central_differences(f, y)
    assert np.max(np.abs(fd)) > 1.0
    np.testing.assert_allclose(g, fd, rtol=1e-6, atol=1e-6 * np.max(np.abs(fd)))
    f_final = jax.jit(lambda yf: metrics.soft_settling_time(jnp.asarray(t), jnp.asarray(y), yf, **kw))
    np.testing.assert_allclose(jax.grad(f_final)(1.0), _central_differences(f_final, np.array(1.0)), rtol=1e-6)
