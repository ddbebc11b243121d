"""3-DOF helicopter ODE: closed-form inertia, hover trim, energy balance."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.core.integrators import RK4
from jaxsim.core.pytree import replace
from jaxsim.plants import helicopter_3dof as heli

P = heli.HelicopterParams()


def test_mass_matrix_at_rest_matches_the_parameters():
    """At θ = ψ = 0 (closed forms): travel Je + Jp (the motors at ±lh add m_h lh² = Jp about the vertical),
    elevation Je + m_h hp² + ε, pitch Jp + m_h hp²."""
    kinetic, _ = heli.energies(P)
    mass = jax.hessian(kinetic, argnums=1)(jnp.zeros(3), jnp.zeros(3))
    d = heli.derived(P)
    eps, mh_hp2 = heli.EPS_INERTIA, float(d["m_h"]) * P.hp**2
    np.testing.assert_allclose(np.diag(mass), [P.je + P.jp, P.je + mh_hp2 + eps, P.jp + mh_hp2], rtol=1e-12)
    np.testing.assert_allclose(float(d["m_h"]) * P.lh**2, P.jp, rtol=1e-12)


def test_hover_voltage_is_a_trim_point():
    u = heli.hover_voltage(P)
    x = jnp.concatenate([jnp.zeros(6), P.kf * u])
    np.testing.assert_allclose(heli.dynamics(P, x, u, 0.0), np.zeros(8), atol=1e-14)


@pytest.mark.slow
def test_energy_is_conserved_without_damping_and_thrust():
    """No damping, no thrust: T + V is constant along a large-angle RK4 trajectory."""
    p = replace(P, damping=0.0)
    kinetic, potential = heli.energies(p)
    x0 = jnp.array([0.0, 0.4, -0.6, 0.5, -0.3, 1.2, 0.0, 0.0])

    def step(x, _):
        x = RK4.step(lambda t, z: heli.dynamics(p, z, jnp.zeros(2), t), 0.0, x, 1e-3)
        return x, kinetic(x[:3], x[3:6]) + potential(x[:3])

    _, energy = jax.jit(lambda x: jax.lax.scan(step, x, None, length=2000))(x0)
    assert np.ptp(np.asarray(energy)) < 1e-9 * abs(float(energy[0])) + 1e-10
