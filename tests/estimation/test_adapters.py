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
from jaxsim.estimation.adapters import (
    ekf_estimator,
    filter_estimator,
    kalman_estimator,
    luenberger_estimator,
    ukf_estimator,
)
from jaxsim.estimation.filtering import FilterMember
from jaxsim.estimation.lgssm import kalman_filter, lgssm, linear_member
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
    loop = ClosedLoop(
        plant, pid(kp=1.0, ki=2.0), reference=Step(1.0), sensor=gaussian_sensor(STD, period=3 * TS), estimator=estimator
    )
    sim = jax.jit(
        lambda lp: simulate(
            lp,
            jnp.zeros(2),
            Timing(t_final=2.0, dt=TS / 10, controller_period=TS),
            key=jax.random.PRNGKey(0),
            solver=ExponentialEuler(),
        )
    )
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
        nl = nonlinear_ssm(
            lambda p, x, u: model.F @ x + model.B @ u, lambda p, x: model.H @ x, model.Q, model.R, model.m0, model.P0
        )
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


def test_one_filter_member_serves_the_scan_the_imm_and_the_closed_loop():
    """The EKF member of a model is the same filter everywhere: the scanned EKF, a one-model IMM,
    and the closed-loop adapter (on a linear model all equal the Kalman filter)."""
    from jaxsim.estimation.ekf import ekf_member, extended_kalman_filter
    from jaxsim.estimation.filtering import scan_member
    from jaxsim.estimation.imm import imm, imm_filter, imm_init
    from jaxsim.estimation.types import GaussianState

    _, model = _setup()
    nl = nonlinear_ssm(lambda p, x, u: model.F @ x, lambda p, x: model.H @ x, model.Q, model.R, model.m0, model.P0)
    member = ekf_member(nl)
    y = np.sin(np.linspace(0.0, 3.0, 40))[:, None]
    mask = np.ones((40, 1), bool)
    scanned = scan_member(member, GaussianState(nl.m0, nl.P0), jnp.asarray(y), jnp.asarray(mask))
    np.testing.assert_array_equal(scanned.means, extended_kalman_filter(nl, y).means)
    bank = imm_filter(imm([member], [[1.0]]), imm_init(nl.m0[None], nl.P0[None], [1.0]), y)
    np.testing.assert_allclose(bank.means, scanned.means, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(scanned.means, kalman_filter(model, y).means, rtol=1e-10, atol=1e-12)
    closed = _run(
        filter_estimator(linear_member(model.F, model.Q, model.H, model.R, model.B), model.m0, model.P0, read="output")
    )
    np.testing.assert_array_equal(closed.x_hat, _run(kalman_estimator(model, read="output")).x_hat)


def test_filter_estimator_bad_input():
    _, model = _setup()
    bare = FilterMember(None, lambda p, s, u: s, lambda p, s, y, m: (s, None))
    with pytest.raises(ValueError, match="^read: 'output' needs the member's observe"):
        filter_estimator(bare, model.m0, model.P0, read="output")
    member = linear_member(model.F, model.Q, model.H, model.R, model.B)
    with pytest.raises(ValueError, match=r"^m0: expected shape \(n,\)"):
        filter_estimator(member, np.zeros((2, 1)), model.P0)
    with pytest.raises(ValueError, match="^P0: must be positive semi-definite"):
        filter_estimator(member, model.m0, -np.eye(2))
    with pytest.raises(ValueError, match="^member: expected a FilterMember"):
        filter_estimator(model, model.m0, model.P0)
    with pytest.raises(ValueError, match="^form:"):
        linear_member(model.F, model.Q, model.H, model.R, form="sqrt")
