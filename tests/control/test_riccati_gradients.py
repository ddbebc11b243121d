"""Implicit derivatives of the Riccati solutions and LQR/Kalman gains.

Oracles: central finite differences of our own solver (rel. 1e-6), CasADi's rootfinder (whose
sensitivities come from CasADi's own implicit-function machinery on the symbolic CARE/DARE
residual), forward == reverse mode, and the gradient of a cost through ``vmap``.
"""

import casadi as ca
import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg as sl

from jaxsim.control.kalman_gain import discrete_kalman, kalman_bucy
from jaxsim.control.lqr import dlqr, lqr
from jaxsim.control.riccati import MarginalStabilityWarning, solve_continuous_are, solve_discrete_are

N, M = 4, 2


def _system(seed, discrete=False):
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(N, N))
    if discrete:
        a = a / np.max(np.abs(np.linalg.eigvals(a))) * 1.2
    b = rng.normal(size=(N, M))
    theta = np.concatenate([rng.uniform(0.5, 2.0, N), rng.uniform(0.5, 2.0, M)])  # diag Q, diag R
    return a, b, theta


def _gain_fn(a, b, discrete):
    design = dlqr if discrete else lqr
    return jax.jit(lambda th: design(a, b, jnp.diag(th[:N]), jnp.diag(th[N:])).k)


def _central_jacobian(f, x, h=1e-5):
    cols = [(np.asarray(f(x + h * e)) - np.asarray(f(x - h * e))) / (2 * h) for e in np.eye(x.size)]
    return np.stack(cols, axis=-1)


def _casadi_gain_jacobian(a, b, theta, discrete):
    """dK/dθ from CasADi: a Newton rootfinder on the symbolic residual, differentiated by CasADi."""
    x = ca.SX.sym("x", N * N)
    p = ca.SX.sym("p", N + M)
    xm = ca.reshape(x, N, N)
    am, bm = ca.DM(a), ca.DM(b)
    qm, rm = ca.diag(p[:N]), ca.diag(p[N:])
    if discrete:
        kx = ca.solve(rm + bm.T @ xm @ bm, bm.T @ xm @ am)
        res = am.T @ xm @ am - xm - am.T @ xm @ bm @ kx + qm
    else:
        res = am.T @ xm + xm @ am - xm @ bm @ ca.solve(rm, bm.T) @ xm + qm
    rf = ca.rootfinder("rf", "newton", ca.Function("g", [x, p], [ca.vec(res)]), {"abstol": 1e-14})
    x0, pp = ca.MX.sym("x0", N * N), ca.MX.sym("p", N + M)
    xs = ca.reshape(rf(x0, pp), N, N)
    rr = ca.diag(pp[N:])
    k = ca.solve(rr + bm.T @ xs @ bm, bm.T @ xs @ am) if discrete else ca.solve(rr, bm.T @ xs)
    jac = ca.Function("gain_jacobian", [x0, pp], [ca.jacobian(ca.vec(k), pp)])
    ref = sl.solve_discrete_are if discrete else sl.solve_continuous_are
    x_start = ref(a, b, np.diag(theta[:N]), np.diag(theta[N:]))
    j = np.asarray(jac(x_start.reshape(-1, order="F"), theta))
    return j.reshape(M, N, N + M, order="F")


@pytest.mark.parametrize("discrete", [False, True], ids=["lqr", "dlqr"])
def test_gain_jacobian_matches_finite_differences_and_casadi(discrete):
    a, b, theta = _system(7, discrete)
    k_of = _gain_fn(a, b, discrete)
    j_fwd = np.asarray(jax.jacfwd(k_of)(theta))
    j_rev = np.asarray(jax.jacrev(k_of)(theta))
    scale = np.abs(j_fwd).max()
    np.testing.assert_allclose(j_rev, j_fwd, rtol=0, atol=1e-12 * scale)
    j_fd = _central_jacobian(k_of, theta)
    assert np.abs(j_fwd - j_fd).max() <= 1e-6 * scale
    j_ca = _casadi_gain_jacobian(a, b, theta, discrete)
    assert np.abs(j_fwd - j_ca).max() <= 1e-9 * scale


@pytest.mark.parametrize("discrete", [False, True], ids=["care", "dare"])
def test_solution_gradient_wrt_a_and_b_matches_finite_differences(discrete):
    a, b, theta = _system(11, discrete)
    q, r = np.diag(theta[:N]), np.diag(theta[N:])
    solve = solve_discrete_are if discrete else solve_continuous_are
    w = np.random.default_rng(0).normal(size=(N, N))

    @jax.jit
    def f(a, b):
        return jnp.sum(w * solve(a, b, q, r))

    ga, gb = jax.grad(f, argnums=(0, 1))(a, b)
    for arg, g, idx, k in [(a, ga, (1, 3), 0), (a, ga, (2, 2), 0), (b, gb, (0, 1), 1)]:
        e = np.zeros_like(arg)
        e[idx] = 1e-6
        plus = f(a + e, b) if k == 0 else f(a, b + e)
        minus = f(a - e, b) if k == 0 else f(a, b - e)
        np.testing.assert_allclose(g[idx], (plus - minus) / 2e-6, rtol=1e-6)


def test_kalman_gains_are_differentiable_in_the_noise_intensities():
    a, _, _ = _system(5)
    c = np.random.default_rng(5).normal(size=(M, N))

    @jax.jit
    def cont(th):
        return kalman_bucy(a, c, jnp.diag(th[:N]), jnp.diag(th[N:])).l

    @jax.jit
    def disc(th):
        return discrete_kalman(0.5 * a, c, jnp.diag(th[:N]), jnp.diag(th[N:])).k

    theta = np.linspace(0.5, 2.0, N + M)
    for f in (cont, disc):
        j = np.asarray(jax.jacfwd(f)(theta))
        assert np.abs(j - _central_jacobian(f, theta)).max() <= 1e-6 * np.abs(j).max()


def test_gradient_of_a_batched_cost_equals_the_sum_of_single_gradients():
    a, b, theta = _system(3)
    thetas = theta * np.linspace(0.5, 1.5, 5)[:, None]

    def cost(th):
        return jnp.trace(lqr(a, b, jnp.diag(th[:N]), jnp.diag(th[N:])).p)

    batched = jax.jit(jax.vmap(jax.grad(cost)))(thetas)
    for i in range(5):
        np.testing.assert_allclose(batched[i], jax.grad(cost)(thetas[i]), rtol=1e-12)


@pytest.mark.parametrize("discrete", [False, True])
def test_gradient_at_a_marginal_solution_is_nan_not_an_error_about_internals(discrete):
    # A = 0 (resp. 1) with q = 0: the only solution X = 0 leaves the mode on the stability boundary,
    # so there is no stabilising solution; the maximal one (X = 0) is returned with a warning, and
    # its derivative does not exist: NaN, eagerly and under jit.
    a = jnp.array([[1.0 if discrete else 0.0]])
    solve = solve_discrete_are if discrete else solve_continuous_are
    f = lambda q: solve(a, jnp.eye(1), q, jnp.eye(1)).sum()  # noqa: E731
    with pytest.warns(MarginalStabilityWarning):
        assert abs(float(f(jnp.zeros((1, 1))))) < 1e-12
    assert np.isnan(jax.grad(f)(jnp.zeros((1, 1)))).all()
    assert np.isnan(jax.jit(jax.grad(f))(jnp.zeros((1, 1)))).all()


def test_gradient_of_a_failed_solve_is_nan_not_an_error_about_internals():
    # (A, B) not stabilisable: no solution at all; eager gives the error, traced solves NaN
    a, b = jnp.diag(jnp.array([1.0, -1.0])), jnp.array([[0.0], [1.0]])
    f = lambda q: solve_continuous_are(a, b, q, jnp.eye(1)).sum()  # noqa: E731
    with pytest.raises(ValueError, match="not stabilisable"):
        f(jnp.eye(2))
    assert np.isnan(jax.grad(f)(jnp.eye(2))).all()
    assert np.isnan(jax.jit(jax.grad(f))(jnp.eye(2))).all()
