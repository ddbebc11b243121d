"""MJCF 3-DOF helicopter (MuJoCo's Newton–Euler) against the Euler–Lagrange ODE of the same geometry."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("mujoco.mjx")

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402

from jaxsim.control.open_loop import feedforward  # noqa: E402
from jaxsim.core.integrators import EULER, HEUN  # noqa: E402
from jaxsim.core.rollout import ClosedLoop, Timing, simulate  # noqa: E402
from jaxsim.core.signals import Sine  # noqa: E402
from jaxsim.mjx.helicopter_3dof import helicopter_mjx_plant  # noqa: E402
from jaxsim.plants import helicopter_3dof as heli  # noqa: E402

P = heli.HelicopterParams()


@pytest.mark.slow
def test_vector_field_equals_lagrangian_ode():
    """Coupled inertia, gravity, thrust mapping and damping agree at random states (large angles)."""
    key = jax.random.PRNGKey(0)
    xs = jax.random.normal(key, (5, 8)) * jnp.array([1.0, 0.4, 0.5, 0.5, 0.5, 1.0, 1.0, 1.0])
    us = jax.random.uniform(jax.random.fold_in(key, 1), (5, 2), minval=0.0, maxval=2.0)
    plant = helicopter_mjx_plant(P)
    f_mjx = jax.jit(jax.vmap(lambda x, u: plant.f(x, u, 0.0)))(xs, us)
    f_ode = jax.jit(jax.vmap(lambda x, u: heli.dynamics(P, x, u, 0.0)))(xs, us)
    assert np.abs(np.asarray(f_ode[:, 3:6])).max() > 1.0  # the accelerations are not trivial
    np.testing.assert_allclose(f_mjx, f_ode, rtol=1e-10, atol=1e-10)


@pytest.mark.slow
def test_trajectory_matches_ode():
    """5 s of the same voltages: ``mjx.step`` (h = 1 ms) vs Heun on the ODE.  Stated tolerance:
    angles 2e-3 rad, rates 5e-3 rad/s, thrusts 1e-3 N (MuJoCo's semi-implicit Euler is first order)."""
    u_hover = heli.hover_voltage(P)
    inputs = Sine(amplitude=jnp.array([0.3, 0.1]), frequency=jnp.array([0.3, 0.5]), offset=u_hover + 0.1)
    timing = Timing(t_final=5.0, dt=1e-3, controller_period=0.01)
    x0 = jnp.concatenate([jnp.zeros(6), P.kf * u_hover])

    def run(plant, solver):
        return simulate(
            ClosedLoop(plant=plant, controller=feedforward(), reference=inputs), x0, timing, solver=solver
        ).x

    ode, mjx = heli.helicopter_plant(P), helicopter_mjx_plant(P, field="step")
    x_ode = jax.jit(lambda plant: run(plant, HEUN))(ode)  # O(h²) ≈ 1e-6: negligible next to MuJoCo's O(h)
    x_mjx = jax.jit(lambda plant: run(plant, EULER))(mjx)
    assert np.abs(np.asarray(x_ode[:, :3])).max(axis=0).min() > 0.05  # all three axes move
    err = np.abs(np.asarray(x_mjx - x_ode)).max(axis=0)
    assert np.all(err[:3] < 2e-3) and np.all(err[3:6] < 5e-3) and np.all(err[6:] < 1e-3), err
