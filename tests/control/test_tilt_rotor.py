"""Two-rotor hover of the tilt-rotor quadcopter: the trim equations against SciPy's root finder and
CasADi (on the independent NumPy plant), the linearisation against central differences, the return
path's velocity against its position."""

import casadi as ca
import jax
import jax.numpy as jnp
import numpy as np
from scipy.optimize import root

from jaxsim.control import tilt_rotor as tc
from jaxsim.plants import tilt_rotor as tr
from tests.plants.test_tilt_rotor import numpy_dynamics

P = tr.TiltRotorParams(alive=(1.0, 0.0, 0.0, 1.0))
W = tr.hover_speed(P, 2)


def numpy_residual(z):
    """Accelerations at rest from the NumPy plant for ``z = [ω1, ω4, ϑ1, ϑ4, roll, pitch]`` (attitude:
    pitch about y, then roll about x: the quaternion product written out)."""
    cp, sp, cr, sr = np.cos(z[5] / 2), np.sin(z[5] / 2), np.cos(z[4] / 2), np.sin(z[4] / 2)
    quat = np.array([cp * cr, cp * sr, sp * cr, -sp * sr])
    u = np.array([z[0], 0, 0, z[1], z[2], 0, 0, z[3]])
    xd = numpy_dynamics(P, np.concatenate([np.zeros(6), quat, np.zeros(3)]), u)
    return np.concatenate([xd[3:6], xd[10:13]])


def casadi_symmetric_trim(guess):
    """``(ω, ϑ, pitch)`` of the symmetric hover (ω1 = ω4, ϑ4 = −ϑ1, no roll) by CasADi's Newton root
    finder on the equations written by hand: body force ``k ω² (2 cos ϑ e_z + √2 sin ϑ e_x)``, pitch
    moment of the arms (x = L/√2, z = h) plus the reaction torques ``√2 k_m ω² sin ϑ``."""
    w, th, pitch = ca.SX.sym("w"), ca.SX.sym("th"), ca.SX.sym("pitch")
    s2 = np.sqrt(0.5)
    fx, fz = P.k_thrust * w**2 * 2 * s2 * ca.sin(th), P.k_thrust * w**2 * 2 * ca.cos(th)
    my = P.rotor_height * fx - P.arm * s2 * fz + P.k_torque * w**2 * 2 * s2 * ca.sin(th)
    world_x = ca.cos(pitch) * fx + ca.sin(pitch) * fz
    world_z = -ca.sin(pitch) * fx + ca.cos(pitch) * fz - P.mass * tr.GRAVITY
    g = ca.Function("g", [ca.vertcat(w, th, pitch)], [ca.vertcat(world_x, world_z, my)])
    return np.asarray(ca.rootfinder("solve", "newton", g, {"abstol": 1e-12})(guess)).ravel()


def scipy_trim():
    w, th, pitch = casadi_symmetric_trim([W, 1.2, -1.1])
    sol = root(numpy_residual, [w * 1.01, w * 0.99, th + 0.02, -th + 0.01, 0.01, pitch - 0.02], tol=1e-13)
    assert sol.success
    return sol.x, (w, th, pitch)


def trim_of(z):
    return tc.Trim(jnp.asarray(z[:4]), jnp.asarray(z[4]), jnp.asarray(z[5]), tc.attitude(z[4], z[5]), jnp.zeros(()))


def test_trim_equations_two_oracles_and_ours_agree():
    z, (w, th, pitch) = scipy_trim()
    # the full six equations (SciPy) land on the symmetric solution (CasADi)
    np.testing.assert_allclose(z, [w, w, th, -th, 0.0, pitch], rtol=1e-9, atol=1e-9)
    # a level body cannot hover: the tilt and the pitch are both large
    assert np.deg2rad(60) < abs(th) < np.deg2rad(90) and abs(pitch) > np.deg2rad(45)
    np.testing.assert_allclose(jax.jit(lambda z: tc.trim_residual(P, z))(jnp.asarray(z)), 0.0, atol=1e-9)


def test_linearisation_equals_central_differences():
    z, _ = scipy_trim()
    trim = trim_of(z)
    a, b = jax.jit(lambda t: tc.linearise(P, t))(trim)
    f = jax.jit(jax.vmap(lambda e, du: tc.error_dynamics(P, trim, e, du)))
    h, scale = 1e-6, np.array([W, W, 1.0, 1.0])
    de = np.concatenate([np.eye(12), np.zeros((4, 12))]) * h
    du = np.concatenate([np.zeros((12, 4)), np.eye(4) * scale]) * h
    diff = (np.asarray(f(de, du)) - np.asarray(f(-de, -du))) / (2 * h)
    np.testing.assert_allclose(a[:12, :12], diff[:12].T, atol=1e-6)
    np.testing.assert_allclose(b[:12] * scale, diff[12:].T, rtol=1e-6, atol=1e-6)
    np.testing.assert_array_equal(a[12:, :3], np.eye(3))  # ξ̇ = r − r_ref


def test_return_path_velocity_is_the_derivative_of_its_position():
    path = tc.ReturnPath(jnp.array([8.0, -3.0, 5.0]), jnp.zeros(3), 6.0, 4.0, jnp.array([1.0, 0, 0, 0]))
    ts = jnp.linspace(0.0, 12.0, 97)
    along = jax.jit(jax.vmap(path))
    out = along(ts)
    h = 1e-6
    fd = (along(ts + h)[:, :3] - along(ts - h)[:, :3]) / (2 * h)
    np.testing.assert_allclose(out[:, 3:6], fd, atol=1e-6)
    np.testing.assert_allclose(out[0, :3], [8.0, -3.0, 5.0])
    np.testing.assert_allclose(path(jnp.asarray(6.0))[:3], [0.0, 0.0, 5.0], atol=1e-12)  # above the base
    np.testing.assert_allclose(out[-1, :6], 0.0, atol=1e-12)  # landed, at rest
