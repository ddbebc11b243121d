"""Ball on a swing: the closed-form plant against Euler–Lagrange by autodiff and hand-derived (θ, s) equations, energy
conservation, the αβγ reduction against the same oracle, the integral of motion and the transverse
linearisation against finite differences."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.core.lagrangian import euler_lagrange
from jaxsim.plants import ball_on_swing as bos

P = bos.Params()
K = 0.6


def oracle_accel(x, u, m=0.1, r=0.025, j_f=0.01, g=9.81):
    """(θ̈, φ̈) from the Euler–Lagrange equations in (θ, s), s = r tan φ, written by hand."""
    th, ph, thd, phd = x
    d, jb = r, 0.4 * m * r**2
    s, s1, s2 = d * math.tan(ph), d / math.cos(ph) ** 2, 2 * d * math.sin(ph) / math.cos(ph) ** 3
    sd = s1 * phd
    mass = np.array([[j_f + m * (d**2 + s**2) + jb, -m * d - jb / r], [-m * d - jb / r, m + jb / r**2]])
    rhs = np.array(
        [
            u - 2 * m * s * sd * thd - m * g * (s * math.cos(th) - d * math.sin(th)),
            m * s * thd**2 - m * g * math.sin(th),
        ]
    )
    tdd, sdd = np.linalg.solve(mass, rhs)
    return tdd, (sdd - s2 * phd**2) / s1


def test_dynamics_match_hand_derived_equations():
    rng = np.random.default_rng(1)
    f = jax.jit(lambda x, u: bos.dynamics(P, x, u))
    for _ in range(5):
        x = rng.uniform([-0.4, -0.5, -2, -3], [0.4, 0.5, 2, 3])
        u = rng.uniform(-1, 1)
        got = np.asarray(f(jnp.asarray(x), jnp.asarray(u)))
        np.testing.assert_allclose(got[:2], x[2:], rtol=0, atol=0)
        np.testing.assert_allclose(got[2:], oracle_accel(x, u), rtol=1e-10, atol=1e-10)


@pytest.mark.parametrize("p", [P, bos.Params(m=0.3, r=0.04, j_b=1e-4, j_f=0.02, d=0.06)], ids=["paper", "offset"])
def test_closed_form_equations_equal_euler_lagrange_autodiff(p):
    """The written-out ``M`` and ``h`` against autodiff of the energies: ``M = ∂²T/∂q̇²`` and the
    accelerations of :func:`jaxsim.core.lagrangian.euler_lagrange` (also with ``d ≠ r``)."""

    def both(x, u):
        q, qd = x[:2], x[2:]
        mass, _ = bos.mass_and_bias(p, q, qd)
        mass_ad = jax.hessian(lambda b: bos.kinetic(p, q, b))(qd)
        force = jnp.stack([u, jnp.zeros_like(u)])
        qdd_ad = euler_lagrange(lambda a, b: bos.kinetic(p, a, b), lambda a: bos.potential(p, a), q, qd, force)
        return mass, mass_ad, bos.dynamics(p, x, u)[2:], qdd_ad

    both = jax.jit(both)
    rng = np.random.default_rng(7)
    for _ in range(5):
        x = jnp.asarray(rng.uniform([-0.6, -0.9, -3, -4], [0.6, 0.9, 3, 4]))
        mass, mass_ad, qdd, qdd_ad = both(x, jnp.asarray(rng.uniform(-1, 1)))
        np.testing.assert_allclose(mass, mass_ad, rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(qdd, qdd_ad, rtol=1e-11, atol=1e-11)


def test_energy_conserved_without_torque():
    field = jax.jit(lambda x: bos.dynamics(P, x, jnp.asarray(0.0)))
    x = jnp.array([0.2, -0.3, 0.5, 1.0])
    e0 = float(bos.energy(P, x))
    h = 5e-4
    for _ in range(200):
        k1 = field(x)
        k2 = field(x + h / 2 * k1)
        k3 = field(x + h / 2 * k2)
        k4 = field(x + h * k3)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    assert abs(float(bos.energy(P, x)) - e0) < 1e-10 * abs(e0)
    # and the energy is not trivially constant: a torque changes it at the rate u·θ̇
    x0 = jnp.array([0.2, -0.3, 0.5, 1.0])
    xd = bos.dynamics(P, x0, jnp.asarray(0.7))
    rate = jax.grad(lambda z: bos.energy(P, z))(x0) @ xd
    assert float(rate) == pytest.approx(0.7 * 0.5, rel=1e-10)


@pytest.mark.parametrize("phi", [-0.35, 0.1, 0.3])
def test_reduced_equation_matches_constrained_oracle(phi):
    phd = 1.7
    a, b, c = np.asarray(bos.abg(P, K, jnp.asarray(phi)))
    # on θ = kφ with θ̈ = kφ̈: the unactuated row of the oracle, solved for φ̈
    m, r, g = 0.1, 0.025, 9.81
    jb, d = 0.4 * m * r**2, r
    s, s1, s2 = d * math.tan(phi), d / math.cos(phi) ** 2, 2 * d * math.sin(phi) / math.cos(phi) ** 3
    th, thd = K * phi, K * phd
    mts, mss = -m * d - jb / r, m + jb / r**2
    # mts θ̈ + mss (s1 φ̈ + s2 φ̇²) − m s θ̇² + m g sin θ = 0
    pdd = -(mss * s2 * phd**2 - m * s * thd**2 + m * g * math.sin(th)) / (mts * K + mss * s1)
    assert -(b * phd**2 + c) / a == pytest.approx(pdd, rel=1e-10)
    # the PFL with v = 0 on the constraint gives the same φ̈
    x = jnp.array([th, phi, thd, phd])
    assert float(bos.phi_ddot(P, K, x, jnp.asarray(0.0))[0]) == pytest.approx(pdd, rel=1e-10)


def test_integral_constant_along_reduced_flow():
    z = jnp.array([-0.3, 0.4])
    f = jax.jit(lambda z: bos.reduced_field(P, K, z))
    integral = jax.jit(lambda z: bos.integral(P, K, z[0], z[1]))
    i0 = float(integral(z))
    h = 1e-3
    for _ in range(150):
        k1 = f(z)
        k2 = f(z + h / 2 * k1)
        k3 = f(z + h / 2 * k2)
        k4 = f(z + h * k3)
        z = z + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    assert float(integral(z)) == pytest.approx(i0, rel=1e-9)
    assert abs(float(z[0]) + 0.3) > 0.05  # it moved


def test_transverse_linearisation_against_finite_differences():
    z = jnp.array([0.05, -2.0])
    a, b = jax.jit(lambda z: bos.transverse_linearisation(P, K, z))(z)
    eps = 1e-6
    jrate = jax.jit(lambda w: bos.integral_rate(P, K, z[0], z[1], w[0], w[1], w[2]))
    rate = lambda w: float(jrate(jnp.asarray(w)))  # noqa: E731
    fd = [(rate(eps * e) - rate(-eps * e)) / (2 * eps) for e in np.eye(3)]
    np.testing.assert_allclose([a[0, 1], a[0, 2], b[0]], fd, rtol=1e-6)
    assert rate(np.zeros(3)) == pytest.approx(0.0, abs=1e-9)  # dI/dt = 0 on the constraint with v = 0
    np.testing.assert_array_equal(np.asarray(a[1:]), [[0, 0, 1], [0, 0, 0]])


@pytest.mark.slow  # one orbit compilation (~10 s here); the study test covers it too
def test_orbit_closes_and_rejects_odd_samples():
    period, z = jax.jit(lambda: bos.orbit(P, K, 0.2, 80))()
    assert float(jnp.max(jnp.abs(z[-1] - z[0]))) < 1e-6 and abs(float(z[40, 0]) + 0.2) < 1e-6
    with pytest.raises(ValueError, match="samples"):
        bos.orbit(P, K, 0.2, 81)
    with pytest.raises(ValueError, match="m must be positive"):
        bos.orbit(bos.Params(m=-1.0), K, 0.2, 80)
