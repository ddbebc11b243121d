"""MJCF free body vs the AUV ODE (jaxsim.plants.auv) reduced to its rigid body."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("mujoco.mjx")

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402

from jaxsim.control.open_loop import feedforward  # noqa: E402
from jaxsim.core.integrators import EULER, RK4  # noqa: E402
from jaxsim.core.rollout import ClosedLoop, Timing, simulate  # noqa: E402
from jaxsim.core.signals import Sine  # noqa: E402
from jaxsim.mjx.auv import auv_mjx_plant, from_mjx_state, ode_rigid_body_plant, to_mjx_state  # noqa: E402

X0 = jnp.array([1.0, -2.0, 3.0, 0.2, -0.3, 0.5, 0.5, 0.1, -0.2, 0.3, -0.2, 0.4])


def test_state_conversion_round_trip():
    xs = X0 * jnp.linspace(-1.5, 1.5, 7)[:, None]
    back = jax.vmap(lambda x: from_mjx_state(to_mjx_state(x)))(xs)
    np.testing.assert_allclose(back, xs, atol=1e-12)
    assert np.allclose(np.linalg.norm(np.asarray(jax.vmap(to_mjx_state)(xs))[:, 3:7], axis=1), 1.0)


@pytest.mark.slow
def test_rigid_body_trajectory_matches_ode():
    """5 s of body-frame forces and moments (all six channels, tumbling motion): MuJoCo free body
    (``mjx.step``, h = 1 ms) vs RK4 on the Fossen rigid-body equations ``M_R ν̇ + C_R(ν) ν = τ`` with
    zero added mass, damping and restoring forces.  Stated tolerance: 2e-3 (m, rad, m/s, rad/s)."""
    inputs = Sine(
        amplitude=jnp.array([50.0, 30.0, 20.0, 5.0, 8.0, 6.0]),
        frequency=jnp.array([0.2, 0.3, 0.25, 0.4, 0.35, 0.3]),
        offset=jnp.array([20.0, 0.0, 0.0, 1.0, 0.0, 0.0]),
    )
    timing = Timing(t_final=5.0, dt=1e-3, controller_period=0.01)

    def run(plant, x0, solver):
        return simulate(
            ClosedLoop(plant=plant, controller=feedforward(), reference=inputs), x0, timing, solver=solver
        ).x

    x_ode = jax.jit(lambda p, x: run(p, x, RK4))(ode_rigid_body_plant(), X0)
    x_mjx = jax.jit(lambda p, x: run(p, x, EULER))(auv_mjx_plant(field="step"), to_mjx_state(X0))
    x_mjx = jax.vmap(from_mjx_state)(x_mjx)
    diff = np.array(x_mjx - x_ode)
    diff[:, 3:6] = (diff[:, 3:6] + np.pi) % (2 * np.pi) - np.pi  # angles modulo 2π
    assert np.abs(np.asarray(x_ode[:, 9:])).max() > 0.5  # it tumbles: the Coriolis terms matter
    assert np.abs(diff).max() < 2e-3, np.abs(diff).max(axis=0)
