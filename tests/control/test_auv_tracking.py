"""Computed torque + variable structure for the AUV follower (seed 002, eqs. 17–24)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.control.auv_tracking import auv_tracking, control_force
from jaxsim.estimation.leader_predictor import LeaderEstimate
from jaxsim.plants import auv, formation


def _read(x, target):
    return LeaderEstimate(x, *jnp.asarray(target))


def test_on_track_force_is_cruise_damping():
    """Follower on a target cruising at 1.2 m/s along x, aligned, ν = ν_r: s = 0, so τ = D(ν)ν
    (closed form (d₁ + d₂·1.2)·1.2 in surge, zero elsewhere) for sign and smooth switches."""
    x = auv.initial_state([2.0, 0.0, 1.0], nu=[1.2, 0, 0, 0, 0, 0])
    target = jnp.array([[2.0, 0.0, 1.0], [1.2, 0.0, 0.0], [0.0, 0.0, 0.0]])
    expected = np.array([(18.0 + 18.0 * 1.2) * 1.2, 0, 0, 0, 0, 0])
    for switch in ("sign", "tanh", "saturation"):
        ctrl = auv_tracking(switch=switch)
        np.testing.assert_allclose(control_force(ctrl.params, x, target), expected, atol=1e-9)


def test_sliding_term_and_start_time():
    """Off track: τ − τ_n = K_s sign(s) exactly for sign; tanh with a tiny width agrees; τ = 0
    before the follower's start time."""
    x = auv.initial_state([0.0, 0.0, 1.0], [0.05, -0.02, 0.1], [0.3, 0.1, -0.1, 0.02, 0.0, 0.01])
    target = jnp.array([[1.0, 0.5, 1.2], [1.2, 0.1, 0.0], [0.0, 0.01, 0.0]])
    sign = auv_tracking(switch="sign")
    no_vs = auv_tracking(switch="sign", k_s=jnp.full(6, 1e-12))
    tau_n = control_force(no_vs.params, x, target)
    tau = control_force(sign.params, x, target)
    np.testing.assert_allclose(np.abs(tau - tau_n), 100.0, rtol=1e-9)
    smooth = auv_tracking(switch="tanh", width=1e-9)
    np.testing.assert_allclose(control_force(smooth.params, x, target), tau, rtol=1e-9)
    _, u = sign.step(sign.params, sign.init(sign.params, None, None), None, _read(x, target), 1e-3, 3.0)
    assert np.all(np.asarray(u) == 0.0)
    _, u = sign.step(sign.params, sign.init(sign.params, None, None), None, _read(x, target), 1e-3, 4.0)
    np.testing.assert_allclose(u, tau)


def test_nominal_closed_loop_converges_exponentially():
    """Exact model, exact target (a straight line) and sign switching: s reaches 0 and the position
    error then decays as exp(−Λt) (Λ = 0.2 1/s); check the ratio of errors 5 s apart."""
    p = auv.nominal_params()
    ctrl = auv_tracking(p, t_start=0.0)
    m = auv.model(p)

    def target(t):
        return jnp.array([[1.0 + 1.2 * t, 0.5, 1.2], [1.2, 0.0, 0.0], [0.0, 0.0, 0.0]])

    h = 1e-3

    def step(x, k):
        t = k * h
        u = control_force(ctrl.params, x, target(t))
        f = lambda z: auv.dynamics(m, z, u, t)  # noqa: E731
        k1 = f(x)
        k2 = f(x + 0.5 * h * k1)
        k3 = f(x + 0.5 * h * k2)
        k4 = f(x + h * k3)
        x1 = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        return x1, jnp.linalg.norm(target(t)[0] - x[:3])

    _, err = jax.lax.scan(step, auv.initial_state([0.0, 0.0, 1.2], nu=[1.2, 0, 0, 0, 0, 0]), jnp.arange(20000))
    err = np.asarray(err)
    np.testing.assert_allclose(err[15000] / err[10000], np.exp(-0.2 * 5.0), rtol=1e-2)


def test_bad_input():
    with pytest.raises(ValueError, match="positive definite"):
        auv_tracking(auv.AUVParams(M_A=-200.0 * jnp.eye(6)))
    with pytest.raises(ValueError, match="lam"):
        auv_tracking(lam=(0.2, 0.2))
    with pytest.raises(ValueError, match="k_s"):
        auv_tracking(k_s=-jnp.ones(6))
    with pytest.raises(ValueError, match="t_start"):
        auv_tracking(t_start=float("inf"))
    with pytest.raises(ValueError, match="camera_period"):
        formation.camera_sensor(camera_period=0.1005, control_period=1e-3)
    with pytest.raises(ValueError, match="pos_std"):
        formation.camera_sensor(pos_std=-0.1)


def test_course_gate_keeps_slow_targets_finite():
    """A (nearly) stopped target point has no course: the gate is 0 below 0.2 m/s, exactly 1 at
    the paper's cruise speeds, and the force stays finite with a huge acceleration estimate."""
    from jaxsim.control.auv_tracking import course_gate

    assert float(course_gate(jnp.array([0.1, 0.05, 0.0]))) == 0.0
    assert float(course_gate(jnp.array([0.83, 0.0, 0.3]))) == 1.0
    x = auv.initial_state([0.0, 0.0, 1.0], nu=[0.5, 0, 0, 0, 0, 0.1])
    ctrl = auv_tracking()
    slow = jnp.array([[1.0, 0.0, 1.0], [1e-3, -2e-3, 0.0], [3.0, 5.0, 0.0]])
    still = slow.at[2].set(0.0)
    tau = control_force(ctrl.params, x, slow)
    assert np.all(np.isfinite(np.asarray(tau)))
    np.testing.assert_allclose(tau[3:], control_force(ctrl.params, x, still)[3:], atol=1e-9)


def test_reference_velocity_applies_lambda_in_body_frame():
    """Paper eq. 20: ``ν_r = V* + Λ J⁻¹ E`` — with roll/pitch ≠ 0, ``Λ J⁻¹ E ≠ J⁻¹ Λ E`` in attitude.
    Oracle: the ZYX Euler-rate inverse ``T(Θ)⁻¹`` written out by hand."""
    from jaxsim.control.auv_tracking import PAPER_LAMBDA, reference_velocity

    phi, theta, psi = 0.3, 0.2, 0.5
    eta = jnp.array([1.0, 2.0, 3.0, phi, theta, psi])
    target = jnp.array([[1.0, 2.0, 3.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]])  # on target, heading 0
    lam = jnp.asarray(PAPER_LAMBDA)
    nu_r = np.asarray(reference_velocity(lam, eta, target))
    t_inv = np.array(
        [
            [1.0, 0.0, -np.sin(theta)],
            [0.0, np.cos(phi), np.cos(theta) * np.sin(phi)],
            [0.0, -np.sin(phi), np.cos(theta) * np.cos(phi)],
        ]
    )
    e_att = -np.array([phi, theta, psi])  # Θ* = 0
    np.testing.assert_allclose(nu_r[3:], np.asarray(PAPER_LAMBDA[3:]) * (t_inv @ e_att), atol=1e-12)
    assert np.abs(nu_r[3:] - t_inv @ (np.asarray(PAPER_LAMBDA[3:]) * e_att)).max() > 1e-3
