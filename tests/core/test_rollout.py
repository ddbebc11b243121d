"""The closed-loop rollout: vmap vs loop, gradients vs finite differences, multi-rate, bad input."""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.control.pid import PIDParams, pid
from jaxsim.core import metrics
from jaxsim.core.discretize import c2d_zoh
from jaxsim.core.integrators import ExponentialEuler
from jaxsim.core.rollout import ClosedLoop, Timing, fold, simulate
from jaxsim.core.signals import Sine, Step
from jaxsim.core.system import Controller, Estimator, gaussian_sensor
from jaxsim.plants.second_order import static_plant
from tests.jaxpr_loops import loop_depths

PLANT = static_plant()
TEMPLATE = pid(kp=1.0, ki=0.0, kd=0.0, tf=0.02, anti_windup="none")


def _loop(params: PIDParams, disturbance_time: float = 0.5, **kw) -> ClosedLoop:
    return ClosedLoop(
        PLANT,
        dataclasses.replace(TEMPLATE, params=params),
        reference=Step(1.0),
        disturbance=Step(0.3, disturbance_time),
        **kw,
    )


def _itae(gains: jax.Array, timing: Timing) -> jax.Array:
    p = PIDParams(kp=gains[0], ki=gains[1], kd=gains[2], tf=0.02, anti_windup="none")
    tr = simulate(_loop(p), jnp.zeros(2), timing)
    return metrics.itae(tr.t, tr.r[:, 0] - tr.y[:, 0])


def test_vmap_over_10000_gain_sets_equals_a_python_loop():
    timing = Timing(t_final=1.0, dt=1e-2)
    rng = np.random.default_rng(0)
    gains = jnp.asarray(rng.uniform([0.1, 0.0, 0.0], [3.0, 3.0, 0.2], size=(10_000, 3)))
    batched = jax.jit(jax.vmap(lambda g: _itae(g, timing)))(gains)
    single = jax.jit(lambda g: _itae(g, timing))
    idx = rng.choice(10_000, size=20, replace=False)
    looped = np.array([float(single(gains[i])) for i in idx])
    np.testing.assert_allclose(np.asarray(batched)[idx], looped, rtol=1e-13, atol=0)
    assert np.all(np.isfinite(np.asarray(batched)))


def test_gradient_of_itae_equals_central_finite_differences():
    timing = Timing(t_final=3.0, dt=1e-3, controller_period=2e-3)
    g0 = jnp.array([0.9, 1.2, 0.05])
    grad = np.asarray(jax.jit(jax.grad(lambda g: _itae(g, timing)))(g0))
    f = jax.jit(lambda g: _itae(g, timing))
    h = 1e-5
    fd = np.array([(float(f(g0.at[i].add(h))) - float(f(g0.at[i].add(-h)))) / (2 * h) for i in range(3)])
    np.testing.assert_allclose(grad, fd, rtol=1e-6)


def test_save_every_decimates_without_changing_the_simulation():
    p = PIDParams(kp=0.8, ki=0.5, kd=0.05, tf=0.02)
    full = simulate(_loop(p), jnp.zeros(2), Timing(t_final=2.0, dt=1e-3))
    dec = simulate(_loop(p), jnp.zeros(2), Timing(t_final=2.0, dt=1e-3, save_every=20))
    np.testing.assert_array_equal(np.asarray(dec.y), np.asarray(full.y)[::20])
    np.testing.assert_array_equal(np.asarray(dec.x_final), np.asarray(full.x_final))


def test_the_tick_is_traced_once_per_loop_level():
    # save_every = 1 stores every tick: one loop, not a second (zero-trip) loop that would trace,
    # transform and compile another copy of the tick
    p = PIDParams(kp=0.8, ki=0.5, kd=0.05, tf=0.02)
    run = lambda every: jax.make_jaxpr(  # noqa: E731
        lambda kp: simulate(_loop(dataclasses.replace(p, kp=kp)), jnp.zeros(2), Timing(2.0, 1e-3, save_every=every)).y
    )(0.8)
    assert loop_depths(run(1)) == [0]
    assert loop_depths(run(20)) == [0, 1]


def test_exact_lti_step_agrees_with_rk4():
    p = PIDParams(kp=0.8, ki=0.5)
    timing = Timing(t_final=2.0, dt=1e-3, controller_period=1e-2)
    # The disturbance acts from t = 0 so that the plant input is piecewise constant, as the exact
    # step assumes (RK4 would see a step at a grid point through its last stage).
    rk = simulate(_loop(p, 0.0), jnp.zeros(2), timing)
    ex = simulate(_loop(p, 0.0), jnp.zeros(2), Timing(t_final=2.0, dt=1e-2), solver=ExponentialEuler())
    # same loop: controller period 10 ms in both; the exact step integrates each 10 ms hold in one go
    np.testing.assert_allclose(ex.y, rk.y, atol=1e-9)


def test_sensor_noise_is_reproducible_and_has_the_stated_std():
    p = PIDParams(kp=0.4)
    loop = _loop(p, sensor=gaussian_sensor(0.05))
    timing = Timing(t_final=20.0, dt=1e-3)
    a = simulate(loop, jnp.zeros(2), timing, key=jax.random.PRNGKey(1))
    b = simulate(loop, jnp.zeros(2), timing, key=jax.random.PRNGKey(1))
    c = simulate(loop, jnp.zeros(2), timing, key=jax.random.PRNGKey(2))
    np.testing.assert_array_equal(np.asarray(a.y_meas), np.asarray(b.y_meas))
    assert not np.allclose(np.asarray(a.y_meas), np.asarray(c.y_meas))
    noise = np.asarray(a.y_meas - a.y)[:, 0]
    assert abs(noise.std() / 0.05 - 1.0) < 0.03  # 20,000 samples: std error ~0.5 %


def _exact_model_estimator(period_ticks_dt: float):
    """Predicts with the exact ZOH model, replaces the position by the measurement on update."""
    ad, bd = c2d_zoh(jnp.array([[0.0, 1.0], [-20.0, -12.0]]), jnp.array([[0.0], [40.0]]), period_ticks_dt)

    def init(params, y0):
        return {"x": jnp.zeros(2), "updates": jnp.asarray(0)}

    def predict(params, s, u, dt):
        return {"x": ad @ s["x"] + bd @ u, "updates": s["updates"]}

    def update(params, s, y):
        return {"x": s["x"].at[0].set(y[0]), "updates": s["updates"] + 1}

    def read(params, s):
        return s["x"][:1]

    return Estimator(None, init, predict, update, read, name="exact_predictor")


def test_multirate_sensor_and_masked_estimator_updates():
    ts = 1e-2
    sensor = gaussian_sensor(0.0, period=0.1)  # every 10 controller ticks
    loop = ClosedLoop(
        PLANT, pid(kp=0.4, ki=0.3), reference=Step(1.0), sensor=sensor, estimator=_exact_model_estimator(ts)
    )
    tr = simulate(loop, jnp.zeros(2), Timing(t_final=3.0, dt=1e-3, controller_period=ts))
    measured = np.asarray(tr.measured)
    assert measured.sum() == 30 and np.all(np.flatnonzero(measured) % 10 == 0)
    held = np.asarray(tr.y_meas)[:, 0].reshape(30, 10)
    np.testing.assert_array_equal(held, np.repeat(held[:, :1], 10, axis=1))
    # with a perfect model and no noise the estimate equals the true output at every tick
    np.testing.assert_allclose(np.asarray(tr.x_hat)[:, 0], np.asarray(tr.y)[:, 0], atol=1e-9)


def test_sine_reference_tracking_runs_under_jit_and_vmap_of_the_loop():
    loops = jax.vmap(lambda a: ClosedLoop(PLANT, TEMPLATE, reference=Sine(a, 0.5)))(jnp.array([0.5, 1.0]))
    out = jax.vmap(lambda lp: simulate(lp, jnp.zeros(2), Timing(t_final=1.0, dt=1e-2)).y)(loops)
    np.testing.assert_allclose(out[1], 2.0 * out[0], rtol=1e-12, atol=1e-15)  # linear loop


@pytest.mark.parametrize(
    "timing, match",
    [
        (
            Timing(t_final=1.0, dt=1e-3, controller_period=2.5e-3),
            "controller_period: must be an integer multiple of dt",
        ),
        (Timing(t_final=1.0, dt=-1e-3), "dt: must be positive"),
        (Timing(t_final=1.005, dt=1e-3, controller_period=1e-2), "t_final: must be an integer multiple"),
        (Timing(t_final=1.0, dt=1e-2, save_every=3), "save_every"),
    ],
)
def test_bad_timing_is_rejected(timing, match):
    with pytest.raises(ValueError, match=match):
        simulate(_loop(PIDParams(kp=1.0)), jnp.zeros(2), timing)


def test_bad_state_and_sensor_period_are_rejected():
    loop = _loop(PIDParams(kp=1.0))
    with pytest.raises(ValueError, match=r"x0: expected shape \(2,\)"):
        simulate(loop, jnp.zeros(3), Timing(t_final=1.0, dt=1e-2))
    with pytest.raises(ValueError, match="x0: must be finite"):
        simulate(loop, jnp.array([jnp.nan, 0.0]), Timing(t_final=1.0, dt=1e-2))
    bad = dataclasses.replace(loop, sensor=gaussian_sensor(0.1, period=0.015))
    with pytest.raises(ValueError, match="sensor_period"):
        simulate(bad, jnp.zeros(2), Timing(t_final=1.0, dt=1e-2))
    with pytest.raises(ValueError, match="std"):
        gaussian_sensor(-1.0)


def test_fold_equals_a_reduction_of_the_stored_trajectory():
    p = PIDParams(kp=0.8, ki=0.5, kd=0.05, tf=0.02)
    timing = Timing(t_final=2.0, dt=1e-3, controller_period=2e-3)
    tr = simulate(_loop(p), jnp.zeros(2), timing)
    want = metrics.itae(tr.t, tr.r[:, 0] - tr.y[:, 0])
    got, x_final = fold(
        _loop(p), jnp.zeros(2), timing, lambda acc, tk: acc + tk.t * jnp.abs(tk.r[0] - tk.y[0]) * timing.ts, 0.0
    )
    np.testing.assert_allclose(got, want, rtol=1e-13)
    np.testing.assert_array_equal(np.asarray(x_final), np.asarray(tr.x_final))


def test_gaussian_sensor_can_be_built_inside_jit():
    @jax.jit
    def run(std):
        loop = _loop(PIDParams(kp=0.4), sensor=gaussian_sensor(std))
        return simulate(loop, jnp.zeros(2), Timing(t_final=0.1, dt=1e-2)).y_meas

    const = jax.jit(lambda: gaussian_sensor(0.1).params)()
    np.testing.assert_allclose(const, 0.1)
    assert run(0.0).shape == (10, 1)


def _time_as_input(params, state, r, y, dt, t):
    """A controller that outputs its tick time and counts ticks (to check ``t = k·Ts``)."""
    return state + 1, jnp.reshape(t, (1,))


def test_controller_receives_the_tick_time():
    timing = Timing(t_final=0.5, dt=1e-3, controller_period=1e-2, save_every=5)
    ctrl = Controller(None, lambda p, r0, y0: jnp.asarray(0), _time_as_input, name="clock")
    tr = simulate(ClosedLoop(PLANT, ctrl), jnp.zeros(2), timing)
    np.testing.assert_array_equal(np.asarray(tr.u)[:, 0], np.asarray(tr.t))
    np.testing.assert_allclose(np.asarray(tr.t), np.arange(0, 50, 5) * 1e-2, rtol=0, atol=1e-15)


def test_a_five_argument_controller_step_is_rejected_by_name():
    old = Controller(None, lambda p, r0, y0: (), lambda p, s, r, y, dt: (s, r - y), name="old_style")
    with pytest.raises(ValueError, match=r"controller 'old_style': step must accept \(params, state, r, y, dt, t\)"):
        simulate(ClosedLoop(PLANT, old, reference=Step(1.0)), jnp.zeros(2), Timing(t_final=0.1, dt=1e-2))


def test_carry_promotion_keeps_values_and_starts_the_loop_carry_batched():
    """``_promote_like``: eager calls return the carry itself; under vmap every float leaf comes out
    batched (so the scan's batching fixed point settles in one round), integers stay as they were,
    values unchanged, and no gradient flows into the anchor; the rollout equals itself without it."""
    import jaxsim.core.rollout as rollout

    carry = {"x": jnp.arange(3.0), "k": jnp.asarray(2), "none": None}
    assert rollout._promote_like(carry, (jnp.ones(2),)) is carry
    axes = {"x": 0, "k": None, "none": None}
    for inputs in (jnp.arange(4.0), jax.random.split(jax.random.key(0), 4)):
        out = jax.vmap(lambda i: rollout._promote_like(carry, i), out_axes=axes)(inputs)
        np.testing.assert_array_equal(out["x"], np.tile(np.arange(3.0), (4, 1)))
    with pytest.raises(ValueError, match="batched"):  # the float leaf is batched: out_axes None refused
        jax.vmap(lambda i: rollout._promote_like(carry, i), out_axes=None)(jnp.arange(4.0))
    assert float(jax.grad(lambda p: jnp.sum(rollout._promote_like(carry, p)["x"]) * p)(2.0)) == 3.0

    timing = Timing(t_final=0.5, dt=1e-2)
    gains = jnp.asarray([[0.9, 1.2, 0.05], [2.0, 0.5, 0.1]])
    with_promotion = jax.jit(jax.vmap(jax.value_and_grad(lambda g: _itae(g, timing))))(gains)
    original = rollout._promote_like
    rollout._promote_like = lambda c, i: c
    try:
        without = jax.jit(jax.vmap(jax.value_and_grad(lambda g: _itae(g, timing))))(gains)
    finally:
        rollout._promote_like = original
    for a, b in zip(with_promotion, without):
        np.testing.assert_allclose(a, b, rtol=1e-13, atol=0)
