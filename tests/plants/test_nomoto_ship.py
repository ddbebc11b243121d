"""Nomoto ship heading loop (seed 004 #4): the state-space loop against the transfer function
(SciPy freqs), the closed-loop matrix against the dynamics, the sector residuals, eigenvalue
gradients against finite differences."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.signal

from jaxsim.plants import nomoto_ship as ship


def test_complementary_sensitivity_against_transfer_function():
    p = ship.Params()
    g = jnp.array([0.8, 12.0, 0.01])
    w = np.logspace(-4, 1, 60)
    num = np.polymul([12.0, 0.8, 0.01], [p.K])  # (k_d s² + k_p s + k_i)·K
    den = np.polymul([p.T * p.T_r, p.T + p.T_r, 1.0], [1.0, 0.0, 0.0])  # s²(Ts+1)(T_r s+1)
    _, lval = scipy.signal.freqs(num, den, worN=w)
    np.testing.assert_allclose(
        np.asarray(ship.complementary_sensitivity(p, g, jnp.asarray(w))), np.abs(lval / (1 + lval)), rtol=1e-9
    )
    # closed-loop poles = roots of den + num
    eig = np.sort_complex(np.linalg.eigvals(np.asarray(ship.closed_loop_matrix(p, g))))
    np.testing.assert_allclose(eig, np.sort_complex(np.roots(np.polyadd(den, num))), rtol=1e-8)


def test_dynamics_match_the_matrices():
    p = ship.Params()
    a, b = ship.open_loop_matrices(p)
    x = jnp.array([0.1, -0.02, 0.05])
    np.testing.assert_allclose(
        np.asarray(ship.dynamics(p, x, jnp.array([0.3]), 0.0)), np.asarray(a[:3, :3] @ x + b[:3, 0] * 0.3), rtol=1e-14
    )


def test_sector_residuals_and_eigenvalue_gradient():
    eigs = jnp.array([-1.0 + 0.5j, -1.0 - 0.5j, -0.2 + 0.0j, -0.5 + 1.0j])
    r = np.asarray(ship.sector_residuals(eigs, 0.3, np.pi / 4))
    np.testing.assert_allclose(r[0], [-0.7, -0.7, 0.1, -0.2])
    np.testing.assert_allclose(r[1], [-0.5, -0.5, -0.2, 0.5], atol=1e-15)
    p = ship.Params()

    def slowest(t):
        return jnp.max(jnp.real(jnp.linalg.eigvals(ship.closed_loop_matrix(p, jnp.exp(t)))))

    th = jnp.log(jnp.array([0.8, 12.0, 0.01]))
    gr = jax.grad(slowest)(th)
    h = 1e-6
    fd = [(slowest(th + h * e) - slowest(th - h * e)) / (2 * h) for e in jnp.eye(3)]
    np.testing.assert_allclose(np.asarray(gr), np.asarray(fd), rtol=1e-5, atol=1e-9)
    assert float(slowest(th)) == pytest.approx(
        float(np.max(np.linalg.eigvals(np.asarray(ship.closed_loop_matrix(p, jnp.exp(th)))).real))
    )
