"""Lyapunov and Sylvester solvers: SciPy's oracle cases, implicit derivatives, vmap, bad input."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg as sl

from jaxsim.control.lyapunov import solve_continuous_lyapunov, solve_discrete_lyapunov
from jaxsim.control.sylvester import solve_sylvester

# Real-valued cases of SciPy's TestSolveLyapunov (scipy/linalg/tests/test_solvers.py): a non-normal
# 2×2, Kitagawa's 1977 5×5 example and an 11×11 companion matrix.
KITAGAWA_A = np.array([[3, 9, 5, 1, 4], [1, 2, 3, 8, 4], [4, 6, 6, 6, 3], [1, 5, 2, 0, 7], [5, 3, 3, 1, 5.0]])
KITAGAWA_Q = np.array([[2, 4, 1, 0, 1], [4, 1, 0, 2, 0], [1, 0, 3, 0, 3], [0, 2, 0, 1, 0], [1, 0, 3, 0, 4.0]])
COMPANION = np.diag(np.ones(10), -1)
COMPANION[0] = np.linspace(0.1, 0.01, 11)
LYAP_CASES = [
    (np.array([[1, 2], [3, 4.0]]), np.array([[9, 10], [11, 12.0]])),
    (KITAGAWA_A, KITAGAWA_Q),
    (COMPANION, np.eye(11)),
    (np.array([[0, 1], [-0.5, -1]]), np.array([[0, 0], [0, 9.0]])),  # scipy gh-4176
]
SYLV_CASES = [
    (np.array([[1, 2], [0, 4.0]]), np.array([[5, 6], [0, 8.0]]), np.array([[9, 10], [11, 12.0]])),
    (
        np.array([[1.0, 0, 0, 0], [0, 1.0, 2.0, 0.0], [0, 0, 3.0, -4], [0, 0, 2, 5]]),
        np.array([[2.0, 0, 0, 1.0], [0, 1.0, 0.0, 0.0], [0, 0, 1.0, -1], [0, 0, 1, 1]]),
        np.eye(4),
    ),
    (np.array([[8, 1, 6], [3, 5, 7], [4, 9, 2.0]]), np.array([[2, 3], [4, 5.0]]), np.array([[1, 2], [3, 4], [5, 6.0]])),
]


def _rel(x, ref):
    return np.linalg.norm(np.asarray(x) - ref) / np.linalg.norm(ref)


@pytest.mark.parametrize("a, q", LYAP_CASES)
def test_continuous_lyapunov_matches_scipy(a, q):
    assert _rel(solve_continuous_lyapunov(a, q), sl.solve_continuous_lyapunov(a, q)) < 1e-12


@pytest.mark.parametrize("a, q", LYAP_CASES)
def test_discrete_lyapunov_matches_scipy_and_its_equation(a, q):
    x = np.asarray(solve_discrete_lyapunov(a, q))
    assert _rel(x, sl.solve_discrete_lyapunov(a, q)) < 1e-10
    assert np.linalg.norm(a @ x @ a.T - x + q) <= 1e-11 * np.linalg.norm(x) * max(1, np.linalg.norm(a)) ** 2


@pytest.mark.parametrize("a, b, c", SYLV_CASES)
def test_sylvester_matches_scipy(a, b, c):
    assert _rel(solve_sylvester(a, b, c), sl.solve_sylvester(a, b, c)) < 1e-12


def _central(f, x, e, h=1e-6):
    return (f(x + h * e) - f(x - h * e)) / (2 * h)


def test_lyapunov_gradients_match_finite_differences_in_both_modes():
    rng = np.random.default_rng(1)
    a, q = rng.normal(size=(4, 4)), rng.normal(size=(4, 4))
    w = rng.normal(size=(4, 4))

    def cont(a, q):
        return jnp.sum(w * jnp.tanh(solve_continuous_lyapunov(a, q)))

    def disc(a, q):
        return jnp.sum(w * jnp.tanh(solve_discrete_lyapunov(0.4 * a, q)))

    for f in (cont, disc):
        ga, gq = jax.grad(f, argnums=(0, 1))(a, q)
        for i, j in [(0, 1), (2, 3), (3, 3)]:
            e = np.zeros((4, 4))
            e[i, j] = 1.0
            np.testing.assert_allclose(ga[i, j], _central(lambda v: f(v, q), a, e), rtol=1e-6, atol=1e-9)
            np.testing.assert_allclose(gq[i, j], _central(lambda v: f(a, v), q, e), rtol=1e-6, atol=1e-9)
        fwd = jax.jacfwd(f)(a, q)
        np.testing.assert_allclose(fwd, ga, rtol=1e-10, atol=1e-12)


def test_sylvester_gradient_matches_finite_differences():
    rng = np.random.default_rng(2)
    a, b, c = rng.normal(size=(3, 3)), rng.normal(size=(2, 2)), rng.normal(size=(3, 2))

    def f(a, b, c):
        return jnp.sum(jnp.sin(solve_sylvester(a, b, c)))

    g = jax.grad(f, argnums=(0, 1, 2))(a, b, c)
    for k, (arg, idx) in enumerate([(a, (1, 2)), (b, (0, 1)), (c, (2, 0))]):
        e = np.zeros_like(arg)
        e[idx] = 1.0
        args = [a, b, c]

        def fk(v, k=k):
            args_k = list(args)
            args_k[k] = v
            return f(*args_k)

        np.testing.assert_allclose(g[k][idx], _central(fk, arg, e), rtol=1e-6, atol=1e-9)


def test_vmap_equals_loop():
    rng = np.random.default_rng(3)
    a, q = rng.normal(size=(6, 3, 3)), rng.normal(size=(6, 3, 3))
    batched = jax.jit(jax.vmap(solve_continuous_lyapunov))(a, q)
    for i in range(6):
        np.testing.assert_allclose(batched[i], sl.solve_continuous_lyapunov(a[i], q[i]), rtol=1e-11, atol=1e-12)


def test_bad_input_names_the_argument():
    with pytest.raises(ValueError, match="a: expected a square matrix"):
        solve_continuous_lyapunov(np.ones((2, 3)), np.eye(2))
    with pytest.raises(ValueError, match="q: expected shape"):
        solve_discrete_lyapunov(np.eye(2), np.eye(3))
    with pytest.raises(ValueError, match="c: expected shape"):
        solve_sylvester(np.eye(2), np.eye(3), np.ones((3, 2)))
    with pytest.raises(ValueError, match="q: must be finite"):
        solve_continuous_lyapunov(np.eye(2), np.full((2, 2), np.nan))
