"""Reference and disturbance signals: values, shapes, vmap."""

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.signals import Constant, FilteredStep, Piecewise, Ramp, Sine, Square, Step, Sum, sample

T = jnp.linspace(0.0, 4.0, 401)


def test_step_ramp_sine_square_closed_forms():
    t = np.asarray(T)
    np.testing.assert_allclose(sample(Step(2.0, 1.0), T)[:, 0], 2.0 * (t >= 1.0))
    np.testing.assert_allclose(sample(Ramp(0.5, 1.0), T)[:, 0], 0.5 * np.maximum(t - 1.0, 0.0), atol=1e-15)
    np.testing.assert_allclose(
        sample(Sine(1.5, 0.25, 0.3, 1.0), T)[:, 0], 1.0 + 1.5 * np.sin(2 * np.pi * 0.25 * t + 0.3), atol=1e-14
    )
    sq = np.asarray(sample(Square(1.0, 2.0, 0.25), T)[:, 0])
    want = np.where(np.mod(t, 2.0) / 2.0 < 0.25, 1.0, -1.0)
    np.testing.assert_array_equal(sq, want)
    np.testing.assert_allclose(sample(Constant(3.0), T)[:, 0], 3.0)


def test_piecewise_constant_and_linear():
    pc = Piecewise(jnp.array([0.0, 1.0, 2.0]), jnp.array([1.0, -1.0, 0.5]))
    v = sample(pc, jnp.array([-1.0, 0.0, 0.5, 1.0, 1.99, 2.0, 5.0]))[:, 0]
    np.testing.assert_allclose(v, [1.0, 1.0, 1.0, -1.0, -1.0, 0.5, 0.5])
    pl = Piecewise(jnp.array([0.0, 1.0, 2.0]), jnp.array([[0.0, 1.0], [1.0, 1.0], [1.0, 3.0]]), linear=True)
    np.testing.assert_allclose(pl(jnp.asarray(0.5)), [0.5, 1.0])
    np.testing.assert_allclose(pl(jnp.asarray(1.5)), [1.0, 2.0])


def test_sum_and_vector_signals_and_vmap():
    s = Sum((Step(jnp.array([1.0, 2.0])), Ramp(jnp.array([0.0, 1.0]))))
    np.testing.assert_allclose(s(jnp.asarray(2.0)), [1.0, 4.0])
    batch = Step(jnp.array([1.0, 2.0, 3.0]), jnp.zeros(3))
    out = jax.vmap(lambda sig: sig(jnp.asarray(1.0)))(batch)
    np.testing.assert_allclose(out[:, 0], [1.0, 2.0, 3.0])


def test_signal_is_differentiable_in_its_parameters():
    g = jax.grad(lambda a: Sine(a, 1.0)(jnp.asarray(0.125))[0])(2.0)
    np.testing.assert_allclose(g, np.sin(2 * np.pi * 0.125))


def test_filtered_step_closed_form_and_bad_time_constant():
    import pytest

    ts = np.array([0.0, 0.2, 0.5, 0.9])
    got = np.asarray(sample(FilteredStep(2.0, 0.3, 0.2), ts))[:, 0]
    want = np.where(ts >= 0.2, 2.0 * (1 - np.exp(-(ts - 0.2) / 0.3)), 0.0)
    np.testing.assert_allclose(got, want, rtol=1e-14, atol=1e-16)
    with pytest.raises(ValueError, match=r"signal.tau"):
        sample(FilteredStep(1.0, 0.0), ts)
