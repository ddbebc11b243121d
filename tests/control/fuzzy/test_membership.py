"""Membership functions against scikit-fuzzy's and simpful's generators; gradients; bad input."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import simpful
import skfuzzy as fuzz

from jaxsim.control import fuzzy as fz

X = np.linspace(-3.0, 3.0, 601)


def _rng_params(kind, rng):
    if kind == "triangular":
        return np.sort(rng.uniform(-2, 2, 3))
    if kind == "trapezoidal":
        return np.sort(rng.uniform(-2, 2, 4))
    if kind == "gaussian":
        return np.array([rng.uniform(-1, 1), rng.uniform(0.2, 1.5)])
    if kind == "bell":
        return np.array([rng.uniform(0.3, 1.5), rng.uniform(0.6, 3.0), rng.uniform(-1, 1)])
    if kind == "sigmoid":
        return np.array([rng.uniform(-1, 1), rng.uniform(-6, 6)])
    raise AssertionError(kind)


SKFUZZY = {
    "triangular": lambda x, p: fuzz.trimf(x, p),
    "trapezoidal": lambda x, p: fuzz.trapmf(x, p),
    "gaussian": lambda x, p: fuzz.gaussmf(x, p[0], p[1]),
    "bell": lambda x, p: fuzz.gbellmf(x, p[0], p[1], p[2]),
    "sigmoid": lambda x, p: fuzz.sigmf(x, p[0], p[1]),
}
SIMPFUL = {
    "triangular": lambda p: simpful.Triangular_MF(*p),
    "trapezoidal": lambda p: simpful.Trapezoidal_MF(*p),
    "gaussian": lambda p: simpful.Gaussian_MF(p[0], p[1]),
    "sigmoid": lambda p: simpful.Sigmoid_MF(p[0], p[1]),
}


@pytest.mark.parametrize("kind", sorted(SKFUZZY))
def test_membership_functions_equal_skfuzzy_and_simpful(kind):
    rng = np.random.default_rng(1)
    for _ in range(5):
        p = _rng_params(kind, rng)
        # include the breakpoints themselves (vertical edges, peaks) in the evaluation points
        x = np.union1d(X, p)
        ours = np.asarray(fz.terms(kind, p[None])(x))[:, 0]
        np.testing.assert_allclose(ours, SKFUZZY[kind](x, p), rtol=0, atol=1e-14)
        if kind in SIMPFUL:
            mf = SIMPFUL[kind](p)
            np.testing.assert_allclose(ours, [mf(v) for v in x], rtol=0, atol=1e-14)


def test_degenerate_edges_follow_skfuzzy():
    x = np.linspace(-1, 2, 301)
    for p in ([0.0, 0.0, 1.0], [0.0, 1.0, 1.0], [0.5, 0.5, 0.5]):
        np.testing.assert_allclose(fz.triangular(x, *p), fuzz.trimf(x, p), atol=1e-15)
    for p in ([0.0, 0.0, 0.5, 1.0], [0.0, 0.5, 1.0, 1.0], [0.0, 0.0, 1.0, 1.0]):
        np.testing.assert_allclose(fz.trapezoidal(x, *p), fuzz.trapmf(x, p), atol=1e-15)


def test_piecewise_linear_is_interpolation_with_shoulders():
    p = np.array([-1.0, 0.0, 0.5, 2.0, 0.2, 1.0, 0.4, 0.0])
    x = np.linspace(-3, 3, 121)
    np.testing.assert_allclose(fz.piecewise_linear(x, *p), np.interp(x, p[:4], p[4:]), atol=1e-15)
    # simpful's point-based fuzzy sets are shouldered the same way
    fs = simpful.FuzzySet(points=[[xi, yi] for xi, yi in zip(p[:4], p[4:])], term="t")
    np.testing.assert_allclose(fz.piecewise_linear(x, *p), [fs.get_value(v) for v in x], atol=1e-14)


PARAMS = {
    "triangular": [-0.7, 0.1, 0.9],
    "trapezoidal": [-0.9, -0.2, 0.3, 1.1],
    "gaussian": [0.2, 0.6],
    "bell": [0.7, 1.6, -0.1],
    "sigmoid": [0.1, 3.0],
    "piecewise_linear": [-1.0, -0.2, 0.4, 1.2, 0.05, 0.9, 0.6, 0.1],
}


@pytest.mark.parametrize("kind", sorted(PARAMS))
def test_gradients_equal_central_differences(kind):
    p0 = jnp.asarray(PARAMS[kind])
    # points away from the corners of the piecewise-linear kinds
    xs = jnp.asarray([-0.83, -0.45, -0.05, 0.21, 0.66, 0.95])
    f = lambda p, x: fz.terms(kind, p[None])(x)[0]  # noqa: E731
    h = 1e-6
    for x in xs:
        g = jax.grad(f, argnums=(0, 1))(p0, x)
        fd_p = np.array([(f(p0.at[j].add(h), x) - f(p0.at[j].add(-h), x)) / (2 * h) for j in range(p0.size)])
        fd_x = (f(p0, x + h) - f(p0, x - h)) / (2 * h)
        np.testing.assert_allclose(g[0], fd_p, rtol=1e-6, atol=1e-8)
        np.testing.assert_allclose(g[1], fd_x, rtol=1e-6, atol=1e-8)


def test_bell_gradient_is_finite_at_its_centre():
    g = jax.grad(lambda p: fz.bell(0.3, *p), argnums=0)(jnp.asarray([0.5, 2.0, 0.3]))
    assert np.all(np.isfinite(np.asarray(g)))


@pytest.mark.parametrize(
    "kind, params, match",
    [
        ("triangular", [[0.0, -1.0, 1.0]], "a ≤ b ≤ c"),
        ("trapezoidal", [[0.0, 1.0, 0.5, 2.0]], "a ≤ b ≤ c ≤ d"),
        ("gaussian", [[0.0, 0.0]], "sigma > 0"),
        ("bell", [[-1.0, 2.0, 0.0]], "width > 0"),
        ("piecewise_linear", [[0.0, 0.0, 0.5, 1.0]], "increasing x"),
        ("piecewise_linear", [[0.0, 1.0, 0.5, 1.5]], "0 ≤ y ≤ 1"),
        ("triangular", [[0.0, 1.0]], "3 parameters"),
        ("triangular", [[0.0, np.nan, 1.0]], "finite"),
        ("spline", [[0.0, 1.0, 2.0]], "kind"),
    ],
)
def test_bad_membership_parameters_raise_naming_the_argument(kind, params, match):
    with pytest.raises(ValueError, match=match) as info:
        fz.terms(kind, params)
    assert str(info.value).split(":")[0] in ("params", "kind")
