"""ZOH discretisation against SciPy; Van Loan against direct quadrature."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.integrate
import scipy.linalg
import scipy.signal

from jaxsim.core.discretize import c2d_zoh, van_loan


@pytest.mark.parametrize("seed", range(5))
def test_c2d_zoh_matches_scipy_cont2discrete(seed):
    rng = np.random.default_rng(seed)
    n, m = rng.integers(1, 6), rng.integers(1, 3)
    a = rng.normal(size=(n, n))
    b = rng.normal(size=(n, m))
    dt = float(rng.uniform(0.01, 0.5))
    ad, bd = c2d_zoh(a, b, dt)
    ad_ref, bd_ref, *_ = scipy.signal.cont2discrete((a, b, np.eye(n), np.zeros((n, m))), dt, method="zoh")
    np.testing.assert_allclose(ad, ad_ref, rtol=1e-12, atol=1e-13)
    np.testing.assert_allclose(bd, bd_ref, rtol=1e-12, atol=1e-13)


def test_c2d_zoh_second_order_plant():
    a = np.array([[0.0, 1.0], [-20.0, -12.0]])
    b = np.array([[0.0], [40.0]])
    ad, bd = c2d_zoh(a, b, 1e-3)
    ad_ref, bd_ref, *_ = scipy.signal.cont2discrete((a, b, np.eye(2), np.zeros((2, 1))), 1e-3)
    np.testing.assert_allclose(ad, ad_ref, rtol=1e-13)
    np.testing.assert_allclose(bd, bd_ref, rtol=1e-12)


@pytest.mark.parametrize("seed", range(3))
def test_van_loan_matches_quadrature(seed):
    rng = np.random.default_rng(10 + seed)
    n, q = 3, 2
    a = rng.normal(size=(n, n)) - 1.0 * np.eye(n)
    g = rng.normal(size=(n, q))
    l = rng.normal(size=(q, q))
    qc = l @ l.T
    dt = 0.3
    ad, qd = van_loan(a, qc, dt, g)

    def integrand(tau):
        e = scipy.linalg.expm(a * tau)
        return (e @ g @ qc @ g.T @ e.T).ravel()

    want = scipy.integrate.quad_vec(integrand, 0.0, dt, epsabs=1e-14, epsrel=1e-13)[0].reshape(n, n)
    np.testing.assert_allclose(ad, scipy.linalg.expm(a * dt), rtol=1e-12)
    np.testing.assert_allclose(qd, want, rtol=1e-10, atol=1e-14)
    assert np.all(np.linalg.eigvalsh(np.asarray(qd)) > 0)


def test_van_loan_random_walk_closed_form():
    # x' = w, intensity q: Qd = q dt; double integrator: [[dt^3/3, dt^2/2], [dt^2/2, dt]] q
    q, dt = 2.5, 0.1
    _, qd = van_loan(jnp.zeros((1, 1)), jnp.array([[q]]), dt)
    np.testing.assert_allclose(qd, [[q * dt]], rtol=1e-14)
    a = jnp.array([[0.0, 1.0], [0.0, 0.0]])
    _, qd2 = van_loan(a, jnp.array([[q]]), dt, jnp.array([[0.0], [1.0]]))
    np.testing.assert_allclose(qd2, q * np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]]), rtol=1e-13)


def test_discretisation_is_vmappable_and_differentiable():
    a = jnp.array([[0.0, 1.0], [-20.0, -12.0]])
    b = jnp.array([[0.0], [40.0]])
    dts = jnp.array([1e-3, 1e-2, 0.1])
    ads, _ = jax.vmap(lambda d: c2d_zoh(a, b, d))(dts)
    for i, d in enumerate(dts):
        np.testing.assert_allclose(ads[i], scipy.linalg.expm(np.asarray(a) * float(d)), rtol=1e-12)
    g = jax.grad(lambda d: c2d_zoh(a, b, d)[0][0, 1])(0.1)
    h = 1e-6
    fd = (scipy.linalg.expm(np.asarray(a) * (0.1 + h))[0, 1] - scipy.linalg.expm(np.asarray(a) * (0.1 - h))[0, 1]) / (
        2 * h
    )
    np.testing.assert_allclose(g, fd, rtol=1e-7)


def test_bad_input_names_the_argument():
    with pytest.raises(ValueError, match="a: expected a square"):
        c2d_zoh(np.ones((2, 3)), np.ones((2, 1)), 0.1)
    with pytest.raises(ValueError, match="b: expected shape"):
        c2d_zoh(np.eye(2), np.ones((3, 1)), 0.1)
    with pytest.raises(ValueError, match="dt"):
        c2d_zoh(np.eye(2), np.ones((2, 1)), -1.0)
    with pytest.raises(ValueError, match="a: must be finite"):
        c2d_zoh(np.array([[np.nan, 0], [0, 1.0]]), np.ones((2, 1)), 0.1)
    with pytest.raises(ValueError, match="g: expected shape"):
        van_loan(np.eye(2), np.eye(1), 0.1, np.ones((3, 1)))
