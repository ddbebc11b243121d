"""Running costs inside ``fold`` against the trajectory metrics of ``simulate`` on the same loop, the
online softmax surrogates against their stored-trajectory versions, and ``combine``'s bookkeeping."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.control.pid import pid
from jaxsim.core import costs, metrics
from jaxsim.core.rollout import ClosedLoop, Timing, simulate
from jaxsim.core.signals import Step
from jaxsim.plants.second_order import static_plant

TIMING = Timing(t_final=1.5, dt=5e-3, controller_period=1e-2)


def _loop(kp=3.0, ki=2.0, reference=Step(1.0), u_max=jnp.inf):  # noqa: B008  (an immutable default)
    return ClosedLoop(static_plant(), pid(kp=kp, ki=ki, u_max=u_max, u_min=-u_max), reference=reference)


@pytest.fixture(scope="module")
def run():
    loop = _loop()
    tr = simulate(loop, jnp.zeros(2), TIMING)
    return loop, tr


def test_running_integrals_equal_the_trajectory_metrics(run):
    loop, tr = run
    objective = costs.combine(iae=costs.iae(), ise=costs.ise(), itae=costs.itae(), energy=costs.control_energy())
    got = costs.rollout_cost(objective, loop, jnp.zeros(2), TIMING).terms
    e = tr.r[:, 0] - tr.y[:, 0]
    expected = {
        "iae": metrics.iae(tr.t, e),
        "ise": metrics.ise(tr.t, e),
        "itae": metrics.itae(tr.t, e),
        "energy": metrics.control_energy(tr.t, tr.u),
    }
    for name, value in expected.items():
        assert float(got[name]) == pytest.approx(float(value), rel=1e-12), name
    # and a hand-written sum, independent of the shared integrands
    t, ts = np.asarray(tr.t), TIMING.ts
    assert float(got["itae"]) == pytest.approx(np.sum(t * np.abs(np.asarray(e))) * ts, rel=1e-12)


def test_online_soft_overshoot_and_settling_equal_the_stored_versions(run):
    loop, tr = run
    objective = costs.combine(os=costs.soft_overshoot(0.5), ts=costs.soft_settling_time(0.02, 0.002, 0.02))
    got = costs.rollout_cost(objective, loop, jnp.zeros(2), TIMING).terms
    y = tr.y[:, 0]
    assert float(got["os"]) == pytest.approx(float(metrics.soft_overshoot(y, 1.0, 0.5)), rel=1e-12)
    assert float(got["ts"]) == pytest.approx(float(metrics.soft_settling_time(tr.t, y, 1.0)), rel=1e-12)
    # the loop overshoots: the surrogate is within a few temperatures of the exact value
    exact = float(metrics.step_info(tr.t, y, 1.0).overshoot)
    assert exact > 5.0 and exact - 3 * 0.5 <= float(got["os"]) <= exact + 1e-9


def test_online_surrogates_have_finite_gradients():
    def f(kp):
        obj = costs.combine(os=costs.soft_overshoot(0.5), ts=costs.soft_settling_time())
        return costs.rollout_cost(obj, _loop(kp=kp), jnp.zeros(2), TIMING).total

    g = jax.grad(f)(3.0)
    assert np.isfinite(float(g)) and float(g) != 0.0


def test_saturation_excess_clock_and_terminal_on_handmade_ticks():
    u = jnp.asarray([[0.5, -3.0], [2.5, 0.0], [-1.0, 4.0]])
    t = jnp.asarray([0.0, 0.1, 0.2])
    r = jnp.asarray([[1.0, 0.0]] * 3)
    y = jnp.asarray([[0.2, 0.1], [0.6, -0.3], [0.9, 0.2]])
    ticks = costs.Tick(t=t, x=y, y=y, y_meas=y, measured=jnp.ones(3, bool), u=u, r=r, d=jnp.zeros((3, 1)), x_hat=None)
    ts = 0.1
    sat = costs.accumulate(costs.saturation_excess(2.0), ticks, ts)
    assert float(sat) == pytest.approx((1.0**2 + 0.5**2 + 2.0**2) * ts, rel=1e-14)
    assert float(costs.accumulate(costs.saturation_excess(2.0, channels=1), ticks, ts)) == pytest.approx(
        (1.0**2 + 2.0**2) * ts, rel=1e-14
    )
    clock = costs.itae(clock=lambda tt: jnp.asarray([1.0, 2.0]) + tt)
    e = np.asarray(r - y)
    w = np.asarray(t)[:, None] + np.array([1.0, 2.0])
    assert float(costs.accumulate(clock, ticks, ts)) == pytest.approx(np.sum(w * np.abs(e)) * ts, rel=1e-14)
    last = costs.accumulate(costs.terminal(lambda tk: tk.y[0] ** 2), ticks, ts)
    assert float(last) == pytest.approx(0.81, rel=1e-14)
    energy = costs.accumulate(costs.control_energy(offset=jnp.asarray([0.5, 0.0]), channels=None), ticks, ts)
    assert float(energy) == pytest.approx(np.sum((np.asarray(u) - [0.5, 0.0]) ** 2) * ts, rel=1e-14)
    pen = costs.accumulate(costs.penalty(lambda tk: jnp.abs(tk.y) - 0.5, weight=10.0), ticks, ts)
    assert float(pen) == pytest.approx(10.0 * (0.1**2 + 0.4**2) * ts, rel=1e-12)


def test_combine_weights_terms_and_rate_sums_to_the_total(run):
    loop, tr = run
    obj = costs.combine(itae=costs.itae(), energy=(1e-2, costs.control_energy()))
    b = costs.rollout_cost(obj, loop, jnp.zeros(2), TIMING)
    assert float(b.total) == pytest.approx(float(b.terms["itae"] + 1e-2 * b.terms["energy"]), rel=1e-14)
    ticks = costs.Tick(*tr[:-1])
    rates = jax.vmap(lambda tick: obj.rate(tick, TIMING.ts))(ticks)
    assert float(jnp.sum(rates)) == pytest.approx(float(b.total), rel=1e-12)
    assert costs.combine(a=costs.itae(), b=costs.soft_overshoot()).rate is None
    nested = costs.combine(inner=(2.0, obj), extra=costs.iae())
    nb = costs.rollout_cost(nested, loop, jnp.zeros(2), TIMING)
    assert float(nb.terms["inner"]) == pytest.approx(float(b.total), rel=1e-14)


def test_combine_rejects_bad_terms():
    with pytest.raises(ValueError, match="at least one term"):
        costs.combine()
    with pytest.raises(ValueError, match="energy: expected a RunningCost"):
        costs.combine(energy=lambda tick: 0.0)
    with pytest.raises(ValueError, match="itae: the weight must be finite"):
        costs.combine(itae=(float("nan"), costs.itae()))
    with pytest.raises(ValueError, match="a tuple of 3"):
        costs.combine(itae=(1.0, costs.itae(), 2.0))


def test_channels_select_outputs_of_a_two_channel_error():
    ticks = costs.Tick(
        t=jnp.asarray([0.0, 0.5]),
        x=None,
        y=jnp.asarray([[1.0, 2.0], [0.0, 1.0]]),
        y_meas=None,
        measured=None,
        u=jnp.zeros((2, 1)),
        r=jnp.asarray([[0.0, 0.0], [0.0, 0.0]]),
        d=None,
        x_hat=None,
    )
    assert float(costs.accumulate(costs.iae(channels=1), ticks, 0.5)) == pytest.approx(1.5, rel=1e-15)
    assert float(costs.accumulate(costs.ise(channels=[0]), ticks, 0.5)) == pytest.approx(0.5, rel=1e-15)
