"""Controllability gramians: Lyapunov route and impulse-response route against SciPy's Lyapunov
solver and the closed form of a scalar system; gradient against finite differences."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg

from jaxsim.control.gramian import controllability_gramian, impulse_gramian


def _stable(rng, n):
    m = rng.standard_normal((n, n))
    return m - (np.max(np.linalg.eigvals(m).real) + 0.5) * np.eye(n)


def test_lyapunov_and_impulse_gramians_match_scipy():
    rng = np.random.default_rng(3)
    a, b = _stable(rng, 3), rng.standard_normal((3, 2))
    ref = scipy.linalg.solve_continuous_lyapunov(a, -b @ b.T)
    w = np.asarray(controllability_gramian(a, b))
    np.testing.assert_allclose(w, ref, rtol=1e-10, atol=1e-12)
    t_final = 40.0 / 0.5  # slowest decay rate ≥ 0.5
    emp = np.asarray(impulse_gramian(a, b, t_final, 4000))
    np.testing.assert_allclose(emp, ref, rtol=1e-6, atol=1e-8)
    assert np.all(np.linalg.eigvalsh(0.5 * (emp + emp.T)) > 0)


def test_scalar_closed_form_and_gradient():
    a, b = -1.3, 0.7
    w = float(controllability_gramian(jnp.array([[a]]), jnp.array([[b]]))[0, 0])
    assert w == pytest.approx(b * b / (-2 * a), rel=1e-13)
    g = jax.grad(lambda x: controllability_gramian(jnp.array([[x]]), jnp.array([[b]]))[0, 0])(a)
    assert float(g) == pytest.approx(b * b / (2 * a * a), rel=1e-10)  # d/da of b²/(−2a)


def test_bad_input_raises():
    with pytest.raises(ValueError, match="a:"):
        controllability_gramian(np.array([[0.1]]), np.array([[1.0]]))  # not Hurwitz
    with pytest.raises(ValueError, match="b:"):
        controllability_gramian(-np.eye(2), np.ones((3, 1)))
    with pytest.raises(ValueError, match="n_steps"):
        impulse_gramian(-np.eye(2), np.ones((2, 1)), 5.0, 11)
