"""MJCF TRMS (MuJoCo rigid body + our motor models) against the ODE TRMS of jaxsim.plants.trms."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("mujoco.mjx")

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402

from jaxsim.control.open_loop import feedforward  # noqa: E402
from jaxsim.core.integrators import EULER, RK4  # noqa: E402
from jaxsim.core.linearize import linearize  # noqa: E402
from jaxsim.core.rollout import ClosedLoop, Timing, simulate  # noqa: E402
from jaxsim.core.signals import Sine  # noqa: E402
from jaxsim.mjx.trms import TO_ODE, ode_state, trms_mjx_plant  # noqa: E402
from jaxsim.plants import trms  # noqa: E402

P = trms.FEEDBACK_MANUFACTURER


@pytest.fixture(scope="module")
def hover():
    x_eq, u_eq, res = trms.hover_equilibrium(P, pitch=0.1)
    assert float(res) < 1e-10
    return x_eq, u_eq


def test_vector_field_equals_ode():
    """Same ẋ at random states and inputs (MuJoCo's inertia, gravity and damping vs the ODE's)."""
    key = jax.random.PRNGKey(3)
    xs = jax.random.normal(key, (6, 7)) * jnp.array([0.5, 2.0, 1.0, 1.0, 1.0, 1.0, 0.2])
    us = jax.random.uniform(jax.random.fold_in(key, 1), (6, 2), minval=-3.0, maxval=3.0)
    plant = trms_mjx_plant(P)
    f_mjx = jax.jit(jax.vmap(lambda x, u: plant.f(x, u, 0.0)))(ode_state(xs), us)
    f_ode = jax.vmap(lambda x, u: trms.dynamics(P, x, u, 0.0))(xs, us)
    np.testing.assert_allclose(ode_state(f_mjx), f_ode, rtol=1e-11, atol=1e-11)


def test_linearisation_equals_ode(hover):
    """``jacfwd`` through ``mjx.forward`` gives the ODE's (A, B, C) at the hover equilibrium."""
    x_eq, u_eq = hover
    lin_ode = trms.linearize_at(P, x_eq, u_eq)
    lin_mjx = jax.jit(linearize)(trms_mjx_plant(P), x_eq[TO_ODE], u_eq)
    perm = np.ix_(TO_ODE, TO_ODE)
    np.testing.assert_allclose(lin_mjx.a[perm], lin_ode.a, atol=1e-10)
    np.testing.assert_allclose(lin_mjx.b[TO_ODE], lin_ode.b, atol=1e-10)
    np.testing.assert_allclose(lin_mjx.c[:, TO_ODE], lin_ode.c, atol=1e-12)


@pytest.mark.slow
def test_step_linearisation_is_first_order_in_timestep(hover):
    """``jacfwd`` through ``mjx.step`` gives ``(Φ − I)/h = A + O(h)``: the error shrinks 4× for h/4."""
    x_eq, u_eq = hover
    a_ode = np.asarray(trms.linearize_at(P, x_eq, u_eq).a)
    errors = []
    lin_fn = jax.jit(linearize)  # the timestep is a leaf of the MJX model: one compilation for both
    for h in (1e-3, 2.5e-4):
        lin = lin_fn(trms_mjx_plant(P, field="step", timestep=h), x_eq[TO_ODE], u_eq)
        errors.append(np.abs(np.asarray(lin.a)[np.ix_(TO_ODE, TO_ODE)] - a_ode).max())
    assert errors[0] < 1e-3 * np.abs(a_ode).max() ** 2  # |O(h)| ≲ h‖A‖²
    assert 3.5 < errors[0] / errors[1] < 4.5


@pytest.mark.slow
def test_trajectory_matches_ode(hover):
    """10 s of the same input sequence: MuJoCo's semi-implicit Euler (h = 1 ms, ``mjx.step``) vs RK4
    on the ODE.  Stated tolerance: angles 1e-3 rad, rates 2e-3 rad/s, motor states 2e-4."""
    x_eq, u_eq = hover
    inputs = Sine(amplitude=jnp.array([0.3, 0.3]), frequency=jnp.array([0.2, 0.11]), offset=u_eq)
    timing = Timing(t_final=10.0, dt=1e-3, controller_period=0.01)

    def run(plant, x0, solver):
        return simulate(
            ClosedLoop(plant=plant, controller=feedforward(), reference=inputs), x0, timing, solver=solver
        ).x

    x_ode = jax.jit(lambda x0: run(trms.trms_plant(P), x0, RK4))(x_eq)
    x_mjx = ode_state(jax.jit(lambda x0: run(trms_mjx_plant(P, field="step"), x0, EULER))(x_eq[TO_ODE]))
    err = np.abs(np.asarray(x_mjx - x_ode)).max(axis=0)
    assert np.abs(np.asarray(x_ode[:, :2] - x_eq[:2])).max() > 0.1  # the input moves the stand
    assert np.all(err[:2] < 1e-3) and np.all(err[2:4] < 2e-3) and np.all(err[4:] < 2e-4), err
