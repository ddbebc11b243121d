"""Sampled LQG tracker: exact agreement with its closed-loop matrix, and offset-free tracking of a
linear plant (the TRMS design model)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.control.lqg_tracker import design, lqg_tracker, sampled_closed_loop_matrix
from jaxsim.core.integrators import ExponentialEuler
from jaxsim.core.rollout import ClosedLoop, Timing, simulate
from jaxsim.core.signals import Constant
from jaxsim.core.system import Plant
from jaxsim.plants.trms import FEEDBACK_MANUFACTURER, hover_equilibrium, linearize_at

TS = 0.01


@pytest.fixture(scope="module")
def setup():
    x_eq, u_eq, _ = hover_equilibrium(FEEDBACK_MANUFACTURER, -0.05)
    lin = linearize_at(FEEDBACK_MANUFACTURER, x_eq, u_eq)
    params = design(
        lin, x_eq, u_eq, np.diag([40.0, 25, 1, 1, 1, 1, 1]), np.eye(2) * 0.2, np.eye(7) * 1e-2, np.eye(2) * 1e-6, TS
    )

    def f(p, x, u, t):
        return lin.a @ (x - p[0]) + lin.b @ (u - p[1])

    plant = Plant((x_eq, u_eq), f, lambda p, x: x[:2], n_states=7, n_inputs=2, n_outputs=2, name="trms_lin")
    return lin, params, plant, np.asarray(x_eq)


def test_rollout_equals_the_sampled_closed_loop_matrix(setup):
    lin, params, plant, x_eq = setup
    ctrl, est = lqg_tracker(params)
    loop = ClosedLoop(plant, ctrl, reference=Constant(np.asarray(params.y_eq)), estimator=est)
    dx0 = np.array([0.05, -0.1, 0.0, 0.2, 0.1, 0.0, 0.0])
    traj = simulate(loop, jnp.asarray(x_eq + dx0), Timing(t_final=2.0, dt=TS), solver=ExponentialEuler())
    phi = np.asarray(sampled_closed_loop_matrix(lin, params, TS))
    z = np.concatenate([dx0, np.zeros(7)])
    for k in range(traj.x.shape[0]):
        np.testing.assert_allclose(traj.x[k] - x_eq, z[:7], atol=1e-11)
        z = phi @ z
    assert np.max(np.abs(np.linalg.eigvals(phi))) < 1


def test_linear_plant_tracks_a_constant_reference_without_offset(setup):
    lin, params, plant, x_eq = setup
    ctrl, est = lqg_tracker(params)
    target = np.asarray(params.y_eq) + np.array([0.1, -0.2])
    loop = ClosedLoop(plant, ctrl, reference=Constant(target), estimator=est)
    traj = simulate(loop, jnp.asarray(x_eq), Timing(t_final=40.0, dt=TS, save_every=100), solver=ExponentialEuler())
    np.testing.assert_allclose(traj.y[-1], target, atol=1e-6)
    np.testing.assert_allclose(traj.x_hat[-1], traj.x[-1], atol=1e-6)  # the observer converged


def test_design_is_differentiable_in_the_weights(setup):
    lin, _, _, x_eq = setup
    x_eq_, u_eq = jnp.asarray(x_eq), jnp.zeros(2)

    def rho(logw):
        p = design(
            lin, x_eq_, u_eq, jnp.diag(jnp.exp(logw[:7])), jnp.eye(2) * 0.2, jnp.eye(7) * 1e-2, jnp.eye(2) * 1e-6, TS
        )
        return jnp.sum(sampled_closed_loop_matrix(lin, p, TS) ** 2)

    logw = np.log(np.array([40.0, 25, 1, 1, 1, 1, 1]))
    g = jax.grad(rho)(logw)
    e = np.eye(7)[0] * 1e-6
    np.testing.assert_allclose(g[0], (rho(logw + e) - rho(logw - e)) / 2e-6, rtol=1e-6)
