"""``mode="measure"``: the tuner times the AD modes once per problem and runs the faster (the second
mode compiled only when the first one's steps are dear); a mode JAX cannot differentiate the loss in
is left out; a second call measures and compiles nothing."""

import sys

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


def _wide(x):
    """30 parameters (``"auto"``: forward mode) spread over a 3,840-wide state through a 100-step
    recursion: forward mode pushes 30 tangent lanes through every wide step, reverse mode one adjoint
    pass — reverse is several times faster and a forward step is dear enough to measure."""
    v = jnp.repeat(x, 128)

    def step(y, k):
        y = jnp.tanh(y + 0.01 * v * jnp.sin(0.1 * k))
        return y, jnp.mean(y**2)

    _, costs = jax.lax.scan(step, jnp.zeros_like(v), jnp.arange(100.0))
    return jnp.sum(costs) + jnp.sum((x - 1.0) ** 2)


def _chunks(compiled):
    return [m for m in compiled if m.startswith("Compiling jit(chunk)")]


def test_measure_compiles_both_modes_and_runs_the_faster():
    opts = dict(optimizer=optax.adam(0.05), steps=20)
    x0 = jnp.zeros(30)
    measured, compiled_first, _ = _compile_messages(lambda: tune(_wide, x0, mode="measure", **opts))
    assert measured.mode == "reverse" and len(_chunks(compiled_first)) == 2  # "auto" would run forward
    # the run is the reverse-mode run, bit for bit, and neither measures nor compiles again
    reverse, compiled_reverse, _ = _compile_messages(lambda: tune(_wide, x0, mode="reverse", **opts))
    again, compiled_again, traced_again = _compile_messages(lambda: tune(_wide, x0, mode="measure", **opts))
    assert compiled_reverse == [] and compiled_again == [] and traced_again == []
    for other in (reverse, again):
        np.testing.assert_array_equal(other.params, measured.params)
        np.testing.assert_array_equal(other.history.loss, measured.history.loss)
        assert other.mode == "reverse"


def test_measure_keeps_the_auto_mode_when_its_steps_are_cheap(monkeypatch):
    """A step of a 3-parameter quadratic costs about 0.3 ms here (the chunk call), its compilation
    about 1 s: with a horizon of 100 steps (30× margin; the default 1,000 leaves 3×) the other mode
    cannot repay its compilation and is neither built nor compiled."""
    monkeypatch.setattr(sys.modules["optim.tune"], "MEASURE_HORIZON_STEPS", 100)

    def bowl(x):
        return jnp.sum((x - jnp.arange(3.0)) ** 2)

    tuners = sys.modules["optim.tune"]._TUNERS
    tuners.clear()  # a count from empty: a full cache (32 entries, earlier files in this worker) would evict
    result, compiled, _ = _compile_messages(
        lambda: tune(bowl, jnp.zeros(3), method="lbfgs", steps=30, gtol=1e-12, mode="measure")
    )
    assert result.mode == "forward" and len(_chunks(compiled)) == 1
    assert len(tuners) == 1  # nor is its tuner built
    np.testing.assert_allclose(result.params, [0.0, 1.0, 2.0], atol=1e-9)


def test_bad_mode_is_named():
    with pytest.raises(ValueError, match="mode: must be 'auto', 'forward', 'reverse' or 'measure'"):
        tune(_wide, jnp.zeros(3), mode="fastest")
