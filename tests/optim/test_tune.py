"""Gradient tuner: known optima (quadratic, constrained toy, bounded Rosenbrock), accounting, bad input."""

import jax
import jax.numpy as jnp
import numpy as np
import optax
import pytest

from optim.reparam import Interval, Positive
from optim.robust import mean, robust_loss, worst_case
from optim.tune import FORWARD_MODE_MAX_PARAMS, tune

C = jnp.array([1.0, -2.0, 3.0])
A = jnp.array([[3.0, 1.0, 0.0], [1.0, 2.0, 0.5], [0.0, 0.5, 1.0]])


def quadratic(p):
    d = p["a"] - C
    return 0.5 * d @ A @ d + jnp.sum((p["b"] - 2.0) ** 2)


@pytest.fixture(scope="module")
def quad_runs():
    p0 = {"a": jnp.zeros(3), "b": jnp.ones((2, 2))}
    return {m: tune(quadratic, p0, optimizer=optax.adam(0.1), steps=400, mode=m) for m in ("forward", "reverse")}


def test_quadratic_reaches_the_known_minimiser_in_both_modes(quad_runs):
    for res in quad_runs.values():
        np.testing.assert_allclose(res.params["a"], C, atol=1e-6)
        np.testing.assert_allclose(res.params["b"], 2.0, atol=1e-6)
        assert res.loss < 1e-10 and res.start_index == 0
    f, r = quad_runs["forward"], quad_runs["reverse"]
    assert (f.mode, r.mode) == ("forward", "reverse")
    # same gradients → the same trajectory step for step.  Near the minimiser the gradient A(a − C) is
    # a difference of O(1) numbers: an iterate one ulp apart (4.4e-16 at |a| = 3, the two modes are
    # compiled apart and may round differently) moves it by up to ‖A‖·ulp ≈ 2e-15 — its floor.
    np.testing.assert_allclose(f.history.loss, r.history.loss, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(f.history.grad_norm, r.history.grad_norm, rtol=1e-9, atol=8 * 4.4e-16)
    np.testing.assert_allclose(f.params["a"], r.params["a"], rtol=0, atol=4 * 4.4e-16)


def test_history_accounting(quad_runs):
    res = quad_runs["reverse"]
    h = res.history
    assert res.n_steps == 400 and h.loss.shape == (400,) and h.loss_per_start.shape == (400, 1)
    # one gradient evaluation per step, worth grad_cost loss evaluations
    assert res.n_evals == 400 and res.grad_cost >= 1.0
    np.testing.assert_allclose(h.sims, res.grad_cost * np.arange(1, 401), rtol=1e-12)
    assert res.n_sims == round(400 * res.grad_cost) and np.all(np.diff(h.wall_s) >= 0) and res.wall_s >= h.wall_s[-1]
    assert np.all(np.diff(h.best_loss) <= 0)
    # grad norm at the first point equals the analytic gradient norm at params0
    g_a = A @ (jnp.zeros(3) - C)
    g_b = 2 * (jnp.ones((2, 2)) - 2.0)
    assert h.grad_norm[0] == pytest.approx(float(jnp.sqrt(g_a @ g_a + jnp.sum(g_b**2))), rel=1e-12)


def test_auto_mode_follows_the_parameter_count():
    loss = lambda x: jnp.sum((x - 1.0) ** 2)  # noqa: E731
    small = tune(loss, jnp.zeros(FORWARD_MODE_MAX_PARAMS), steps=2)
    large = tune(loss, jnp.zeros(FORWARD_MODE_MAX_PARAMS + 1), steps=2)
    assert (small.mode, large.mode) == ("forward", "reverse")


def test_constrained_toy_augmented_lagrangian_hits_the_kkt_point():
    """min (x−2)² + (y−1)²  s.t. x + y ≤ 1: optimum (1, 0), multiplier 2."""
    f = lambda z: (z[0] - 2) ** 2 + (z[1] - 1) ** 2  # noqa: E731
    g = lambda z: z[0] + z[1] - 1  # noqa: E731
    opt = optax.adam(optax.exponential_decay(0.05, 500, 0.1))
    al = tune(
        f,
        jnp.zeros(2),
        optimizer=opt,
        steps=1500,
        constraints=g,
        constraint_method="augmented_lagrangian",
        penalty_weight=100.0,
    )
    np.testing.assert_allclose(al.params, [1.0, 0.0], atol=2e-6)
    assert al.loss == pytest.approx(2.0, abs=1e-5)
    assert al.constraint_violation <= 1e-6
    np.testing.assert_allclose(al.multipliers, [2.0], rtol=1e-3)
    # the quadratic penalty stops at its own minimiser: violation s = 2/(1 + w), closed form
    w = 100.0
    pen = tune(f, jnp.zeros(2), optimizer=opt, steps=1500, constraints=g, penalty_weight=w)
    s = 2 / (1 + w)
    np.testing.assert_allclose(pen.params, [2 - w * s / 2, 1 - w * s / 2], atol=1e-6)
    assert pen.constraint_violation == pytest.approx(s, rel=1e-4)


def test_bounded_rosenbrock_with_lbfgs_and_positive_reparam():
    rosen = lambda p: (1 - p[0]) ** 2 + 100 * (p[1] - p[0] ** 2) ** 2  # noqa: E731
    res = tune(rosen, jnp.array([0.3, 2.0]), optimizer=optax.lbfgs(), steps=200, reparam=Positive(), gtol=1e-12)
    np.testing.assert_allclose(res.params, [1.0, 1.0], atol=1e-7)
    assert res.n_evals > res.n_steps  # line-search trials are counted
    # optax.lbfgs's default zoom line search evaluates the gradient at every trial
    assert res.n_sims == round(res.n_evals * res.grad_cost)


def test_multistart_finds_the_global_minimum_of_a_double_well():
    # minima near x = −1.04 (global) and x = +0.96 (local); a single start at 1.2 stays local
    well = lambda x: (x[0] ** 2 - 1) ** 2 + 0.3 * x[0]  # noqa: E731
    one = tune(well, jnp.array([1.2]), optimizer=optax.adam(0.05), steps=300)
    many = tune(
        well,
        jnp.array([1.2]),
        optimizer=optax.adam(0.05),
        steps=300,
        n_starts=8,
        key=jax.random.PRNGKey(3),
        init_spread=1.5,
        sims_per_eval=5,
    )
    roots = np.roots([4, 0, -4, 0.3])  # stationary points: 4x³ − 4x + 0.3 = 0
    x_glob, x_loc = roots.real.min(), roots.real.max()
    assert float(one.params[0]) == pytest.approx(x_loc, abs=1e-4)
    assert float(many.params[0]) == pytest.approx(x_glob, abs=1e-4)
    assert many.start_index != 0
    assert many.history.loss_per_start.shape == (300, 8)
    assert many.n_evals == 300 * 8 * 5 and many.n_sims == round(300 * 8 * 5 * many.grad_cost)


def test_early_stopping_and_callback():
    loss = lambda x: jnp.sum((x - 3.0) ** 2)  # noqa: E731
    res = tune(loss, jnp.zeros(2), optimizer=optax.sgd(0.4), steps=500, patience=5, rtol=1e-6)
    assert res.n_steps < 500 and "early stop" in res.message
    np.testing.assert_allclose(res.params, 3.0, atol=1e-3)
    seen = []

    def cb(step, params, value):
        seen.append((step, float(value)))
        return step == 4

    res = tune(loss, jnp.zeros(2), optimizer=optax.sgd(0.1), steps=100, callback=cb, steps_per_call=1)
    assert res.n_steps == 5 and "callback at step 4" in res.message
    assert [s for s, _ in seen] == [0, 1, 2, 3, 4]
    assert seen[0][1] == pytest.approx(18.0)
    # chunked: the callback still sees every step in order; its stop takes effect at the chunk's end
    seen.clear()
    res = tune(loss, jnp.zeros(2), optimizer=optax.sgd(0.1), steps=100, callback=cb, steps_per_call=8)
    assert res.n_steps == 8 and "callback at step 4" in res.message
    assert [s for s, _ in seen] == [0, 1, 2, 3, 4]
    # sgd(0.1) on (x − 3)²: x_k = 3(1 − 0.8^k), the loss seen at step k is 2·9·0.64^k
    np.testing.assert_allclose([v for _, v in seen], 18.0 * 0.64 ** np.arange(5), rtol=1e-12)


def test_nan_loss_stops_and_keeps_the_best_finite_point():
    # walking from 0 toward the minimum at 5; the loss is NaN beyond x = 3
    loss = lambda x: jnp.where(x[0] > 3.0, jnp.nan, (x[0] - 5.0) ** 2)  # noqa: E731
    res = tune(loss, jnp.zeros(1), optimizer=optax.sgd(0.1), steps=100)
    assert res.n_steps < 100
    assert "non-finite" in res.message and "kept the best finite point" in res.message
    assert np.isfinite(res.loss) and float(res.params[0]) <= 3.0
    assert res.loss == pytest.approx((float(res.params[0]) - 5) ** 2)
    # the last finite iterate is the best one: x_k = 5(1 − 0.8^k) while ≤ 3
    k = int(np.floor(np.log(0.4) / np.log(0.8)))
    assert float(res.params[0]) == pytest.approx(5 * (1 - 0.8**k), rel=1e-12)
    with pytest.raises(ValueError, match="loss"):
        tune(lambda x: jnp.nan * x[0], jnp.zeros(1), steps=3)


def test_bad_input_names_the_argument():
    loss = lambda x: jnp.sum(x**2)  # noqa: E731
    with pytest.raises(ValueError, match="params0"):
        tune(loss, jnp.array([0.5, 2.0]), reparam=Interval(0.0, 1.0))
    with pytest.raises(ValueError, match="lo/hi"):
        tune(loss, jnp.array([0.5]), reparam=Interval(1.0, 0.0))
    with pytest.raises(ValueError, match="params0"):
        tune(loss, jnp.array([jnp.nan]))
    with pytest.raises(ValueError, match="steps"):
        tune(loss, jnp.ones(1), steps=0)
    with pytest.raises(ValueError, match="mode"):
        tune(loss, jnp.ones(1), mode="sideways")
    with pytest.raises(ValueError, match="constraint_method"):
        tune(loss, jnp.ones(1), constraints=lambda x: x, constraint_method="barrier")
    with pytest.raises(ValueError, match="penalty_weight"):
        tune(loss, jnp.ones(1), penalty_weight=0.0)
    with pytest.raises(ValueError, match="optimizer"):
        tune(loss, jnp.ones(1), optimizer="adam")


def test_robust_objectives_reach_their_known_minimisers():
    s = jnp.array([0.0, 1.0, 2.0, 7.0])
    per_sample = lambda x, si: (x[0] - si) ** 2  # noqa: E731
    opt = optax.adam(optax.exponential_decay(0.2, 400, 0.05))
    res_mean = tune(robust_loss(per_sample, s, mean), jnp.zeros(1), optimizer=opt, steps=800, sims_per_eval=4)
    assert float(res_mean.params[0]) == pytest.approx(2.5, abs=1e-6)  # the sample mean
    assert res_mean.n_evals == 800 * 4
    res_worst = tune(robust_loss(per_sample, s, worst_case), jnp.zeros(1), optimizer=opt, steps=800)
    assert float(res_worst.params[0]) == pytest.approx(3.5, abs=2e-3)  # the midrange


def test_each_run_compiles_its_step_once():
    """Stable carry types: the jitted step must not recompile after the first step (it did once,
    when a weak-typed optimiser-state leaf turned strong; that cost seconds per run)."""
    from optim.pso import pso
    from tests.jax_log import jax_messages

    f = lambda x: jnp.sum((x - 1.0) ** 2)  # noqa: E731
    with jax_messages() as messages:
        tune(f, jnp.zeros(2), optimizer=optax.lbfgs(), steps=6, n_starts=2)
        pso(f, -np.ones(2), np.ones(2), n_particles=8, n_iters=30)
    names = ("Compiling jit(chunk)", "Compiling jit(_jitted_steps)")
    compiles = [m for m in messages if m.startswith(names)]
    assert len(compiles) == 2, compiles
