"""Integrators against the exact matrix-exponential solution of LTI systems."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg

from jaxsim.core.integrators import EULER, HEUN, RK4, ExponentialEuler, SemiImplicitEuler, integrate

A = np.array([[0.0, 1.0], [-20.0, -12.0]])  # static plant of the fuzzy-PID paper, poles -2 and -10
B = np.array([0.0, 40.0])
X0 = np.array([1.0, -0.5])


def field(t, x):
    return jnp.asarray(A) @ x + jnp.asarray(B) * jnp.sin(3.0 * t)


def exact(t_end: float) -> np.ndarray:
    """Exact solution via the augmented matrix exponential (sin input as a 2-state exosystem)."""
    big = np.zeros((4, 4))
    big[:2, :2] = A
    big[:2, 2] = B  # input = w1 where w = [sin 3t, cos 3t]
    big[2, 3] = 3.0
    big[3, 2] = -3.0
    z = scipy.linalg.expm(big * t_end) @ np.concatenate([X0, [0.0, 1.0]])
    return z[:2]


@pytest.mark.parametrize("solver, order", [(EULER, 1), (HEUN, 2), (RK4, 4)])
def test_explicit_rk_converges_at_its_order(solver, order):
    t_end = 1.0
    errors = []
    for n in (100, 200, 400):
        _, xs = integrate(field, X0, 0.0, t_end / n, n, solver)
        errors.append(np.max(np.abs(np.asarray(xs[-1]) - exact(t_end))))
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(rates - order) < 0.15), (errors, rates)


def test_rk4_small_step_is_accurate():
    _, xs = integrate(field, X0, 0.0, 1e-3, 1000, RK4)
    # global error ~ (|λ|dt)^4 with |λ| = 10: about 1e-8 relative at most
    np.testing.assert_allclose(xs[-1], exact(1.0), rtol=1e-9, atol=1e-12)


def test_exponential_euler_is_exact_for_lti_with_held_input():
    b = jnp.array([0.3, -1.0])
    f = lambda t, x: jnp.asarray(A) @ x + b  # noqa: E731
    _, xs = integrate(f, X0, 0.0, 0.25, 4, ExponentialEuler())
    ad = scipy.linalg.expm(A * 1.0)
    want = ad @ X0 + np.linalg.solve(A, (ad - np.eye(2)) @ np.asarray(b))
    np.testing.assert_allclose(xs[-1], want, rtol=1e-12)


def test_semi_implicit_euler_is_stable_on_a_stiff_system_where_euler_blows_up():
    stiff = jnp.array([[-1e4, 0.0], [1.0, -1.0]])
    f = lambda t, x: stiff @ x  # noqa: E731
    x0 = jnp.array([1.0, 1.0])
    _, xs_si = integrate(f, x0, 0.0, 1e-2, 100, SemiImplicitEuler())
    _, xs_e = integrate(f, x0, 0.0, 1e-2, 100, EULER)
    assert np.all(np.isfinite(xs_si)) and np.max(np.abs(xs_si[-1])) < 1.0
    assert not np.all(np.abs(np.asarray(xs_e[-1])) < 1e3)
    # first order: halving the step halves the error at t = 1 on the slow mode
    ref = float(np.exp(-1.0))  # slow component decays like e^-t once the fast one died
    e1 = abs(float(integrate(f, x0, 0.0, 1e-2, 100, SemiImplicitEuler())[1][-1, 1]) - ref)
    e2 = abs(float(integrate(f, x0, 0.0, 5e-3, 200, SemiImplicitEuler())[1][-1, 1]) - ref)
    assert 1.6 < e1 / e2 < 2.4


def test_integrate_rejects_bad_step():
    with pytest.raises(ValueError, match="dt"):
        integrate(field, X0, 0.0, -0.1, 10)
    with pytest.raises(ValueError, match="n_steps"):
        integrate(field, X0, 0.0, 0.1, 0)


def test_integrators_are_differentiable():
    def final(a00):
        f = lambda t, x: jnp.array([[a00, 1.0], [-20.0, -12.0]]) @ x  # noqa: E731
        return integrate(f, jnp.asarray(X0), 0.0, 1e-2, 50, RK4)[1][-1, 0]

    g = jax.grad(final)(0.0)
    h = 1e-6
    fd = (final(h) - final(-h)) / (2 * h)
    np.testing.assert_allclose(g, fd, rtol=1e-7)


def test_rolled_rk4_equals_rk4_and_traces_the_field_once():
    from jaxsim.core.integrators import RK4_ROLLED

    calls = []

    def f(t, x):
        calls.append(1)
        return jnp.array([x[1], -jnp.sin(x[0]) - 0.1 * x[1] + jnp.cos(t)])

    x = jnp.array([1.2, -0.3])
    ref = RK4.step(f, 0.7, x, 0.05)
    calls.clear()
    rolled = RK4_ROLLED.step(f, 0.7, x, 0.05)
    assert len(calls) == 1  # the field is traced once, inside the scan
    np.testing.assert_allclose(rolled, ref, rtol=1e-14, atol=1e-15)
    assert RK4_ROLLED.order == RK4.order
