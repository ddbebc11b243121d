"""``mode="measure"``: the tuner times both AD modes once per problem and runs the faster; a mode
JAX cannot differentiate the loss in is left out; a second call measures and compiles nothing."""

import jax
import jax.numpy as jnp
import numpy as np
import optax
import pytest

from optim.tune import tune
from tests.optim.test_tune_chunks import _compile_messages


def _fixed_point(x):
    """A loss through a ``lax.while_loop`` (a data-dependent iteration count): forward mode only."""

    def body(c):
        y, k = c
        return 0.5 * (y + x / y), k + 1

    y, _ = jax.lax.while_loop(lambda c: (jnp.max(jnp.abs(c[0] ** 2 - x)) > 1e-12) & (c[1] < 60), body, (x, 0))
    return jnp.sum((y - 1.5) ** 2)  # y = sqrt(x): minimiser x = 2.25


@jax.custom_vjp
def _square(x):
    return x**2


_square.defvjp(lambda x: (x**2, x), lambda x, g: (2.0 * x * g,))


def test_only_forward_mode_differentiates_a_while_loop():
    result = tune(_fixed_point, jnp.array([1.0, 4.0]), method="lbfgs", steps=100, gtol=1e-10, mode="measure")
    assert result.mode == "forward"
    np.testing.assert_allclose(result.params, [2.25, 2.25], rtol=1e-8)
    with pytest.raises(ValueError, match="while_loop"):
        tune(_fixed_point, jnp.array([1.0, 4.0]), steps=2, mode="reverse")


def test_only_reverse_mode_differentiates_a_custom_vjp():
    def loss(x):
        return jnp.sum(_square(x - 3.0))

    result = tune(loss, jnp.zeros(2), method="lbfgs", steps=50, gtol=1e-10, mode="measure")
    assert result.mode == "reverse"
    np.testing.assert_allclose(result.params, [3.0, 3.0], rtol=1e-9)


def test_neither_mode_compiling_raises_the_loss_error():
    def loss(x):
        return jnp.sum(x) @ jnp.ones(3)  # a matmul of a scalar: a shape error in either mode

    with pytest.raises(ValueError, match="matmul input operand 0"):
        tune(loss, jnp.zeros(2), steps=2, mode="measure")


def _many_gains(x):
    """300 parameters through a 200-step recursion: forward mode pushes 300 tangent lanes through
    every step, reverse mode one adjoint pass (about a hundred times less work)."""

    def step(y, k):
        y = jnp.tanh(y + 0.01 * x * jnp.sin(0.1 * k))
        return y, jnp.sum(y**2)

    _, costs = jax.lax.scan(step, jnp.zeros_like(x), jnp.arange(200.0))
    return jnp.sum(costs) + jnp.sum((x - 1.0) ** 2)


def test_measure_picks_reverse_mode_for_many_parameters_and_matches_it():
    opts = dict(optimizer=optax.adam(0.05), steps=30, n_starts=1)
    x0 = jnp.zeros(300)
    measured, compiled_first, _ = _compile_messages(lambda: tune(_many_gains, x0, mode="measure", **opts))
    assert measured.mode == "reverse" and len(compiled_first) >= 2  # both modes' chunks were compiled
    # the run is the reverse-mode run, bit for bit, and neither measures nor compiles again
    reverse, compiled_reverse, _ = _compile_messages(lambda: tune(_many_gains, x0, mode="reverse", **opts))
    again, compiled_again, traced_again = _compile_messages(lambda: tune(_many_gains, x0, mode="measure", **opts))
    assert compiled_reverse == [] and compiled_again == [] and traced_again == []
    for other in (reverse, again):
        np.testing.assert_array_equal(other.params, measured.params)
        np.testing.assert_array_equal(other.history.loss, measured.history.loss)
        assert other.mode == "reverse"


def test_bad_mode_is_named():
    with pytest.raises(ValueError, match="mode: must be 'auto', 'forward', 'reverse' or 'measure'"):
        tune(_many_gains, jnp.zeros(3), mode="fastest")
