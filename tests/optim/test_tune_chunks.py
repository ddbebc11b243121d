"""The chunked tuner: same trajectory whatever the chunk length, compiled once across calls,
``mode="auto"`` over parameters × starts, L-BFGS by name, honest accounting."""

import jax
import jax.numpy as jnp
import numpy as np
import optax
import pytest

from optim.compile_cache import fingerprint, key_or_none
from optim.tune import FORWARD_MODE_MAX_PARAMS, tune, use_forward_mode
from tests.jax_log import jax_messages


def _well(x):
    return jnp.sum((x**2 - 1.0) ** 2 + 0.3 * x)


@pytest.mark.parametrize("method", ["adam", "lbfgs"])
def test_chunked_run_equals_one_step_per_call(method):
    """Patience stops the starts at different steps, inside a chunk: records, kept point and
    accounting must be those of one step per call."""
    opts = dict(steps=300, n_starts=3, key=jax.random.PRNGKey(2), init_spread=1.0, grad_cost=3.0)
    if method == "adam":
        opts.update(optimizer=optax.adam(0.1), patience=5, rtol=1e-4)
    else:
        opts.update(method="lbfgs", gtol=1e-6, patience=5, rtol=1e-12)
    one = tune(_well, jnp.array([0.5, -0.2]), steps_per_call=1, **opts)
    for chunk in (7, 64):
        many = tune(_well, jnp.array([0.5, -0.2]), steps_per_call=chunk, **opts)
        assert many.n_steps == one.n_steps < 300 and many.message == one.message
        for name in ("best_loss", "sims", "loss", "grad_norm", "loss_per_start", "grad_norm_per_start"):
            np.testing.assert_array_equal(getattr(many.history, name), getattr(one.history, name), err_msg=name)
        np.testing.assert_array_equal(many.params, one.params)
        assert (many.loss, many.start_index, many.n_sims, many.n_evals) == (
            one.loss,
            one.start_index,
            one.n_sims,
            one.n_evals,
        )


def _compile_messages(run):
    with jax_messages() as messages:
        out = run()
    compiled = [m for m in messages if m.startswith("Compiling")]
    return out, compiled, [m for m in messages if m.startswith("Finished tracing")]


def test_a_second_call_traces_and_compiles_nothing():
    traces = []

    def loss(x):
        traces.append(1)  # runs only while JAX traces the loss
        return jnp.sum((x - 2.0) ** 2)

    def run():
        # a fresh optimiser object with the same settings, as a caller writes it every time
        return tune(loss, jnp.zeros(3), optimizer=optax.adam(0.1), steps=40, n_starts=2)

    first, compiled_first, _ = _compile_messages(run)
    n_traces = len(traces)
    assert n_traces > 0 and compiled_first
    second, compiled_second, traced_second = _compile_messages(run)
    # nothing traced at all, not even the parameters' shapes (the reparametrisation's inverse)
    assert len(traces) == n_traces and compiled_second == [] and traced_second == []
    assert second.compile_s < first.compile_s
    np.testing.assert_array_equal(second.params, first.params)
    # other optimiser settings: a new compilation
    _, compiled_other, _ = _compile_messages(lambda: tune(loss, jnp.zeros(3), optimizer=optax.adam(0.2), steps=5))
    assert len(traces) > n_traces and compiled_other


def test_a_cold_call_compiles_three_programs_and_the_default_key_is_prngkey_0():
    from optim.tune import _default_key

    np.testing.assert_array_equal(np.asarray(_default_key()), np.asarray(jax.random.PRNGKey(0)))
    params0 = jnp.array([0.3, -0.4])  # made before: its own transfer is not the tuner's

    def loss(x):  # a new function: nothing cached for it
        return jnp.sum((x - 1.0) ** 2 + 0.1 * x**4)

    _, compiled, _ = _compile_messages(lambda: tune(loss, params0, method="lbfgs", steps=20))
    names = sorted(m.split(" with ")[0].removeprefix("Compiling ") for m in compiled)
    # the starting point, the chunk of steps, the kept point back to parameters: no eager op
    assert names == ["jit(<lambda>)", "jit(chunk)", "jit(init_from_x)"], names


def test_fingerprint_keys_settings_not_objects():
    assert fingerprint(optax.adam(0.05)) == fingerprint(optax.adam(0.05))
    assert fingerprint(optax.adam(0.05)) != fingerprint(optax.adam(0.1))
    assert fingerprint(optax.lbfgs()) == fingerprint(optax.lbfgs())
    assert fingerprint(np.arange(3.0)) != fingerprint(np.arange(3.0) + 1e-12)
    a, b = 1.0, 2.0
    assert fingerprint(lambda x: x + a) != fingerprint(lambda x: x + b)
    assert key_or_none({"x": {1, 2}}) is None  # an unhashable leaf (a set): not cached
    assert key_or_none({"x": [1, 2]}) == key_or_none({"x": [1, 2]}) != key_or_none({"x": [1, 3]})


def test_auto_mode_weighs_parameters_times_starts():
    assert use_forward_mode(3, 1) and use_forward_mode(3, 8) and not use_forward_mode(3, 32)
    assert use_forward_mode(FORWARD_MODE_MAX_PARAMS, 1) and not use_forward_mode(FORWARD_MODE_MAX_PARAMS + 1, 1)
    loss = lambda x: jnp.sum((x - 1.0) ** 2)  # noqa: E731
    few = tune(loss, jnp.zeros(3), steps=2, n_starts=8, grad_cost=1.0)
    many = tune(loss, jnp.zeros(3), steps=2, n_starts=16, grad_cost=1.0)
    assert (few.mode, many.mode) == ("forward", "reverse")


def test_lbfgs_by_name_and_its_accounting():
    rosen = lambda p: (1 - p[0]) ** 2 + 100 * (p[1] - p[0] ** 2) ** 2  # noqa: E731
    res = tune(rosen, jnp.array([-1.2, 1.0]), method="lbfgs", steps=200, gtol=1e-10, grad_cost=4.0)
    np.testing.assert_allclose(res.params, [1.0, 1.0], atol=1e-8)
    assert res.converged and res.n_steps < 100
    # optim.lbfgs: every step is one line-search trial, evaluated with its gradient (4 loss evaluations)
    assert res.n_evals == res.n_steps and res.n_sims == 4 * res.n_steps
    # optax's backtracking search: a gradient evaluation per step, a trial is one loss evaluation
    optax_ls = optax.lbfgs(linesearch=optax.scale_by_backtracking_linesearch(30, decrease_factor=0.5))
    res = tune(rosen, jnp.array([-1.2, 1.0]), optimizer=optax_ls, steps=20, grad_cost=4.0)
    trials = res.n_evals - res.n_steps
    assert trials > 0 and res.n_sims == 4 * res.n_steps + trials
    with pytest.raises(ValueError, match="method"):
        tune(rosen, jnp.zeros(2), method="lbfgs", optimizer=optax.adam(0.1))
    with pytest.raises(ValueError, match="method"):
        tune(rosen, jnp.zeros(2), method="newton")
    with pytest.raises(ValueError, match="grad_cost"):
        tune(rosen, jnp.zeros(2), grad_cost=0.0)
    with pytest.raises(ValueError, match="grad_cost: must be None, 'measure' or a positive number"):
        tune(rosen, jnp.zeros(2), grad_cost="measured")
    with pytest.raises(ValueError, match="steps_per_call"):
        tune(rosen, jnp.zeros(2), steps_per_call=0)


@pytest.mark.parametrize("method", ["adam", "lbfgs"])
def test_a_single_start_steps_unbatched_like_a_batched_start(method):
    """One start runs its step without ``vmap``; two identical starts (spread 0) run it vmapped:
    the iterates agree to rounding."""

    def loss(x):
        def tick(s, _):
            return 0.95 * s + 0.05 * jnp.tanh(x[:2] * s + x[2]), None

        s, _ = jax.lax.scan(tick, jnp.ones(2), None, length=40)
        return jnp.sum((s - 0.3) ** 2) + 0.01 * jnp.sum(x**2)

    x0 = jnp.array([0.5, -0.2, 0.1])
    one = tune(loss, x0, method=method, steps=25)
    two = tune(loss, x0, method=method, steps=25, n_starts=2, init_spread=0.0)
    np.testing.assert_allclose(one.history.loss, two.history.loss_per_start[:, 0], rtol=1e-12)
    np.testing.assert_allclose(one.params, two.params, rtol=1e-10, atol=1e-14)
