"""Orbital-station rigid body: invariants without orbit rate and torque, SciPy ``solve_ivp`` with them."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from jaxsim.plants import orbital_station as st


def _rk4(f, x, h, n):
    def step(x, _):
        k1 = f(x)
        k2 = f(x + 0.5 * h * k1)
        k3 = f(x + 0.5 * h * k2)
        k4 = f(x + h * k3)
        return x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4), None

    return jax.lax.scan(step, x, None, length=n)[0]


def test_torque_free_invariants():
    p = st.StationParams(orbit_rate=0.0)
    x0 = jnp.array([0.9, 0.1, -0.3, 0.2, 1e-3, -2e-3, 3e-3])
    x0 = x0.at[:4].divide(jnp.linalg.norm(x0[:4]))
    x = jax.jit(lambda x: _rk4(lambda x: st.rhs(x, jnp.zeros(3), p), x, 1.0, 4000))(x0)
    j = np.asarray(p.inertia)

    def energy(x):
        return 0.5 * np.sum(j * np.asarray(x[4:]) ** 2)

    def momentum_orbital(x):  # inertial momentum in the (here inertial) orbital frame
        return np.asarray(st.dcm(x[:4])) @ (j * np.asarray(x[4:]))

    assert energy(x) == pytest.approx(energy(x0), rel=1e-9)
    np.testing.assert_allclose(momentum_orbital(x), momentum_orbital(x0), rtol=1e-8, atol=1e-6)
    assert float(jnp.linalg.norm(x[:4])) == pytest.approx(1.0, abs=1e-10)


def test_rest_is_equilibrium_and_gravity_gradient_against_solve_ivp():
    p = st.StationParams()
    # principal axes aligned with the orbital frame: a relative equilibrium of the gravity-gradient torque
    x_rest = st.rest_state(jnp.array([1.0, 0.0, 0.0, 0.0]), p)
    np.testing.assert_allclose(st.rhs(x_rest, jnp.zeros(3), p), 0.0, atol=1e-15)
    # tilted station under a constant torque: our RK4 against SciPy's DOP853 at tight tolerance
    q = jnp.array([0.95, 0.2, 0.15, -0.1])
    x0 = st.rest_state(q / jnp.linalg.norm(q), p)
    u = jnp.array([50.0, -30.0, 20.0])
    t_end, n = 2000.0, 2000
    x = jax.jit(lambda x: _rk4(lambda x: st.rhs(x, u, p), x, t_end / n, n))(x0)
    f = jax.jit(lambda x: st.rhs(x, u, p))
    ref = solve_ivp(
        lambda t, x: np.asarray(f(jnp.asarray(x))), (0, t_end), np.asarray(x0), method="DOP853", rtol=1e-11, atol=1e-13
    )
    np.testing.assert_allclose(np.asarray(x), ref.y[:, -1], rtol=1e-7, atol=1e-9)


def test_scaled_rhs_is_the_si_rhs_rescaled():
    p = st.StationParams()
    t_h, jz = 5400.0, p.inertia[2]
    x = jnp.array([0.8, 0.1, 0.5, 0.3, 1e-3, -1e-3, 2e-3])
    u = jnp.array([100.0, -200.0, 300.0])
    xs = x.at[4:].multiply(t_h)
    lhs = st.scaled_rhs(xs, u * t_h**2 / jz, p, t_h)
    rhs = st.rhs(x, u, p) * t_h
    np.testing.assert_allclose(lhs[:4], rhs[:4], rtol=1e-12)
    np.testing.assert_allclose(lhs[4:], rhs[4:] * t_h, rtol=1e-12)


def test_fuel_of_an_impulse():
    p = st.StationParams()
    assert float(st.fuel_kg(p.arm * p.isp * st.G0)) == pytest.approx(1.0)
