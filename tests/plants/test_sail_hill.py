"""Sail in the Hill frame (seed 004 #6/#18): light-pressure formula, HCW against the closed-form
solution and solve_ivp, the ellipse-centre relations, the pitch inversion."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.integrate

from jaxsim.core.integrators import RK4, integrate
from jaxsim.plants import sail_hill as sh


def test_acceleration_scale_and_pressure_law():
    p = sh.SailParams()
    assert float(sh.acceleration_scale(p)) == pytest.approx(2 * 1370 * 7.85e3 / (3e8 * 500), rel=1e-14)
    s = jnp.array([0.0, 0.0, 1.0])
    n = jnp.array([0.0, np.sin(0.4), np.cos(0.4)])
    a = sh.srp_acceleration(p, n, s)
    np.testing.assert_allclose(np.asarray(a), float(sh.acceleration_scale(p)) * np.cos(0.4) ** 2 * np.asarray(n))
    assert float(jnp.linalg.norm(sh.srp_acceleration(p, -n, s))) == 0.0  # lit from behind
    assert float(np.degrees(sh.max_visible_latitude(42164e3))) == pytest.approx(
        np.degrees(np.arccos(6378.137 / 42164)), rel=1e-12
    )


def test_unforced_hcw_matches_closed_form():
    p = sh.SailParams(reflection=1e-30)  # no sail force
    n = float(sh.mean_motion(p))
    x0 = np.array([100.0, -50.0, 20.0, 0.05, -0.1, 0.02])
    plant = sh.sail_hill(p)
    ts, xs = integrate(lambda t, x: plant.f(x, jnp.zeros(4), t), jnp.asarray(x0), 0.0, 10.0, 600, RK4)
    t = np.asarray(ts)
    x, y, z, vx, vy, vz = x0
    s, c = np.sin(n * t), np.cos(n * t)
    xr = 4 * x + 2 * vy / n + vx / n * s - (3 * x + 2 * vy / n) * c
    yr = y - 2 * vx / n + 2 * vx / n * c + (6 * x + 4 * vy / n) * s - (6 * n * x + 3 * vy) * t
    zr = z * c + vz / n * s
    np.testing.assert_allclose(np.asarray(xs[:, 0]), xr, atol=1e-6)
    np.testing.assert_allclose(np.asarray(xs[:, 1]), yr, atol=1e-6)
    np.testing.assert_allclose(np.asarray(xs[:, 2]), zr, atol=1e-6)
    # the centre relations: x_c and ρ constant, y_c drifts at −(3/2) n x_c
    c_all = np.asarray(jax.vmap(lambda xx: sh.centre(p, xx))(xs))
    np.testing.assert_allclose(c_all[:, 0], c_all[0, 0], atol=1e-6)
    np.testing.assert_allclose(c_all[:, 2], c_all[0, 2], atol=1e-6)
    np.testing.assert_allclose(c_all[:, 1], c_all[0, 1] - 1.5 * n * c_all[0, 0] * t, atol=1e-6)


def test_forced_hcw_against_solve_ivp():
    p = sh.SailParams()
    plant = sh.sail_hill(p)
    u = jnp.array([0.3, 1e-6, -2e-6, 5e-7])
    n, a = float(sh.mean_motion(p)), float(sh.acceleration_scale(p))
    ts, xs = integrate(lambda t, x: plant.f(x, u, t), jnp.zeros(6), 0.0, 20.0, 300, RK4)
    acc = np.array([1e-6, a * np.cos(0.3) ** 2 * np.sin(0.3) - 2e-6, a * np.cos(0.3) ** 3 + 5e-7])

    def rhs(t, x):
        return [*x[3:], 3 * n**2 * x[0] + 2 * n * x[4] + acc[0], -2 * n * x[3] + acc[1], -(n**2) * x[2] + acc[2]]

    ref = scipy.integrate.solve_ivp(rhs, (0, 6000.0), np.zeros(6), t_eval=np.asarray(ts), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(np.asarray(xs).T, ref.y, atol=1e-6)  # metres; solve_ivp at rtol 1e-12


def test_pitch_inverts_the_tangential_push():
    p = sh.SailParams()
    a = float(sh.acceleration_scale(p))
    top = a * 2 / (3 * np.sqrt(3))
    want = jnp.array([-top, -0.3 * top, 0.0, 0.7 * top, top])
    alpha = sh.pitch_for(p, want)
    np.testing.assert_allclose(np.asarray(sh.tangential_acceleration(p, alpha)), np.asarray(want), atol=1e-12 * a)
    assert float(sh.pitch_for(p, 10 * top)) == pytest.approx(np.arctan(1 / np.sqrt(2)), abs=1e-7)  # flat maximum


def test_bad_parameters_raise():
    with pytest.raises(ValueError, match="mass"):
        sh.sail_hill(mass=0.0)
