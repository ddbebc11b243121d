"""Linearisation by jacfwd against the closed-form state space of the paper's plants."""

import jax.numpy as jnp
import numpy as np
import pytest
import scipy.signal

from jaxsim.core.linearize import find_equilibrium, linearize
from jaxsim.core.system import Plant
from jaxsim.core.transfer_function import ss2tf
from jaxsim.plants.second_order import astatic_plant, static_plant
from tests.jax_log import jax_messages


def test_linearised_second_order_plants_have_the_paper_transfer_functions():
    lin = linearize(static_plant(), jnp.zeros(2), jnp.zeros(1))
    num, den = ss2tf(lin.a, lin.b, lin.c, lin.d)
    num_ref, den_ref = scipy.signal.normalize([2.0], [0.05, 0.6, 1.0])
    np.testing.assert_allclose(den, den_ref, rtol=1e-13)
    np.testing.assert_allclose(np.trim_zeros(np.asarray(num), "f"), num_ref[0], rtol=1e-13)
    lin = linearize(astatic_plant(), jnp.zeros(2), jnp.zeros(1))
    np.testing.assert_allclose(lin.a, [[0.0, 1.0], [0.0, -10.0]])
    np.testing.assert_allclose(lin.b, [[0.0], [20.0]])
    np.testing.assert_allclose(lin.c, [[1.0, 0.0]])


def pendulum_dynamics(p, x, u, t):
    return jnp.array([x[1], -p["g"] * jnp.sin(x[0]) - p["c"] * x[1] + u[0]])


PEND = Plant({"g": 9.81, "c": 0.3}, pendulum_dynamics, lambda p, x: x[:1], 2, 1, 1, "pendulum")


def test_equilibrium_and_linearisation_of_a_nonlinear_plant():
    u_eq = jnp.array([9.81 * np.sin(0.4)])
    eq = find_equilibrium(lambda x: PEND.f(x, u_eq, 0.0), jnp.array([0.3, 0.1]))
    np.testing.assert_allclose(eq.z, [0.4, 0.0], atol=1e-12)
    assert float(eq.residual_norm) < 1e-12
    lin = linearize(PEND, eq.z, u_eq)
    np.testing.assert_allclose(lin.a, [[0.0, 1.0], [-9.81 * np.cos(0.4), -0.3]], rtol=1e-12)


def test_bad_shapes():
    with pytest.raises(ValueError, match="x0: expected shape"):
        linearize(PEND, jnp.zeros(3), jnp.zeros(1))
    with pytest.raises(ValueError, match="u0: expected shape"):
        linearize(PEND, jnp.zeros(2), jnp.zeros(2))


def _decay_plant(params):
    return Plant(
        params=params,
        dynamics=_decay,
        output=_identity,
        n_states=1,
        n_inputs=1,
        n_outputs=1,
    )


def _identity(p, x):
    return x


def _decay(p, x, u, t):
    return -p["a"] * p.get("o", _Gain()).k * x + u


class _Gain:  # a parameter that is not a JAX type (not a pytree: a leaf jit cannot take)
    k = 2.0


def test_one_compilation_for_new_parameters_and_points_and_eager_for_foreign_parameters():
    """The Jacobians run as one jitted program reused for new parameter values and points (the
    plant's functions are the key: module-level ones here, a fresh lambda would be a new key); a
    parameter that is not a JAX type is linearised eagerly."""
    with jax_messages() as messages:
        lins = [linearize(_decay_plant({"a": a}), jnp.full(1, a), jnp.zeros(1)) for a in (3.0, 5.0)]
    assert len([m for m in messages if m.startswith("Compiling jit(_jacobians)")]) == 1, messages
    assert [float(lin.a[0, 0]) for lin in lins] == [-6.0, -10.0]  # −a·k with the default k = 2
    foreign = linearize(_decay_plant({"a": 3.0, "o": _Gain()}), jnp.zeros(1), jnp.zeros(1))
    assert float(foreign.a[0, 0]) == -6.0 and float(foreign.b[0, 0]) == 1.0
