"""Tilt-rotor quadcopter plant: against an independent NumPy implementation of the same physics, SciPy's
``solve_ivp``, and the invariants of a torque-free rigid body."""

import jax
import jax.numpy as jnp
import numpy as np
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

from jaxsim.core.integrators import RK4
from jaxsim.core.rotations import rotation_from_quat
from jaxsim.plants import tilt_rotor as tr

P = tr.TiltRotorParams(wind=(1.0, -0.5, 0.2))


def numpy_dynamics(p, x, u):
    """The plant's equations written out with SciPy rotations (an independent implementation)."""
    v, q, om = x[3:6], x[6:10], x[10:13]
    rot = Rotation.from_quat(np.roll(q / np.linalg.norm(q), -1)).as_matrix()
    f_b, m_b = np.zeros(3), np.zeros(3)
    for i, (psi, spin) in enumerate(zip(tr.ARM_AZIMUTH_DEG, tr.SPIN)):
        c, s = np.cos(np.deg2rad(psi)), np.sin(np.deg2rad(psi))
        arm, tilt_dir = np.array([c, s, 0.0]), np.array([-s, c, 0.0])
        axis = np.cos(u[4 + i]) * np.array([0, 0, 1.0]) + np.sin(u[4 + i]) * tilt_dir
        w2 = p.alive[i] * u[i] ** 2
        thrust = p.k_thrust * w2 * axis
        f_b += thrust
        m_b += np.cross(p.arm * arm + [0, 0, p.rotor_height], thrust) + spin * p.k_torque * w2 * axis
    acc = (rot @ f_b - p.drag * (v - np.asarray(p.wind))) / p.mass - [0, 0, tr.GRAVITY]
    inertia = np.asarray(p.inertia)
    om_dot = (m_b - np.cross(om, inertia * om)) / inertia
    w, x_, y, z = q
    q_dot = 0.5 * np.array(
        [
            -x_ * om[0] - y * om[1] - z * om[2],
            w * om[0] + y * om[2] - z * om[1],
            w * om[1] + z * om[0] - x_ * om[2],
            w * om[2] + x_ * om[1] - y * om[0],
        ]
    )
    return np.concatenate([v, acc, q_dot, om_dot])


def random_state(rng):
    q = rng.normal(size=4)
    return np.concatenate([rng.normal(size=6), q / np.linalg.norm(q), rng.normal(size=3)])


def test_dynamics_equal_an_independent_numpy_implementation():
    rng = np.random.default_rng(0)
    f = jax.jit(lambda x, u: tr.dynamics(P, x, u, 0.0))
    for _ in range(5):
        x, u = random_state(rng), np.concatenate([rng.uniform(300, 900, 4), rng.uniform(-1.5, 1.5, 4)])
        np.testing.assert_allclose(f(jnp.asarray(x), jnp.asarray(u)), numpy_dynamics(P, x, u), rtol=1e-12, atol=1e-12)


def test_four_vertical_rotors_at_hover_speed_balance_the_weight():
    w = tr.hover_speed(P, 4)
    force, moment = tr.rotor_wrench(P, jnp.full(4, w), jnp.zeros(4))
    np.testing.assert_allclose(force, [0, 0, P.mass * tr.GRAVITY], rtol=1e-14)
    np.testing.assert_allclose(moment, 0.0, atol=1e-14)  # opposite spins cancel the reaction torques


def test_a_powered_flight_matches_solve_ivp():
    """Constant inputs for 1 s: RK4 (dt = 1 ms, jitted scan) against solve_ivp (DOP853, rtol 1e-11)."""
    rng = np.random.default_rng(1)
    x0, u = random_state(rng) * 0.3, np.concatenate([rng.uniform(600, 900, 4), rng.uniform(-0.3, 0.3, 4)])
    x0[6:10] /= np.linalg.norm(x0[6:10])

    def step(x, _):
        return RK4.step(lambda t, z: tr.dynamics(P, z, jnp.asarray(u), t), 0.0, x, 1e-3), None

    ours = jax.jit(lambda x: jax.lax.scan(step, x, None, length=1000)[0])(jnp.asarray(x0))
    ref = solve_ivp(lambda t, x: numpy_dynamics(P, x, u), (0, 1), x0, method="DOP853", rtol=1e-11, atol=1e-11)
    np.testing.assert_allclose(ours, ref.y[:, -1], rtol=1e-8, atol=1e-8)


def test_torque_free_body_conserves_energy_momentum_and_the_unit_quaternion():
    p = tr.TiltRotorParams(drag=0.0)
    x0 = np.concatenate([[0, 0, 10.0], [1.0, -2.0, 3.0], [1.0, 0, 0, 0], [0.3, 2.0, -0.5]])

    def step(x, _):
        return RK4.step(lambda t, z: tr.dynamics(p, z, jnp.zeros(8), t), 0.0, x, 1e-3), None

    x1 = jax.jit(lambda x: jax.lax.scan(step, x, None, length=2000)[0])(jnp.asarray(x0))
    inertia = np.asarray(p.inertia)
    h0 = np.asarray(rotation_from_quat(jnp.asarray(x0[6:10]))) @ (inertia * x0[10:13])
    h1 = np.asarray(rotation_from_quat(x1[6:10])) @ (inertia * np.asarray(x1[10:13]))
    assert abs(float(tr.energy(p, x1)) - float(tr.energy(p, jnp.asarray(x0)))) < 1e-9
    np.testing.assert_allclose(h1, h0, atol=1e-10)
    assert abs(float(jnp.linalg.norm(x1[6:10])) - 1.0) < 1e-10
