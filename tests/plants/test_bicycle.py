"""Dynamic bicycle model: steady-state cornering closed form and SciPy solve_ivp on the same ODE."""

import jax
import jax.numpy as jnp
import numpy as np
from scipy.integrate import solve_ivp

from jaxsim.plants import bicycle


def test_steady_yaw_rate_matches_closed_form():
    p = bicycle.BicycleParams(Cr=1.0e5)  # understeering (K_us > 0)
    L, V, delta = p.lf + p.lr, p.V, 0.02
    kus = p.m / L * (p.lr / p.Cf - p.lf / p.Cr)
    assert float(bicycle.understeer_gradient(p)) > 0
    x = jnp.zeros(5)
    u = jnp.array([delta, 0.0])
    step = jax.jit(lambda x: bicycle.rk4_step(p, x, u, 0.01))
    for _ in range(1500):
        x = step(x)
    assert abs(float(x[4]) - V / (L + kus * V**2) * delta) < 1e-8
    assert abs(float(bicycle.steady_yaw_rate(p, delta)) - V / (L + kus * V**2) * delta) < 1e-15


def test_rk4_matches_solve_ivp():
    p = bicycle.BicycleParams()
    u = jnp.array([0.05, 800.0])
    x0 = np.array([0.0, 0.0, 0.3, 0.2, -0.1])
    x = jnp.asarray(x0)
    for _ in range(300):
        x = bicycle.rk4_step(p, x, u, 0.01)
    ref = solve_ivp(
        lambda t, y: np.asarray(bicycle.dynamics(p, jnp.asarray(y), u)), (0, 3.0), x0, rtol=1e-11, atol=1e-11
    )
    np.testing.assert_allclose(np.asarray(x), ref.y[:, -1], atol=1e-7)
