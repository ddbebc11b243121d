"""Switching functions: limits, boundary layers and slopes as documented."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.core import switching as sw

S = jnp.linspace(-3.0, 3.0, 601)


@pytest.mark.parametrize("name", ["saturation", "tanh", "ratio"])
def test_smooth_switches_converge_to_sign_and_have_slope_one_over_width(name):
    fn = sw.get_switch(name)
    far = jnp.abs(S) > 0.05
    errs = [float(jnp.max(jnp.abs(fn(S, w) - jnp.sign(S))[far])) for w in (1e-1, 1e-2, 1e-3)]
    assert errs[0] > errs[1] >= errs[2] and errs[2] < 0.03
    assert np.all(np.abs(fn(S, 0.1)) <= 1.0)
    np.testing.assert_allclose(fn(-S, 0.1), -fn(S, 0.1))  # odd
    assert float(jax.grad(fn)(0.0, 0.05)) == pytest.approx(20.0, rel=1e-12)


def test_documented_boundary_layer_values():
    assert float(sw.saturation(0.5, 0.5)) == 1.0 and float(sw.saturation(0.25, 0.5)) == 0.5
    assert float(sw.tanh_sign(2.0, 1.0)) == pytest.approx(0.9640, abs=1e-4)
    assert float(sw.ratio_sign(1e-3, 1e-3)) == pytest.approx(0.5, rel=1e-12)
    assert float(sw.sign(0.0)) == 0.0 and float(sw.sign(-2.0)) == -1.0


def test_bad_width_and_name():
    with pytest.raises(ValueError, match="width"):
        sw.tanh_sign(1.0, 0.0)
    with pytest.raises(ValueError, match="switch"):
        sw.get_switch("sigmoid")


def test_smooth_sign_is_tanh_for_positive_width_and_exact_sign_at_zero_with_finite_gradients():
    np.testing.assert_array_equal(sw.smooth_sign(S, 0.2), jnp.tanh(S / 0.2))
    np.testing.assert_array_equal(sw.smooth_sign(S, 0.0), jnp.sign(S))
    # the width is a parameter: one jitted function serves both, and d/d(width) is finite at 0
    f = jax.jit(sw.smooth_sign)
    np.testing.assert_array_equal(f(S, 0.0), jnp.sign(S))
    g = jax.grad(lambda w: jnp.sum(sw.smooth_sign(S, w)))
    assert np.isfinite(float(g(0.0))) and np.isfinite(float(g(0.2)))
    assert float(jax.grad(sw.smooth_sign)(0.0, 0.05)) == pytest.approx(20.0, rel=1e-12)
