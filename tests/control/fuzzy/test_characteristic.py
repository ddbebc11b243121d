"""The paper's three-section characteristic: gains, forms, gradients, fit, bad input."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.control import fuzzy as fz


def test_paper_gains_from_breakpoints():
    static = fz.three_section(0.75, 0.3, 1.2, 1.0)  # paper line 488: K1 = 0.4, K2 = 1.56
    astatic = fz.three_section(0.2, 0.25, 1.2, 2.0)  # lines 619–620: K1 = 1.25, K2 = 1.75
    assert float(static.k1) == pytest.approx(0.4, abs=1e-15)
    assert float(static.k2) == pytest.approx(0.7 / 0.45, abs=1e-15)
    assert round(float(static.k2), 2) == 1.56
    assert float(astatic.k1) == pytest.approx(1.25, abs=1e-15)
    assert float(astatic.k2) == pytest.approx(1.75, abs=1e-15)
    back = fz.from_gains(1.25, 1.75, 0.2, 1.2)
    assert (float(back.b), float(back.d)) == pytest.approx((0.25, 2.0), abs=1e-15)


def test_exact_form_sections_and_odd_symmetry():
    p = fz.three_section(0.75, 0.3, 1.2, 1.0)
    e = jnp.asarray([0.0, 0.5, 0.75, 1.0, 1.2, 3.0])
    expected = [0.0, 0.2, 0.3, 0.3 + (0.7 / 0.45) * 0.25, 1.0, 1.0]
    np.testing.assert_allclose(p(e), expected, atol=1e-15)
    np.testing.assert_allclose(p(-e), -np.asarray(expected), atol=1e-15)
    # the slope at the origin is K1 (not 0 from sign(e)·|e|)
    assert float(jax.grad(lambda v: p(v))(0.0)) == pytest.approx(0.4)


@pytest.mark.parametrize("tau", [0.05, 0.01, 0.001])
def test_smooth_form_is_odd_and_within_its_bound(tau):
    a, b, c, d = 0.75, 0.3, 1.2, 1.0
    exact = fz.three_section(a, b, c, d)
    smooth = fz.three_section(a, b, c, d, form="smooth", temperature=tau)
    e = jnp.linspace(-3, 3, 2001)
    gap = np.max(np.abs(np.asarray(smooth(e) - exact(e))))
    k1, k2 = 0.4, 0.7 / 0.45
    assert gap <= tau * np.log(2) * (abs(k2 - k1) + k2) + 1e-12
    assert gap >= 0.5 * tau * np.log(2) * abs(k2 - k1)  # the bound is attained at the corner ±a
    np.testing.assert_allclose(smooth(-e), -smooth(e), atol=1e-15)
    assert float(smooth(0.0)) == 0.0


@pytest.mark.parametrize("form", ["exact", "smooth"])
def test_gradients_wrt_breakpoints_equal_central_differences(form):
    def u(params, e):
        a, b, c, d = params
        return fz.ThreeSection(a, b, c, d, 0.02, form)(e)

    p0 = jnp.asarray([0.75, 0.3, 1.2, 1.0])
    g = jax.jit(jax.grad(u, argnums=(0, 1)))
    h = 1e-6
    for e in (0.31, 0.9, 1.05, 2.2, -0.6, -1.0):  # one point per section, away from the kinks
        ga, ge = g(p0, e)
        fd = [(u(p0.at[j].add(h), e) - u(p0.at[j].add(-h), e)) / (2 * h) for j in range(4)]
        np.testing.assert_allclose(ga, fd, rtol=1e-6, atol=1e-8)
        assert float(ge) == pytest.approx(float((u(p0, e + h) - u(p0, e - h)) / (2 * h)), rel=1e-6, abs=1e-8)


@pytest.mark.parametrize(
    "args, name",
    [
        ((1.2, 0.3, 0.75, 1.0), "a"),  # a ≥ c
        ((0.75, 0.3, 0.75, 1.0), "a"),
        ((-0.75, 0.3, 1.2, 1.0), "a"),
        ((0.75, -0.3, 1.2, 1.0), "b"),
        ((0.75, 0.3, 1.2, 0.0), "d"),
        ((0.75, 0.3, 1.2, 0.2), "d"),  # d < b
        ((0.75, 0.3, np.inf, 1.0), "c"),
    ],
)
def test_bad_breakpoints_raise_naming_the_argument(args, name):
    with pytest.raises(ValueError, match=f"^{name}:"):
        fz.three_section(*args)


def test_fit_recovers_a_three_section_characteristic():
    true = fz.three_section(0.62, 0.41, 1.37, 1.18)
    e = jnp.linspace(-2.5, 2.5, 401)
    fit = fz.fit_three_section(e, true(e))
    assert fit.abcd == pytest.approx((0.62, 0.41, 1.37, 1.18), abs=1e-6)
    assert fit.rms < 1e-8
    with pytest.raises(ValueError, match="u:"):
        fz.fit_three_section(e, true(e)[:-1])


def test_static_characteristic_of_a_single_input_mamdani_and_its_fit():
    # a symmetric five-term controller with terms moved away from the centre (the paper's Fig. 2)
    inputs = [
        (
            "trapezoidal",
            [
                [-9, -9, -1.4, -0.7],
                [-1.4, -0.7, -0.7, 0.0],
                [-0.7, 0.0, 0.0, 0.7],
                [0.0, 0.7, 0.7, 1.4],
                [0.7, 1.4, 9, 9],
            ],
        )
    ]
    out = ("triangular", [[-1.5, -1.0, -0.5], [-1.0, -0.3, 0.0], [-0.3, 0.0, 0.3], [0.0, 0.3, 1.0], [0.5, 1.0, 1.5]])
    fis = fz.mamdani(inputs, np.linspace(-1.5, 1.5, 301), out, fz.rule_base([[0], [1], [2], [3], [4]], range(5)))
    e = jnp.linspace(-2.0, 2.0, 201)
    u = np.asarray(jax.jit(fz.static_characteristic)(fis, e))
    ev = jax.jit(fz.evaluate)
    for k in (13, 57, 100, 161):
        assert u[k] == pytest.approx(float(ev(fis, e[k : k + 1])), abs=1e-14)
    np.testing.assert_allclose(u[::-1], -u, atol=1e-12)  # odd
    fit = fz.fit_three_section(e, u)
    a, b, c, d = fit.abcd
    assert 0 < a < c and 0 < b < d
    assert fit.rms < 0.05 * d  # three sections describe the curve to a few percent of its range


def test_odd_sugeno_template_is_exactly_the_three_section_characteristic():
    e = jnp.linspace(-3.0, 3.0, 601)
    sug = fz.odd_sugeno([0.75, 1.2], [0.3, 1.0])
    u = jax.jit(fz.static_characteristic)(sug, e)
    np.testing.assert_allclose(u, fz.three_section(0.75, 0.3, 1.2, 1.0)(e), atol=1e-14)


def test_odd_mamdani_template_has_the_three_section_shape():
    mam = fz.odd_mamdani([0.75, 1.2], [0.3, 1.0], 0.1, u_range=1.5)
    e = jnp.linspace(-3.0, 3.0, 301)
    fit = fz.fit_three_section(e, jax.jit(fz.static_characteristic)(mam, e))
    assert fit.abcd == pytest.approx((0.75, 0.3, 1.2, 1.0), abs=0.06)
