"""Mariner 3-DOF model: published Nomoto constants, kinematics, steady turn."""

import jax.numpy as jnp
import numpy as np
import pytest
import scipy.signal

from jaxsim.core.integrators import RK4, integrate
from jaxsim.plants import ship_3dof as sh


def test_yaw_transfer_function_matches_the_published_nomoto_constants():
    """Fossen (2011), Mariner class vessel at 15 kn: K = 0.185 s⁻¹, T1 = 118 s, T2 = 7.8 s, T3 = 18.5 s."""
    A, b = (np.asarray(m) for m in sh.sway_yaw_matrices(sh.ShipParams()))
    num, den = scipy.signal.ss2tf(A, b[:, None], np.array([[0.0, 1.0]]), np.zeros((1, 1)))
    num = num[0][np.abs(num[0]) > 1e-14]
    T1, T2 = sorted(-1.0 / np.roots(den), reverse=True)
    (T3,) = -1.0 / np.roots(num)
    assert abs(num[-1] / den[-1]) == pytest.approx(0.185, abs=5e-4)
    assert (T1, T2, T3) == pytest.approx((118.0, 7.8, 18.5), abs=0.1)


def test_straight_run_and_steady_turn():
    p = sh.ShipParams()
    f0 = lambda t, x: sh.dynamics(p, x, jnp.zeros(2), t)  # noqa: E731
    _, xs = integrate(f0, jnp.zeros(7), 0.0, 0.1, 1000, RK4)
    np.testing.assert_allclose(xs[-1, :3], [100.0 * p.U0, 0.0, 0.0], atol=1e-9)
    delta = np.deg2rad(2.0)
    f = lambda t, x: sh.dynamics(p, x, jnp.array([delta, 0.0]), t)  # noqa: E731
    _, xs = integrate(f, jnp.zeros(7), 0.0, 0.1, 12000, RK4)
    A, b = (np.asarray(m) for m in sh.sway_yaw_matrices(p))
    v_ss, r_ss = -np.linalg.solve(A, b * delta)
    assert float(xs[-1, 5]) == pytest.approx(r_ss, rel=1e-4)  # e^(−1200/118) ≈ 4e-5 left
    assert float(xs[-1, 4]) == pytest.approx(v_ss, rel=1e-4)


def test_bad_parameters():
    with pytest.raises(ValueError, match="T_rudder"):
        sh.ship_plant(sh.ShipParams(T_rudder=0.0))
