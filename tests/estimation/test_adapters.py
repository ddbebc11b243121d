"""Filters as closed-loop estimators: the in-loop Kalman filter equals the same filter run offline."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.control.pid import pid
from jaxsim.core.discretize import c2d_zoh
from jaxsim.core.integrators import ExponentialEuler
from jaxsim.core.linearize import linearize
from jaxsim.core.rollout import ClosedLoop, Timing, simulate
from jaxsim.core.signals import Step
from jaxsim.core.system import gaussian_sensor
from jaxsim.estimation.adapters import ekf_estimator, kalman_estimator, luenberger_estimator, ukf_estimator
from jaxsim.estimation.lgssm import kalman_filter, lgssm
from jaxsim.estimation.nonlinear import nonlinear_ssm
from jaxsim.estimation.observers import current_observer_gain
from jaxsim.plants.second_order import static_plant

TS = 0.01
STD = 0.05


def _setup():
    plant = static_plant()
    lin = linearize(plant, jnp.zeros(2), jnp.zeros(1))
    ad, bd = c2d_zoh(lin.a, lin.b, TS)
    model = lgssm(ad, 1e-6 * np.eye(2), lin.c, [[STD**2]], np.zeros(2), 0.01 * np.eye(2), B=bd)
    return plant, model


def _run(estimator):
    plant, _ = _setup()
    loop = ClosedLoop(plant, pid(kp=1.0, ki=2.0), reference=Step(1.0),
                      sensor=gaussian_sensor(STD, period=3 * TS), estimator=estimator)
    sim = jax.jit(lambda lp: simulate(lp, jnp.zeros(2), Timing(t_final=2.0, dt=TS / 10, controller_period=TS),
                                      key=jax.random.PRNGKey(0), solver=ExponentialEuler()))
    return sim(loop)


def test_kalman_estimator_in_closed_loop_equals_offline_masked_filter():
    _, model = _setup()
    traj = _run(kalman_estimator(model, read="output"))
    measured = np.asarray(traj.measured)
    assert measured.sum() < len(measured)  # multi-rate: the sensor is 3× slower than the loop
    offline = kalman_filter(model, traj.y_meas, traj.u, mask=traj.measured)
    np.testing.assert_allclose(traj.x_hat, offline.means @ model.H.T, rtol=1e-10, atol=1e-12)
    rms_est = np.sqrt(np.mean((np.asarray(traj.x_hat) - np.asarray(traj.y)) ** 2))
    rms_meas = np.sqrt(np.mean((np.asarray(traj.y_meas) - np.asarray(traj.y)) ** 2))
    assert rms_est < 0.5 * rms_meas


@pytest.mark.parametrize("kind", ["ekf", "ukf", "luenberger"])
def test_other_estimators_plug_into_the_rollout(kind):
    _, model = _setup()
    if kind == "luenberger":
        gain = current_observer_gain(model.F, model.H, [0.6, 0.7])
        est = luenberger_estimator(model.F, model.B, model.H, gain, np.zeros(2), read="output")
    else:
        nl = nonlinear_ssm(lambda p, x, u: model.F @ x + model.B @ u, lambda p, x: model.H @ x,
                           model.Q, model.R, model.m0, model.P0)
        est = ekf_estimator(nl, read="output") if kind == "ekf" else ukf_estimator(nl, alpha=0.8, read="output")
    traj = _run(est)
    if kind == "luenberger":
        err = np.abs(np.asarray(traj.x_hat) - np.asarray(traj.y))[-50:]
        assert np.max(err) < 4 * STD
    else:  # on a linear model the EKF/UKF are the Kalman filter
        ref = _run(kalman_estimator(model, read="output"))
        np.testing.assert_allclose(traj.x_hat, ref.x_hat, rtol=1e-8, atol=1e-10)


def test_adapter_bad_input():
    _, model = _setup()
    with pytest.raises(ValueError, match="^read:"):
        kalman_estimator(model, read="state")
    with pytest.raises(ValueError, match="^form:"):
        kalman_estimator(model, form="sqrt")
