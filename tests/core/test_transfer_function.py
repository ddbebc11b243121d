"""SISO tf ↔ ss against scipy.signal."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.signal

from jaxsim.core.transfer_function import characteristic_polynomial, ss2tf, tf2ss


@pytest.mark.parametrize("seed", range(6))
def test_tf2ss_matches_scipy(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 6))
    den = rng.normal(size=n + 1)
    num = rng.normal(size=int(rng.integers(1, n + 2)))
    ours = tf2ss(num, den)
    ref = scipy.signal.tf2ss(num, den)
    for got, want in zip(ours, ref):
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("seed", range(6))
def test_ss2tf_matches_scipy(seed):
    rng = np.random.default_rng(100 + seed)
    n = int(rng.integers(1, 6))
    a, b, c, d = rng.normal(size=(n, n)), rng.normal(size=(n, 1)), rng.normal(size=(1, n)), rng.normal(size=(1, 1))
    num, den = ss2tf(a, b, c, d)
    num_ref, den_ref = scipy.signal.ss2tf(a, b, c, d)
    np.testing.assert_allclose(den, den_ref, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(num, num_ref[0], rtol=1e-10, atol=1e-10)


def test_round_trip_second_order_plants():
    for num, den in (([2.0], [0.05, 0.6, 1.0]), ([2.0], [0.1, 1.0, 0.0])):
        n2, d2 = ss2tf(*tf2ss(num, den))
        scale = den[0]
        np.testing.assert_allclose(np.asarray(d2) * scale, den, atol=1e-14)
        np.testing.assert_allclose(np.trim_zeros(np.asarray(n2) * scale, "f"), num, atol=1e-14)


def test_characteristic_polynomial_is_differentiable():
    a = jnp.array([[0.0, 1.0], [-2.0, -3.0]])
    g = jax.grad(lambda x: characteristic_polynomial(a.at[1, 1].set(x))[1])(-3.0)
    np.testing.assert_allclose(g, -1.0)  # det(sI - A) = s^2 - a11 s + ..., d/d a11 of coeff = -1


def test_bad_input():
    with pytest.raises(ValueError, match="num: improper"):
        tf2ss([1.0, 2.0, 3.0], [1.0, 1.0])
    with pytest.raises(ValueError, match="den: leading"):
        tf2ss([1.0], [0.0, 1.0])
    with pytest.raises(ValueError, match="b: expected shape"):
        ss2tf(np.eye(2), np.ones((2, 2)), np.ones((1, 2)), np.zeros((1, 1)))
