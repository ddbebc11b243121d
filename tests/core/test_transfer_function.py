"""SISO tf ↔ ss against scipy.signal; round trips on random proper transfer functions (hypothesis)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.signal
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

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


PROPERTY = settings(max_examples=40, deadline=None, derandomize=True)  # reproducible in CI
bounded = st.floats(-3.0, 3.0, allow_subnormal=False)


@st.composite
def _proper_tf(draw):
    """``num/den`` of order 1…5: poles with moduli in [0.3, 3] (real or conjugate pairs, so the
    coefficients are well conditioned), a leading coefficient of either sign, any proper numerator."""
    n = draw(st.integers(1, 5))
    poles = []
    while len(poles) < n:
        r, ang = draw(st.floats(0.3, 3.0)), draw(st.floats(0.0, np.pi))
        if len(poles) + 2 <= n and draw(st.booleans()):
            poles += [r * np.exp(1j * ang), r * np.exp(-1j * ang)]
        else:
            poles.append(r * np.cos(ang))
    lead = draw(st.floats(0.5, 2.0)) * draw(st.sampled_from([-1.0, 1.0]))
    den = lead * np.real(np.poly(poles))
    num = draw(hnp.arrays(np.float64, draw(st.integers(1, n + 1)), elements=bounded))
    return num, den


def _points(poles: np.ndarray) -> np.ndarray:
    """Evaluation points to the right of every pole (bounded resolvent)."""
    sigma = max(float(np.max(np.real(poles))), 0.0) + 1.0
    return sigma + 1j * np.array([0.0, 0.3, 1.0, 4.0])


def _ss_response(a, b, c, d, s: np.ndarray) -> np.ndarray:
    a, b, c, d = (np.asarray(m, float) for m in (a, b, c, d))
    eye = np.eye(a.shape[0])
    return np.array([(c @ np.linalg.solve(z * eye - a, b) + d)[0, 0] for z in s])


@PROPERTY
@given(_proper_tf())
def test_tf_to_ss_to_tf_round_trip(tf):
    num, den = tf
    a, b, c, d = tf2ss(num, den)
    s = _points(np.roots(den))
    # the realisation has the transfer function's frequency response (NumPy resolvent vs polyval)
    np.testing.assert_allclose(
        _ss_response(a, b, c, d, s), np.polyval(num, s) / np.polyval(den, s), rtol=1e-10, atol=1e-12
    )
    # and converts back to the same coefficients, normalised to a monic denominator
    num2, den2 = ss2tf(a, b, c, d)
    padded = np.concatenate([np.zeros(len(den) - len(num)), num]) / den[0]
    np.testing.assert_allclose(den2, den / den[0], rtol=1e-9, atol=1e-9 * np.max(np.abs(den / den[0])))
    np.testing.assert_allclose(num2, padded, rtol=1e-9, atol=1e-9 * max(np.max(np.abs(padded)), 1.0))


moderate = st.one_of(st.just(0.0), st.floats(0.01, 3.0), st.floats(-3.0, -0.01))


@st.composite
def _state_space(draw):
    """SISO ``(A, B, C, D)`` of order 1…5 with moderate entries; ``B``, ``C``, ``D`` each scaled by a
    power of ten in [1e-12, 1e12] (badly scaled units, as in SI models with tiny gains)."""
    n = draw(st.integers(1, 5))
    scale = lambda: 10.0 ** draw(st.integers(-12, 12))  # noqa: E731
    a = draw(hnp.arrays(np.float64, (n, n), elements=moderate))
    b = draw(hnp.arrays(np.float64, (n, 1), elements=moderate)) * scale()
    c = draw(hnp.arrays(np.float64, (1, n), elements=moderate)) * scale()
    d = draw(hnp.arrays(np.float64, (1, 1), elements=moderate)) * scale()
    return a, b, c, d


@PROPERTY
@given(_state_space())
def test_ss_to_tf_to_ss_round_trip_keeps_the_frequency_response(abcd):
    """Errors are measured against ``|C|·|B|·‖(sI − A)⁻¹‖ + |D|``: a transfer function accurate to
    rounding whatever the scaling of ``B``, ``C`` and ``D``."""
    a, b, c, d = abcd
    num, den = ss2tf(a, b, c, d)
    poly_a = np.real(np.poly(a))
    np.testing.assert_allclose(den, poly_a, rtol=1e-9, atol=1e-9 * np.max(np.abs(poly_a)))
    s = _points(np.linalg.eigvals(a))
    want = _ss_response(a, b, c, d, s)
    eye = np.eye(a.shape[0])
    resolvent = max(np.linalg.norm(np.linalg.inv(z * eye - a), 2) for z in s)
    bound = 1e-9 * (np.linalg.norm(c) * np.linalg.norm(b) * resolvent + abs(d[0, 0]))
    got = np.polyval(np.asarray(num), s) / np.polyval(np.asarray(den), s)
    assert np.max(np.abs(got - want)) <= bound, (got, want)
    assert np.max(np.abs(_ss_response(*tf2ss(num, den), s) - want)) <= bound
