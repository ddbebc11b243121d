"""optim.lbfgs: L-BFGS whose line-search trials are the tuner's own evaluations.

Oracles: optax.lbfgs with a backtracking search (the same accepted points under the same rules),
Rosenbrock's and a constrained quadratic's known minimisers, the lowered step's loops."""

import jax
import jax.numpy as jnp
import numpy as np
import optax
import pytest

from optim.lbfgs import evaluated_an_iterate, evaluates_trial, lbfgs
from optim.tune import gradient_tuner, tune


def rosen(p):
    return (1 - p[0]) ** 2 + 100 * (p[1] - p[0] ** 2) ** 2


def _optax_iterates(opt, f, x0, n):
    """``n`` iterates of ``opt`` (an optax L-BFGS with its own line search), each with its loss."""
    vg = jax.jit(jax.value_and_grad(f))
    x, state, out = x0, opt.init(x0), []
    for _ in range(n):
        v, g = vg(x)
        out.append((float(v), np.asarray(x)))
        u, state = opt.update(g, state, x, value=v, grad=g, value_fn=f)
        x = optax.apply_updates(x, u)
    return out


def _trial_points(opt, f, x0, n):
    """``n`` evaluations of ``opt`` (one trial per update): every point with its loss and whether
    the update accepted it (the next point starts a new search)."""
    vg = jax.jit(jax.value_and_grad(f))
    x, state, out = x0, opt.init(x0), []
    for _ in range(n):
        v, g = vg(x)
        u, new = opt.update(g, state, x, value=v)
        out.append((float(v), np.asarray(x), int(new.trials) == 1))
        x, state = optax.apply_updates(x, u), new
    return out


@pytest.mark.parametrize("increase_factor", [1.0, np.inf])
def test_accepts_the_points_optax_backtracking_lbfgs_iterates_through(increase_factor):
    """restart_uphill=False: optax's rules; its iterates are our accepted trials, in order."""
    x0 = jnp.array([-1.2, 1.0])
    ref_inc = 1e300 if np.isinf(increase_factor) else increase_factor  # optax: inf·0 would be NaN
    ls = optax.scale_by_backtracking_linesearch(max_backtracking_steps=30, decrease_factor=0.5, increase_factor=ref_inc)
    ref = _optax_iterates(optax.lbfgs(linesearch=ls), rosen, x0, 7)
    ours = lbfgs(max_backtracking_steps=30, decrease_factor=0.5, increase_factor=increase_factor, restart_uphill=False)
    trials = _trial_points(ours, rosen, x0, 60)
    accepted = [(v, x) for v, x, acc in trials if acc][: len(ref)]
    assert len(accepted) == len(ref)
    for (v, x), (rv, rx) in zip(accepted, ref):
        assert v == pytest.approx(rv, rel=1e-12)
        np.testing.assert_allclose(x, rx, rtol=1e-12, atol=1e-14)
    assert len(trials) > len(ref)  # some searches cut the step: rejected trials in between


def test_restart_uphill_goes_on_where_optax_stalls():
    """With the unit step tried in every search, optax's L-BFGS exhausts a search at J ≈ 3.34 on
    Rosenbrock (an uphill direction after a pair with ⟨s, y⟩ < 0); restarting the memory there
    reaches the minimiser (1, 1)."""
    x0 = jnp.array([-1.2, 1.0])
    ls = optax.scale_by_backtracking_linesearch(max_backtracking_steps=30, decrease_factor=0.5, increase_factor=1e300)
    stalled = _optax_iterates(optax.lbfgs(linesearch=ls), rosen, x0, 9)
    assert stalled[-1][0] == pytest.approx(stalled[-2][0], rel=1e-6) and stalled[-1][0] > 3.0
    res = tune(rosen, x0, optimizer=lbfgs(), steps=120, gtol=1e-10)
    np.testing.assert_allclose(res.params, [1.0, 1.0], atol=1e-9)
    assert res.converged and res.n_evals < 100


def test_pytree_params_and_float32():
    """A dict of arrays, in float32: a separable quadratic reaches its minimiser."""
    target = {"a": jnp.array([1.0, -2.0], jnp.float32), "b": jnp.array(3.0, jnp.float32)}
    scale = {"a": jnp.array([1.0, 10.0], jnp.float32), "b": jnp.array(0.1, jnp.float32)}

    def f(p):
        return sum(jnp.sum(s * (p[k] - target[k]) ** 2) for k, s in scale.items())

    p0 = {"a": jnp.zeros(2, jnp.float32), "b": jnp.array(0.0, jnp.float32)}
    res = tune(f, p0, optimizer=lbfgs(), steps=60, gtol=1e-5)
    for k in target:
        assert res.params[k].dtype == jnp.float32
        np.testing.assert_allclose(res.params[k], target[k], atol=1e-4)


def test_a_nan_trial_is_a_rejected_trial_not_a_dead_start():
    """Rosenbrock undefined for x > 1.2: the full steps from (−1.2, 1) land there 8 times; each is
    cut like any failed trial, and the start reaches (1, 1) — a NaN loss here comes with a zero
    gradient (``where``), which must not count as convergence either."""
    f = lambda p: jnp.where(p[0] < 1.2, rosen(p), jnp.nan)  # noqa: E731
    res = tune(f, jnp.array([-1.2, 1.0]), method="lbfgs", steps=150, gtol=1e-10)
    losses = np.asarray(res.history.loss_per_start).ravel()
    assert np.sum(~np.isfinite(losses)) >= 1
    np.testing.assert_allclose(res.params, [1.0, 1.0], atol=1e-9)
    assert res.converged, res.message


def test_augmented_lagrangian_with_lbfgs_hits_the_kkt_point():
    """min (x−2)² + (y−1)² s.t. x + y ≤ 1: optimum (1, 0), multiplier 2 — a multiplier update
    between a search's anchor and its trial does not stall the search."""
    f = lambda z: (z[0] - 2) ** 2 + (z[1] - 1) ** 2  # noqa: E731
    g = lambda z: z[0] + z[1] - 1  # noqa: E731
    al = tune(
        f,
        jnp.zeros(2),
        method="lbfgs",
        steps=300,
        constraints=g,
        constraint_method="augmented_lagrangian",
        penalty_weight=100.0,
        multiplier_every=10,
    )
    np.testing.assert_allclose(al.params, [1.0, 0.0], atol=1e-6)
    assert al.constraint_violation <= 1e-6
    np.testing.assert_allclose(al.multipliers, [2.0], rtol=1e-4)


def _copies_of_the_loss(optimizer, loss, x0):
    """How many times the lowered tuner step holds the loss's one ``tanh``."""
    tuner = gradient_tuner(loss, optimizer, params0=x0, mode="forward")
    state = tuner.init(key=jax.random.PRNGKey(0))
    return tuner.step.lower(state).as_text().count("stablehlo.tanh")


def test_the_step_holds_one_copy_of_the_loss():
    """A loss whose scan holds one ``tanh``: Adam's step and ours hold it once (the forward-mode
    gradient's rollout carries the value); optax's backtracking L-BFGS holds a second, primal copy
    for its line search."""

    def loss(x):
        def tick(s, _):
            return 0.9 * s + 0.1 * jnp.tanh(x), None

        s, _ = jax.lax.scan(tick, jnp.zeros_like(x), None, length=50)
        return jnp.sum((s - 0.5) ** 2)

    x0 = jnp.array([0.1, 0.2])
    adam = _copies_of_the_loss(optax.adam(0.1), loss, x0)
    ours = _copies_of_the_loss(lbfgs(), loss, x0)
    optax_ls = _copies_of_the_loss(optax.lbfgs(linesearch=optax.scale_by_backtracking_linesearch(20)), loss, x0)
    assert adam == ours == 1 and optax_ls == 2


def test_a_rejected_trial_with_a_zero_gradient_does_not_stop_the_start():
    """The second direction (curvature 0.02 from the first pair) jumps to u = 10, on a plateau where
    the loss is higher and flat: a rejected trial, zero gradient.  The start goes on, cutting the
    step, to the edge of the valley (u → 5⁻, loss → 0.25); stopping there on ``gnorm ≤ gtol`` left
    it at the first accepted point, loss 0.9604."""

    def loss(u):
        return jnp.where(u[0] < 5.0, 0.01 * (u[0] - 10.0) ** 2, 1.0)

    res = tune(loss, jnp.zeros(1), optimizer=lbfgs(), steps=40, gtol=1e-12, mode="forward")
    assert 0.25 <= res.loss < 0.26 and 4.9 < float(res.params[0]) < 5.0
    assert res.history.grad_norm[2] == 0.0 and res.history.loss[2] == 1.0  # the plateau trial, evaluated
    assert not res.converged and "ran out of steps" in res.message


def test_evaluated_an_iterate_tells_accepted_points_from_rejected_trials():
    opt = lbfgs()
    state = opt.init(jnp.zeros(1))
    assert bool(evaluated_an_iterate(optax.adam(0.1).init(jnp.zeros(1))))
    _, state = opt.update(jnp.ones(1), state, jnp.zeros(1), value=jnp.asarray(2.0))  # the start
    assert bool(evaluated_an_iterate(state))
    _, rejected = opt.update(jnp.ones(1), state, -jnp.ones(1), value=jnp.asarray(3.0))  # uphill
    _, accepted = opt.update(jnp.ones(1), state, -jnp.ones(1), value=jnp.asarray(1.0))
    assert not bool(evaluated_an_iterate(rejected)) and bool(evaluated_an_iterate(accepted))


def test_evaluates_trial_and_bad_arguments():
    opt = lbfgs()
    state = opt.init(jnp.zeros(2))
    assert not bool(evaluates_trial(state)) and not bool(evaluates_trial(optax.adam(0.1).init(jnp.zeros(2))))
    _, state = opt.update(jnp.ones(2), state, jnp.zeros(2), value=jnp.asarray(2.0))
    assert bool(evaluates_trial(state))
    for name, bad in [
        ("memory_size", 0),
        ("max_backtracking_steps", -1),
        ("decrease_factor", 1.0),
        ("decrease_factor", "half"),
        ("increase_factor", 0.5),
        ("max_learning_rate", np.inf),
        ("slope_rtol", 0.0),
    ]:
        with pytest.raises(ValueError, match=name):
            lbfgs(**{name: bad})
