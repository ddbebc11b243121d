"""Nested saturated feedback, the dual switch and the ESO (seed 004 #31): the linear region against
the closed-form gain, constraints (7) tight, the level set's bound by sampling its boundary, the
ESO's error poles and its exact recovery of a constant disturbance (SciPy solve_ivp), the plant."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.integrate

from jaxsim.control import nested_saturation as ns
from jaxsim.estimation import extended_state_observer as eso
from jaxsim.plants import integrator_chain as ic


def test_nsf_linear_region_and_bounds():
    k = jnp.array([0.2, 0.5, 1.5])
    levels = ns.constrained_levels(k, 1.0, 0.2, 2.0)
    res = ns.design_residuals(k, levels, 1.0, 0.2, 2.0)
    np.testing.assert_allclose(np.asarray(res[:3]), 0.0, atol=1e-15)  # (7) tight
    assert float(jnp.max(res)) <= 1e-15
    x = jnp.array([0.01, -0.02, 0.015])  # inside every linear zone
    u = ns.nsf_control(k, levels, x, jnp.array(0.05), 1.0)
    gain = ns.linear_gain(k)
    # σ3(x3 + σ2(x2 + σ1 x1)) = k3 x3 + k3k2 x2 + k3k2k1 x1
    np.testing.assert_allclose(np.asarray(gain), [1.5 * 0.5 * 0.2, 1.5 * 0.5, 1.5], rtol=1e-14)
    assert float(u) == pytest.approx(-0.05 - float(gain @ x), rel=1e-14)
    big = jax.vmap(lambda x: ns.nsf_control(k, levels, x, jnp.array(0.2), 1.0))(
        jax.random.normal(jax.random.PRNGKey(0), (200, 3)) * 10
    )
    assert float(jnp.max(jnp.abs(big))) <= 1.0
    # the inner law is bounded by M3 = u_m − d_m, so |u| < u_m whenever |d̂| ≤ d_m
    inner = jax.vmap(lambda x: ns.nsf_inner(k, levels, x))(jax.random.normal(jax.random.PRNGKey(1), (200, 3)) * 10)
    assert float(jnp.max(jnp.abs(inner))) <= 0.8 + 1e-12


def test_level_set_bound_and_dual_switch():
    p = jnp.array([[2.0, 0.3, 0.1], [0.3, 1.5, 0.2], [0.1, 0.2, 1.0]])
    gain = jnp.array([1.0, 2.0, 0.5])
    c = ns.lqr_level(gain, p, 1.0, 0.2)
    # sample the boundary xᵀPx = c: max |Kx| = u_m − d_m
    z = np.random.default_rng(0).normal(size=(20000, 3))
    ell = np.linalg.cholesky(np.linalg.inv(np.asarray(p)))
    xs = (z / np.linalg.norm(z, axis=1, keepdims=True)) @ ell.T * np.sqrt(float(c))
    np.testing.assert_allclose(np.einsum("ij,jk,ik->i", xs, p, xs), float(c), rtol=1e-10)
    assert np.max(np.abs(xs @ np.asarray(gain))) == pytest.approx(0.8, rel=1e-3)
    assert np.max(np.abs(xs @ np.asarray(gain))) <= 0.8 + 1e-12
    k = jnp.array([0.2, 0.5, 1.5])
    levels = ns.constrained_levels(k, 1.0, 0.2)
    x_in = jnp.asarray(xs[0] * 0.5)
    u, inside = ns.dual_control(k, levels, gain, p, c, x_in, jnp.array(0.1), 1.0)
    assert bool(inside) and float(u) == pytest.approx(-0.1 - float(gain @ x_in))
    x_out = jnp.asarray(xs[0] * 2.0)
    u, inside = ns.dual_control(k, levels, gain, p, c, x_out, jnp.array(0.1), 1.0)
    assert not bool(inside) and float(u) == pytest.approx(float(ns.nsf_control(k, levels, x_out, jnp.array(0.1), 1.0)))


def test_eso_poles_and_constant_disturbance():
    g = eso.bandwidth_gains(jnp.array(3.0), 3)
    np.testing.assert_allclose(np.asarray(g), [12.0, 54.0, 108.0, 81.0])
    ev = np.linalg.eigvals(np.asarray(eso.error_matrix(g)))
    np.testing.assert_allclose(np.sort(np.real(ev)), -3.0, atol=2e-3)  # a 4-fold pole (perturbed ~ eps^(1/4))
    # triple integrator with constant d under a known input; the ESO recovers d (SciPy, tight tolerance)
    d, u = 0.15, lambda t: 0.3 * np.sin(t)
    der = jax.jit(eso.derivative)

    def rhs(t, z):
        x = z[:3]
        dxh = np.asarray(der(g, jnp.asarray(z[3:]), x[0], u(t)))
        return np.concatenate([[x[1], x[2], u(t) + d], dxh])

    sol = scipy.integrate.solve_ivp(rhs, (0, 12), np.r_[1.0, -0.5, 0.2, 0, 0, 0, 0], rtol=1e-10, atol=1e-12)
    assert sol.y[6, -1] == pytest.approx(d, abs=1e-5)
    np.testing.assert_allclose(sol.y[3:6, -1], sol.y[:3, -1], atol=1e-5)
    with pytest.raises(ValueError, match="n"):
        eso.bandwidth_gains(jnp.array(1.0), 0)


def test_integrator_chain_plant():
    p = ic.Params()
    xd = ic.dynamics(p, jnp.array([1.0, 2.0, 3.0]), jnp.array([5.0, 0.1]), 0.0)
    np.testing.assert_allclose(np.asarray(xd), [2.0, 3.0, 1.1])  # command saturated at u_m = 1
    a, b = ic.matrices(3)
    np.testing.assert_allclose(np.asarray(a @ jnp.array([1.0, 2.0, 3.0]) + b[:, 0] * 0.4), [2.0, 3.0, 0.4])
    with pytest.raises(ValueError, match="d_m"):
        ic.validate(ic.Params(u_m=1.0, d_m=1.5))
    with pytest.raises(ValueError, match="u_m"):
        ic.validate(ic.Params(u_m=-1.0))
