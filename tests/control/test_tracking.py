"""LQ tracking through the regulator (Francis) equations: closed forms and simulated tracking."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg as sl
from scipy.integrate import solve_ivp

from jaxsim.control.tracking import (
    constant_exosystem,
    lq_tracking,
    regulator_equations,
    sinusoidal_exosystem,
    tracking_control,
)

RNG = np.random.default_rng(9)
A = RNG.normal(size=(4, 4))
B = RNG.normal(size=(4, 2))
C = RNG.normal(size=(2, 4))


def test_constant_exosystem_matches_the_static_inverse():
    pi, gamma = regulator_equations(A, B, C, constant_exosystem(2))
    block = np.block([[A, B], [C, np.zeros((2, 2))]])
    expected = np.linalg.solve(block, np.vstack([np.zeros((4, 2)), np.eye(2)]))
    np.testing.assert_allclose(np.vstack([pi, gamma]), expected, rtol=1e-12, atol=1e-12)


def test_sinusoidal_regulator_equations_hold():
    exo = sinusoidal_exosystem([0.7, 1.9])
    pi, gamma = (np.asarray(v) for v in regulator_equations(A, B, C, exo))
    s, q_r = np.asarray(exo.s), np.asarray(exo.q_r)
    np.testing.assert_allclose(pi @ s, A @ pi + B @ gamma, atol=1e-11)
    np.testing.assert_allclose(C @ pi, q_r, atol=1e-12)
    # the exosystem really generates sin/cos pairs: exp(S t) rotates by ω t
    t = 0.37
    rot = sl.expm(s * t)
    np.testing.assert_allclose(
        rot[:2, :2], [[np.cos(0.7 * t), np.sin(0.7 * t)], [-np.sin(0.7 * t), np.cos(0.7 * t)]], atol=1e-12
    )


@pytest.mark.parametrize("exo_kind", ["constant", "sinusoid"])
def test_tracking_error_vanishes_in_closed_loop(exo_kind):
    exo = constant_exosystem(2) if exo_kind == "constant" else sinusoidal_exosystem([0.5, 1.3])
    gains = lq_tracking(A, B, C, np.eye(4) * 10, np.eye(2), exo)
    xi0 = np.array([0.3, -0.2]) if exo_kind == "constant" else np.array([0.3, 0.1, -0.2, 0.2])
    s, q_r = np.asarray(exo.s), np.asarray(exo.q_r)
    u_of = jax.jit(lambda x, xi: tracking_control(gains, x, xi))

    def rhs(_, z):
        x, xi = z[:4], z[4:]
        return np.concatenate([A @ x + B @ np.asarray(u_of(x, xi)), s @ xi])

    t_end = 30.0
    sol = solve_ivp(rhs, (0, t_end), np.concatenate([np.zeros(4), xi0]), rtol=1e-10, atol=1e-12, t_eval=[0.0, t_end])
    x, xi = sol.y[:4], sol.y[4:]
    err = C @ x - q_r @ xi
    assert np.abs(err[:, 0]).max() > 0.1  # it starts off the reference
    assert np.abs(err[:, -1]).max() < 1e-6  # and converges onto it
    # on the invariant manifold x = Πξ the state feedback vanishes and the input is the steady one, Γξ
    pi, gamma = np.asarray(gains.pi), np.asarray(gains.gamma)
    np.testing.assert_allclose(u_of(pi @ xi0, xi0), gamma @ xi0, atol=1e-12)


def test_feedforward_is_differentiable():
    exo = constant_exosystem(2)

    def f(w):
        return jnp.sum(lq_tracking(A, B, C, jnp.diag(w), jnp.eye(2), exo).feedforward ** 2)

    w = np.array([1.0, 2.0, 3.0, 4.0])
    g = jax.grad(f)(w)
    e = np.eye(4)[2] * 1e-6
    np.testing.assert_allclose(g[2], (f(w + e) - f(w - e)) / 2e-6, rtol=1e-6)


def test_singular_regulator_equations_raise():
    # two identical channels driven by one input and measured as their difference: y ≡ 0 in steady
    # state, a transmission zero at s = 0, so no constant reference can be tracked
    a = -np.eye(2)
    b = np.array([[1.0], [1.0]])
    c = np.array([[1.0, -1.0]])
    with pytest.raises(ValueError, match="transmission zero"):
        regulator_equations(a, b, c, constant_exosystem(1))
    with pytest.raises(ValueError, match="p = m"):
        regulator_equations(A, B, C[:1], constant_exosystem(1))
