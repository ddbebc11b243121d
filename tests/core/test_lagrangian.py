"""Euler–Lagrange by autodiff against closed forms."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.lagrangian import body_energy, euler_lagrange, point_force, rotation


def test_rotation_is_rodrigues():
    rot = rotation((0, 0, 2.0), 0.3)  # axis normalised
    np.testing.assert_allclose(
        rot, [[np.cos(0.3), -np.sin(0.3), 0], [np.sin(0.3), np.cos(0.3), 0], [0, 0, 1]], atol=1e-15
    )


def test_compound_pendulum_with_spinning_disc():
    """A rod of mass m, centre at distance l below a hinge about y, centroidal inertia J about y:
    (J + m l²) θ̈ = −m g l sin θ + τ — plus a force at the tip (generalised force L·F·cos θ)."""
    m, l, j, g, tip = 2.0, 0.3, 0.05, 9.81, 0.6

    def pose(q):
        return rotation((0, 1, 0), q[0]), jnp.zeros(3)

    kinetic, potential = body_energy(pose, m, jnp.array([0.0, 0.0, -l]), jnp.array([0.01, j, 0.01]), g)
    q, qd = jnp.array([0.7]), jnp.array([-1.3])
    force_x = 1.5  # N along the body's x axis at the tip (0, 0, −tip)
    gen = point_force(pose, jnp.array([0.0, 0.0, -tip]), jnp.array([force_x, 0.0, 0.0]), q)
    qdd = jax.jit(euler_lagrange, static_argnums=(0, 1))(kinetic, potential, q, qd, gen)
    # r × F about y for r = R(0,0,−tip), F = R(F,0,0): y-component = −tip·F  (body frame, rotation-invariant)
    expected = (-m * g * l * np.sin(0.7) - tip * force_x) / (j + m * l**2)
    np.testing.assert_allclose(qdd, [expected], rtol=1e-12)
