"""Track loss at a gate (exact and soft) and the CV / coordinated-turn motion models."""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.estimation.motion_models import ct_transition, cv_ct_imm, cv_process_noise, cv_transition
from jaxsim.estimation.track_loss import first_miss, miss_distances, soft_track_loss, track_lost
from jaxsim.plants.vessel_target import vessel_manoeuvre, vessel_state


def test_track_lost_first_miss_and_gate_vector():
    d = miss_distances(np.array([[3.0, 4.0], [0.0, 20.0], [30.0, 40.0]]), np.zeros((3, 2)))
    np.testing.assert_allclose(d, [5.0, 20.0, 50.0])
    np.testing.assert_array_equal(track_lost(d, np.array([4.0, 10.0, 30.0, 60.0])), [True, True, True, False])
    assert not bool(track_lost(d, 30.0, mask=np.array([True, True, False])))
    assert int(first_miss(d, 10.0)) == 1 and int(first_miss(d, 60.0)) == -1


def test_first_miss_and_soft_loss_take_a_gate_vector_like_track_lost():
    d = jnp.array([10.0, 35.0, 20.0, 45.0])
    gates = np.array([5.0, 30.0, 40.0, 60.0])
    np.testing.assert_array_equal(first_miss(d, gates), [0, 1, 3, -1])
    for g, i in zip(gates, [0, 1, 3, -1]):
        assert int(first_miss(d, g)) == i
    soft = soft_track_loss(d, gates, 2.0)
    np.testing.assert_allclose(soft, [float(soft_track_loss(d, g, 2.0)) for g in gates], rtol=1e-12)
    np.testing.assert_allclose(soft_track_loss(d, gates, 1e-3), np.asarray(track_lost(d, gates), float), atol=1e-12)


def test_soft_track_loss_tends_to_the_event_and_is_a_probability():
    d = jnp.array([10.0, 35.0, 20.0])
    for gate, lost in ((30.0, 1.0), (40.0, 0.0)):
        np.testing.assert_allclose(soft_track_loss(d, gate, 1e-3), lost, atol=1e-12)
    # independent per-scan "probabilities" σ((d − g)/T): 1 − Π(1 − p_t)
    p = 1.0 / (1.0 + np.exp(-(np.asarray(d) - 30.0) / 5.0))
    np.testing.assert_allclose(soft_track_loss(d, 30.0, 5.0), 1.0 - np.prod(1.0 - p), rtol=1e-12)


def test_miss_distance_gradient_is_finite_at_zero_and_the_unit_vector_elsewhere():
    z = jnp.array([[1.0, 2.0], [3.0, 4.0]])
    pred = jnp.array([[1.0, 2.0], [0.0, 0.0]])  # scan 0: the plot is its own prediction (d = 0)
    g = jax.grad(lambda z: jnp.sum(miss_distances(z, pred)))(z)
    np.testing.assert_array_equal(g[0], [0.0, 0.0])
    np.testing.assert_allclose(g[1], [0.6, 0.8], rtol=1e-12)
    g_soft = jax.grad(lambda z: soft_track_loss(miss_distances(z, pred), 4.0, 1.0))(z)
    assert np.all(np.isfinite(g_soft))


@pytest.mark.parametrize("gate", [0.0, -10.0])
def test_non_positive_gate_raises(gate):
    with pytest.raises(ValueError, match="gate"):
        track_lost(jnp.ones(3), gate)
    with pytest.raises(ValueError, match="gate"):
        soft_track_loss(jnp.ones(3), gate, 1.0)


def test_cv_model_matrices():
    F, Q = cv_transition(3.0), cv_process_noise(3.0, 0.5)
    x = np.array([1.0, 2.0, 10.0, -4.0])
    np.testing.assert_allclose(F @ x, [31.0, -10.0, 10.0, -4.0])
    np.testing.assert_allclose(Q[0, 0], 0.5 * 9.0, rtol=1e-14)  # q dt³/3
    np.testing.assert_allclose(Q[0, 2], 0.5 * 4.5, rtol=1e-14)
    assert np.all(np.linalg.eigvalsh(Q) >= -1e-12)
    with pytest.raises(ValueError, match="dt"):
        cv_transition(0.0)


def test_coordinated_turn_step_follows_the_vessel_arc_and_reduces_to_cv():
    m = vessel_manoeuvre(speed=20.0, turn_radius=300.0, turn_start=0.0, turn_angle=math.pi / 2)
    s0, s1 = vessel_state(m, 6.0), vessel_state(m, 9.0)
    x0 = jnp.concatenate([s0.position, s0.velocity, jnp.array([20.0 / 300.0])])
    x1 = ct_transition(3.0, x0)
    np.testing.assert_allclose(x1[:2], s1.position, atol=1e-9)
    np.testing.assert_allclose(x1[2:4], s1.velocity, atol=1e-12)
    x_straight = jnp.array([1.0, 2.0, 10.0, -4.0, 0.0])
    np.testing.assert_allclose(
        ct_transition(3.0, x_straight)[:4], cv_transition(3.0) @ np.asarray(x_straight[:4]), atol=1e-12
    )
    jac = jax.jacfwd(lambda x: ct_transition(3.0, x))(x_straight)
    assert np.all(np.isfinite(jac))  # smooth at ω = 0


def test_cv_ct_imm_checks_switch_probability():
    with pytest.raises(ValueError, match="switch_prob"):
        cv_ct_imm(3.0, 0.01, 0.05, 1e-4, np.eye(2), switch_prob=1.5)
    with pytest.raises(ValueError, match="switch_prob"):
        cv_ct_imm(3.0, 0.01, 0.05, 1e-4, np.eye(2), switch_prob=[0.1, 0.1, 0.1])


@pytest.mark.parametrize("R", [np.eye(3), np.ones(2), np.array([[1.0, 0.0], [0.0, -1.0]])])
def test_cv_ct_imm_checks_plot_covariance(R):
    with pytest.raises(ValueError, match="R"):
        cv_ct_imm(3.0, 0.01, 0.05, 1e-4, R)


def test_imm_can_be_built_inside_jit_and_still_checks_concrete_transitions():
    # the study builds the CV+CT IMM per run, with the plot covariance R traced
    tr = jax.jit(lambda R: cv_ct_imm(3.0, 0.01, 0.05, 1e-4, R, switch_prob=0.05).transition)(jnp.eye(2))
    np.testing.assert_allclose(tr, [[0.95, 0.05], [0.05, 0.95]])
    from jaxsim.estimation.imm import imm, linear_member

    m = linear_member(np.eye(2), np.eye(2), np.eye(2), np.eye(2))
    with pytest.raises(ValueError, match="transition"):
        imm([m, m], np.array([[0.9, 0.2], [0.1, 0.9]]))
