"""6-DOF Fossen AUV (seed 002): rigid body against Newton–Euler, energy balance, skew-symmetric C,
restoring forces from the potential, bad input."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.plants import auv, marine


def _random_spd(key, n=6):
    a = jax.random.normal(key, (n, n))
    return a @ a.T + n * jnp.eye(n)


def _conservative(params):
    """Damping and restoring off."""
    return auv.AUVParams(
        M_R=params.M_R,
        M_A=params.M_A,
        d1=jnp.zeros(6),
        d2=jnp.zeros(6),
        weight=0.0,
        buoyancy=0.0,
        r_g=params.r_g,
        r_b=params.r_b,
    )


def test_paper_values_and_deviation():
    # paper table: M_n = M_R + M_A, true = nominal + Δ (assumed sign)
    np.testing.assert_allclose(np.diag(auv.nominal_params().mass_matrix), [185, 255, 255, 15.2, 33.0, 33.0])
    true = auv.true_params()
    np.testing.assert_allclose(np.diag(true.mass_matrix), [325, 395, 395, 19.2, 40.0, 40.0])
    np.testing.assert_allclose(true.d1, [27, 155, 155, 30, 110, 110])
    assert float(true.mass) == 170.0 and true.inertia.shape == (3, 3)
    # restoring: BG·W·sin θ in pitch with W = 170·9.81, BG = 0.01 m (paper: 0.01 m offset)
    g = auv.restoring(auv.nominal_params(), jnp.array([0.0, 0.3, 0.0]))
    np.testing.assert_allclose(g, [0, 0, 0, 0, 0.01 * 170 * 9.81 * np.sin(0.3), 0], atol=1e-12)


def test_rigid_body_forces_match_newton_euler():
    """M_R ν̇ + C_R(ν)ν equals m(v̇ + ω×v), I ω̇ + ω×Iω (body-frame Newton–Euler, CG at origin)."""
    p = auv.nominal_params()
    key = jax.random.PRNGKey(3)
    for k in jax.random.split(key, 4):
        nu, nu_dot = jax.random.normal(k, (2, 6))
        v, w = nu[:3], nu[3:]
        inertia = np.asarray(p.inertia)
        force = 170.0 * (nu_dot[:3] + np.cross(w, v))
        moment = inertia @ nu_dot[3:] + np.cross(w, inertia @ w)
        np.testing.assert_allclose(
            auv.rigid_body_forces(p, nu, nu_dot), np.concatenate([force, moment]), rtol=1e-12, atol=1e-10
        )


def test_coriolis_skew_symmetric_for_any_spd_mass():
    for k in jax.random.split(jax.random.PRNGKey(0), 5):
        k1, k2 = jax.random.split(k)
        m = _random_spd(k1)
        nu = jax.random.normal(k2, (6,))
        c = marine.coriolis_from_mass(m, nu)
        np.testing.assert_allclose(c + c.T, 0.0, atol=1e-12)
        assert abs(float(nu @ c @ nu)) < 1e-10


def test_kinetic_energy_rate_equals_power_of_tau():
    """Damping and restoring off: d/dt ½νᵀMν = νᵀτ, pointwise and over an RK4 trajectory."""
    p = _conservative(auv.true_params())
    m = auv.model(p)
    x0 = auv.initial_state([1.0, -2.0, 3.0], [0.2, -0.3, 1.0], [0.5, -0.2, 0.3, 0.4, -0.6, 0.8])

    def tau(t):
        return jnp.array([30.0 * jnp.sin(t), -20.0, 10.0 * jnp.cos(2 * t), 3.0, -2.0 * t, 1.0])

    nu_dot = auv.acceleration(m, x0, tau(0.0))
    np.testing.assert_allclose(x0[6:] @ p.mass_matrix @ nu_dot, x0[6:] @ tau(0.0), rtol=1e-12)

    h, n = 1e-3, 2000
    f = lambda x, t: auv.dynamics(m, x, tau(t), t)  # noqa: E731

    def step(carry, k):
        x, work = carry
        t = k * h
        k1 = f(x, t)
        k2 = f(x + 0.5 * h * k1, t + 0.5 * h)
        k3 = f(x + 0.5 * h * k2, t + 0.5 * h)
        k4 = f(x + h * k3, t + h)
        x1 = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        power = lambda xx, tt: xx[6:] @ tau(tt)  # noqa: E731
        work = work + h / 6 * (power(x, t) + 4 * power(x + 0.5 * h * k2, t + 0.5 * h) + power(x1, t + h))
        return (x1, work), None

    (x1, work), _ = jax.lax.scan(step, (x0, 0.0), jnp.arange(n))
    de = auv.energy(p, x1) - auv.energy(p, x0)
    assert abs(float(work)) > 1.0  # τ does real work
    np.testing.assert_allclose(de, work, rtol=1e-6)


def test_restoring_forces_derive_from_potential():
    """With damping off the total energy (kinetic + potential) changes only by νᵀτ: g = Jᵀ ∇V."""
    p = auv.AUVParams(d1=jnp.zeros(6), d2=jnp.zeros(6), buoyancy=1600.0, r_b=jnp.array([0.1, -0.05, -0.02]))
    m = auv.model(p)
    x = auv.initial_state([0.3, 0.2, 5.0], [0.4, -0.5, 2.0], [0.3, 0.1, -0.2, 0.5, 0.3, -0.4])
    tau = jnp.array([5.0, -3.0, 2.0, 1.0, 0.5, -0.7])
    x_dot = auv.dynamics(m, x, tau, 0.0)
    _, de = jax.jvp(lambda z: auv.energy(p, z), (x,), (x_dot,))
    np.testing.assert_allclose(de, x[6:] @ tau, rtol=1e-10)


def test_kinematics_jacobian():
    eta = jnp.array([1.0, 2.0, 3.0, 0.3, -0.4, 2.5])
    j = auv.kinematics(eta)
    r = j[:3, :3]
    np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(j @ marine.kinematics_jacobian_inverse(eta), np.eye(6), atol=1e-12)
    np.testing.assert_allclose(marine.euler_from_rotation(r), eta[3:], atol=1e-12)
    # Euler rates: R(Θ(t)) with Θ̇ = T ω must satisfy Ṙ = R S(ω)
    omega = jnp.array([0.2, -0.1, 0.3])
    _, r_dot = jax.jvp(marine.rotation_zyx, (eta[3:],), (j[3:, 3:] @ omega,))
    np.testing.assert_allclose(r_dot, r @ marine.skew(omega), atol=1e-12)


def test_bad_input():
    with pytest.raises(ValueError, match="positive definite"):
        auv.auv_plant(auv.AUVParams(M_A=-200.0 * jnp.eye(6)))
    singular = np.diag([185.0, 255, 255, 15.2, 33, 0.0])  # PSD, not PD: M_A = 0 leaves it singular
    with pytest.raises(ValueError, match="M .*positive definite"):
        auv.auv_plant(auv.AUVParams(M_R=singular, M_A=jnp.zeros((6, 6))))
    bad = np.diag([185.0, 255, 255, 15.2, 33, 33])
    bad[0, 1] = 5.0
    with pytest.raises(ValueError, match="symmetric"):
        auv.auv_plant(auv.AUVParams(M_R=bad))
    with pytest.raises(ValueError, match="d1"):
        auv.auv_plant(auv.AUVParams(d1=-jnp.ones(6)))
    with pytest.raises(ValueError, match="M_R"):
        auv.auv_plant(auv.AUVParams(M_R=jnp.eye(3)))


def test_course_attitude_along_velocity_and_guarded_when_slow():
    """x axis along ``v = (1, 1, −√2)``: ψ = θ = 45° (NED, climbing); rotating e_x by it gives ``v/|v|``.
    Below ``min_speed`` the attitude and its derivative are exactly 0."""
    v = jnp.array([1.0, 1.0, -np.sqrt(2.0)])
    att = marine.course_attitude(v)
    np.testing.assert_allclose(att, [0.0, np.pi / 4, np.pi / 4], atol=1e-12)
    np.testing.assert_allclose(marine.rotation_zyx(att)[:, 0], v / 2.0, atol=1e-12)
    slow = jnp.array([0.05, 0.02, 0.3])
    val, der = jax.jvp(lambda u: marine.course_attitude(u, 0.1), (slow,), (jnp.array([1.0, -2.0, 3.0]),))
    assert np.all(np.asarray(val) == 0.0) and np.all(np.asarray(der) == 0.0)
    assert float(marine.course_attitude(slow)[2]) != 0.0  # unguarded: a heading even when slow
