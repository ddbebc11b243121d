"""Discrete PID: convergence to the continuous loop, derivative filter, saturation, anti-windup."""

import dataclasses

import control
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.control.pid import PIDParams, pid, pid_transfer_function
from jaxsim.core.rollout import ClosedLoop, Timing, simulate
from jaxsim.core.signals import Step
from jaxsim.plants.second_order import astatic_plant, static_plant

PLANT_TF = control.tf([2.0], [0.05, 0.6, 1.0])


def _continuous_response(kp, ki, kd, tf, t):
    """Continuous loop with P and I on the error and the filtered derivative on −y."""
    c_pi = control.tf(*pid_transfer_function(kp, ki, 0.0))
    d = control.tf([kd, 0.0], [tf, 1.0])
    closed = control.feedback(PLANT_TF, c_pi + d) * c_pi
    return control.step_response(closed, T=t).outputs


@pytest.mark.parametrize("gains", [(0.7, 1.6, 0.0, 0.0), (1.0, 0.5, 0.05, 0.02)])
def test_sampled_pid_converges_to_the_continuous_loop_at_first_order(gains):
    errs = []
    for ts in (2e-3, 1e-3, 5e-4):
        kp, ki, kd, tf = gains
        ctrl = pid(kp=kp, ki=ki, kd=kd, tf=tf, derivative_on="measurement")
        loop = ClosedLoop(static_plant(), ctrl, reference=Step(1.0))
        tr = simulate(loop, jnp.zeros(2), Timing(t_final=3.0, dt=ts))
        y_ref = _continuous_response(*gains, np.asarray(tr.t))
        errs.append(np.max(np.abs(np.asarray(tr.y[:, 0]) - y_ref)))
    ratios = np.array(errs[:-1]) / np.array(errs[1:])
    assert np.all((ratios > 1.7) & (ratios < 2.3)), (errs, ratios)
    assert errs[-1] < 5e-3


def test_derivative_filter_matches_backward_euler_closed_form():
    # open loop: feed e(t) = t (ramp), D = s/(tf s + 1) → D(t) = 1 − exp(−t/tf) in continuous time;
    # backward Euler: D_k = (tf D_{k−1} + ts)/(tf + ts) → 1 − (tf/(tf+ts))^k
    p = PIDParams(kp=0.0, kd=1.0, tf=0.05)
    ctrl = pid(p)
    ts = 1e-3
    state = ctrl.init(p, jnp.zeros(1), jnp.zeros(1))
    outs = []
    for k in range(1, 200):
        state, u = ctrl.step(p, state, jnp.array([k * ts]), jnp.zeros(1), ts, k * ts)
        outs.append(float(u[0]))
    k = np.arange(1, 200)
    np.testing.assert_allclose(outs, 1 - (0.05 / (0.05 + ts)) ** k, rtol=1e-12)


def _windup_run(mode: str):
    loop = ClosedLoop(
        astatic_plant(), pid(kp=2.0, ki=4.0, u_min=-0.3, u_max=0.3, anti_windup=mode), reference=Step(1.0)
    )
    return simulate(loop, jnp.zeros(2), Timing(t_final=8.0, dt=1e-3))


def test_saturation_and_anti_windup_reduce_overshoot():
    runs = {m: _windup_run(m) for m in ("none", "clamping", "back_calculation")}
    for tr in runs.values():
        assert float(jnp.max(jnp.abs(tr.u))) <= 0.3 + 1e-15
    over = {m: float(jnp.max(tr.y[:, 0])) - 1.0 for m, tr in runs.items()}
    assert over["clamping"] < 0.5 * over["none"]
    assert over["back_calculation"] < 0.5 * over["none"]
    for tr in runs.values():  # all settle at the reference (integral action)
        assert abs(float(tr.y[-1, 0]) - 1.0) < 1e-3


def test_clamping_freezes_the_integral_while_saturated():
    p = PIDParams(kp=1.0, ki=1.0, u_min=-1.0, u_max=1.0, anti_windup="clamping")
    ctrl = pid(p)
    s = ctrl.init(p, jnp.zeros(1), jnp.zeros(1))
    for k in range(100):
        s, u = ctrl.step(p, s, jnp.array([5.0]), jnp.zeros(1), 0.01, 0.01 * k)
    assert float(u[0]) == 1.0 and float(s.integral[0]) == 0.0


def test_pid_gradients_through_saturation_are_finite():
    def loss(kp):
        ctrl = dataclasses.replace(pid(kp=1.0), params=PIDParams(kp=kp, ki=1.0, u_min=-0.5, u_max=0.5))
        tr = simulate(ClosedLoop(static_plant(), ctrl, reference=Step(1.0)), jnp.zeros(2), Timing(t_final=2.0, dt=1e-2))
        return jnp.sum((tr.r - tr.y) ** 2)

    assert np.isfinite(float(jax.grad(loss)(2.0)))


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"tf": -0.1}, "tf: must be non-negative"),
        ({"kp": float("nan")}, "kp: must be finite"),
        ({"u_min": 1.0, "u_max": -1.0}, "u_min/u_max"),
        ({"anti_windup": "magic"}, "anti_windup"),
        ({"tt": 0.0}, "tt: must be positive"),
    ],
)
def test_bad_pid_parameters(kwargs, match):
    with pytest.raises(ValueError, match=match):
        pid(**kwargs)


@pytest.mark.parametrize("mode", ["clamping", "back_calculation"])
def test_loss_gradient_through_saturated_pid_matches_finite_differences(mode):
    """Closed loop with the actuator saturated for a good part of the step: the gradient of a
    tracking-plus-effort loss in ``(kp, ki, kd, u_max)`` against central differences (1e-6 relative
    step).  The loss is piecewise smooth (samples enter and leave saturation); the parameters sit
    inside one smooth piece, which the one-sided differences confirm."""
    ctrl = pid(kp=1.0)
    timing = Timing(t_final=2.0, dt=1e-2)

    def loss(theta):
        kp, ki, kd, u_max = theta
        p = PIDParams(kp=kp, ki=ki, kd=kd, tf=0.05, u_min=-u_max, u_max=u_max, anti_windup=mode)
        loop = ClosedLoop(static_plant(), dataclasses.replace(ctrl, params=p), reference=Step(1.0))
        tr = simulate(loop, jnp.zeros(2), timing)
        return jnp.sum((tr.r - tr.y) ** 2) * timing.dt + 0.01 * jnp.sum(tr.u**2) * timing.dt, tr.u

    theta = np.array([3.0, 2.0, 0.1, 0.6])
    value_and_grad = jax.jit(jax.value_and_grad(loss, has_aux=True))
    (_, u), grad = value_and_grad(theta)
    saturated = np.abs(np.asarray(u)) >= 0.6
    assert 10 <= saturated.sum() <= len(u) - 10  # saturation active, but not all the time

    f = lambda th: float(value_and_grad(th)[0][0])  # noqa: E731
    f0 = f(theta)
    h = 1e-6 * theta
    for i in range(4):
        e = np.zeros(4)
        e[i] = h[i]
        fp, fm = f(theta + e), f(theta - e)
        forward, backward, central = (fp - f0) / h[i], (f0 - fm) / h[i], (fp - fm) / (2 * h[i])
        assert abs(forward - backward) <= 1e-4 * abs(central), i  # inside one smooth piece
        np.testing.assert_allclose(grad[i], central, rtol=1e-6, err_msg=f"parameter {i}")
    assert abs(float(grad[3])) > 1e-2  # the saturation level itself matters to the loss
