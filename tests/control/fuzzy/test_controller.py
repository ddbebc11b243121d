"""Fuzzy PID channels in the closed loop: linear channels reproduce the PID exactly; gradients of
a rollout cost w.r.t. the breakpoints equal central differences; bad input."""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.control import fuzzy as fz
from jaxsim.control.pid import pid
from jaxsim.core.rollout import ClosedLoop, Timing, fold, simulate
from jaxsim.core.signals import Ramp, Step, Sum
from jaxsim.plants.second_order import astatic_plant, static_plant

TIMING = Timing(t_final=3.0, dt=2e-3)


@pytest.mark.parametrize(
    "gains",
    [dict(kp=0.7), dict(kp=0.7, ki=1.6), dict(kp=0.7, kd=0.05, tf=0.02), dict(kp=0.9, ki=1.2, kd=0.04, tf=0.03)],
)
def test_linear_channels_reproduce_the_pid(gains):
    lin = lambda k: fz.linear(k) if k else None  # noqa: E731
    fuzzy = fz.fuzzy_pid(
        p=lin(gains.get("kp")),
        i=lin(gains.get("ki")),
        d=lin(gains.get("kd")),
        tf=gains.get("tf", 0.0),
        anti_windup="none",
    )
    ref = pid(anti_windup="none", **gains)
    refs = Sum((Step(1.0), Ramp(0.2)))
    run = jax.jit(
        lambda c: simulate(ClosedLoop(static_plant(), c, reference=refs, disturbance=Step(0.3)), jnp.zeros(2), TIMING).y
    )
    np.testing.assert_allclose(run(fuzzy), run(ref), rtol=0, atol=1e-12)


def test_saturation_and_clamping_match_the_pid():
    fuzzy = fz.fuzzy_pid(p=fz.linear(2.0), i=fz.linear(3.0), u_min=-0.5, u_max=0.8)
    ref = pid(kp=2.0, ki=3.0, u_min=-0.5, u_max=0.8, anti_windup="clamping")
    run = jax.jit(
        lambda c: (
            simulate(ClosedLoop(astatic_plant(), c, reference=Step(1.0), disturbance=Step(0.6)), jnp.zeros(2), TIMING).u
        )
    )
    np.testing.assert_allclose(run(fuzzy), run(ref), rtol=0, atol=1e-12)


def test_fuzzy_output_never_exceeds_the_saturation_level():
    fc = fz.three_section(0.75, 0.3, 1.2, 1.0)
    tr = jax.jit(lambda c: simulate(ClosedLoop(static_plant(), c, reference=Step(3.0)), jnp.zeros(2), TIMING))(
        fz.fuzzy_pid(p=fc)
    )
    assert float(jnp.max(jnp.abs(tr.u))) == pytest.approx(1.0, abs=1e-15)  # e(0) = 3 > c: u = d


@pytest.mark.parametrize("form", ["exact", "smooth"])
def test_rollout_cost_gradient_wrt_breakpoints_equals_central_differences(form):
    def itae(params):
        a, b, c, d = params
        ctrl = fz.fuzzy_pid(p=fz.ThreeSection(a, b, c, d, 0.02, form))
        loop = ClosedLoop(static_plant(), ctrl, reference=Step(1.0), disturbance=Step(0.3))
        cost = lambda acc, tick: acc + tick.t * jnp.abs(tick.r[0] - tick.y[0]) * TIMING.ts  # noqa: E731
        return fold(loop, jnp.zeros(2), TIMING, cost, jnp.zeros(()))[0]

    p0 = jnp.asarray([0.75, 0.3, 1.2, 1.0])
    grad = jax.jit(jax.grad(itae))(p0)
    f = jax.jit(itae)
    h = 1e-6
    fd = np.array([(f(p0.at[j].add(h)) - f(p0.at[j].add(-h))) / (2 * h) for j in range(4)])
    np.testing.assert_allclose(grad, fd, rtol=1e-4, atol=1e-7)
    assert np.all(np.abs(fd) > 1e-4)  # every breakpoint matters in this scenario


def test_controller_bad_input():
    with pytest.raises(ValueError, match="p/i/d"):
        fz.fuzzy_pid()
    with pytest.raises(ValueError, match="^i:"):
        fz.fuzzy_pid(p=fz.linear(1.0), i=2.0)
    with pytest.raises(ValueError, match="tf"):
        fz.fuzzy_pid(p=fz.linear(1.0), tf=-0.1)
    with pytest.raises(ValueError, match="u_min/u_max"):
        fz.fuzzy_pid(p=fz.linear(1.0), u_min=1.0, u_max=0.0)
    with pytest.raises(ValueError, match="anti_windup"):
        fz.fuzzy_pid(p=fz.linear(1.0), anti_windup="back_calculation")
    # replacing the parameters keeps the structure (what a tuner does)
    c = fz.fuzzy_pid(p=fz.three_section(0.75, 0.3, 1.2, 1.0))
    c2 = dataclasses.replace(c, params=dataclasses.replace(c.params, p=fz.three_section(0.5, 0.3, 1.2, 1.0)))
    assert float(c2.params.p.k1) == pytest.approx(0.6)
