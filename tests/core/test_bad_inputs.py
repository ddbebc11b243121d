"""Bad inputs to the rollout and the signals that used to give silent garbage: each raises a
``ValueError`` naming the argument (or, under ``jit``, propagates NaN as documented)."""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.control.pid import pid
from jaxsim.core import rollout
from jaxsim.core.rollout import ClosedLoop, Timing, fold, simulate, tick_times
from jaxsim.core.signals import Constant, Piecewise, Ramp, Sine, Square, Step, Sum, check_signal, sample
from jaxsim.core.system import Plant
from jaxsim.plants.second_order import static_plant

PLANT = static_plant()  # SISO: 2 states, 1 input, 1 output
PID = pid(kp=1.0, ki=0.5, kd=0.0, tf=0.02, anti_windup="none")
TIMING = Timing(t_final=0.05, dt=0.01)
X0 = jnp.zeros(2)


def _loop(**kw) -> ClosedLoop:
    return ClosedLoop(PLANT, PID, **{"reference": Step(1.0), **kw})


def _ticks_sum(acc, tick):
    return acc + jnp.sum(tick.u)


# --- reference / disturbance dimensions -----------------------------------------------------


@pytest.mark.parametrize("run", ["simulate", "fold"])
def test_reference_of_the_wrong_dimension_is_rejected(run):
    loop = _loop(reference=Step(jnp.ones(3)))  # a 3-vector on a SISO plant (was: 3-column u)
    with pytest.raises(ValueError, match=r"^reference: .*shape \(3,\).*n_outputs=1"):
        if run == "simulate":
            simulate(loop, X0, TIMING)
        else:
            fold(loop, X0, TIMING, _ticks_sum, 0.0)


def test_reference_dimension_is_checked_under_jit_too():
    loop = _loop(reference=Step(jnp.ones(3)))
    with pytest.raises(ValueError, match=r"^reference: "):
        jax.jit(lambda lp: simulate(lp, X0, TIMING).u)(loop)


def test_disturbance_of_the_wrong_dimension_is_rejected():
    loop = _loop(disturbance=Step(jnp.ones(2)))  # u − d would be (2,) for a 1-input plant
    with pytest.raises(ValueError, match=r"^disturbance: .*shape \(2,\).*n_inputs=1"):
        simulate(loop, X0, TIMING)


def test_matching_vector_signals_still_run():
    tr = simulate(_loop(reference=Step(jnp.ones(1)), disturbance=Constant(jnp.zeros(1))), X0, TIMING)
    assert tr.u.shape == (5, 1) and tr.r.shape == (5, 1)


# --- plant functions returning the wrong shape ----------------------------------------------


def _plant(output=None, dynamics=None) -> Plant:
    return dataclasses.replace(
        PLANT, output=output or PLANT.output, dynamics=dynamics or PLANT.dynamics, name="user_plant"
    )


@pytest.mark.parametrize(
    "output, got",
    [
        (lambda p, x: x[0], r"\(\)"),  # a scalar
        (lambda p, x: x, r"\(2,\)"),  # both states with n_outputs = 1 (was: a 2-channel PID)
    ],
)
def test_plant_output_of_the_wrong_shape_is_rejected(output, got):
    loop = ClosedLoop(_plant(output=output), PID, reference=Step(1.0))
    with pytest.raises(
        ValueError,
        match=rf"^plant 'user_plant': output\(params, x\) returns shape {got}, "
        r"expected \(1,\)",
    ):
        simulate(loop, X0, TIMING)


def test_plant_dynamics_of_the_wrong_shape_is_rejected():
    loop = ClosedLoop(_plant(dynamics=lambda p, x, u, t: jnp.concatenate([x, u])), PID, reference=Step(1.0))
    with pytest.raises(
        ValueError,
        match=r"^plant 'user_plant': dynamics\(params, x, u, t\) returns shape "
        r"\(3,\), expected \(2,\)",
    ):
        fold(loop, X0, TIMING, _ticks_sum, 0.0)


# --- signals with non-finite or impossible parameters ----------------------------------------


@pytest.mark.parametrize(
    "signal, field",
    [
        (Step(jnp.nan), "amplitude"),
        (Step(jnp.inf), "amplitude"),
        (Step(1.0, jnp.nan), "t0"),
        (Ramp(jnp.inf), "slope"),
        (Sine(1.0, jnp.nan), "frequency"),
        (Square(1.0, jnp.inf), "period"),
        (Constant(jnp.array([0.0, -jnp.inf])), "value"),
        (Piecewise(jnp.array([0.0, jnp.nan]), jnp.array([1.0, 2.0])), "times"),
        (Sum((Step(1.0), Step(jnp.nan))), r"terms\[1\]\.amplitude"),
    ],
)
def test_non_finite_signal_parameters_are_rejected(signal, field):
    with pytest.raises(ValueError, match=rf"^reference\.{field}: must be finite"):
        simulate(_loop(reference=signal), X0, TIMING)
    with pytest.raises(ValueError, match=rf"^disturbance\.{field}: must be finite"):
        simulate(_loop(disturbance=signal), X0, TIMING)


@pytest.mark.parametrize(
    "signal, message",
    [
        (Square(period=0.0), r"^signal\.period: must be positive"),
        (Square(period=-1.0), r"^signal\.period: must be positive"),
        (Square(duty=1.5), r"^signal\.duty: must lie in \[0, 1\]"),
        (Piecewise(jnp.array([0.0, 2.0, 1.0]), jnp.array([1.0, 2.0, 3.0])), r"^signal\.times: must be non-decreasing"),
        (Sum((Step(1.0), Square(period=0.0))), r"^signal\.terms\[1\]\.period: must be positive"),
    ],
)
def test_impossible_signal_parameters_are_rejected(signal, message):
    with pytest.raises(ValueError, match=message):
        check_signal("signal", signal)
    with pytest.raises(ValueError, match=message):
        sample(signal, jnp.linspace(0.0, 1.0, 3))


def test_non_finite_signal_under_jit_propagates_nan():
    # Inside jit the amplitude is a tracer: no error can be raised, the trajectory is NaN (documented).
    tr = jax.jit(lambda a: simulate(_loop(reference=Step(a)), X0, TIMING))(jnp.nan)
    assert np.all(np.isnan(np.asarray(tr.u)))


# --- horizons too long to run ----------------------------------------------------------------


@pytest.mark.parametrize("timing", [Timing(1e10, 1e-10), Timing(1e12, 1.0)])
def test_horizon_beyond_the_step_limit_is_rejected(timing):
    with pytest.raises(
        ValueError,
        match=r"^t_final: t_final/dt = 1e\+(20|12) steps exceeds the limit of "
        rf"{rollout.MAX_STEPS}",
    ):
        fold(_loop(), X0, timing, _ticks_sum, 0.0)
    with pytest.raises(ValueError, match=r"exceeds the limit"):
        tick_times(timing)


def test_horizon_at_the_step_limit_is_accepted():
    n_ticks, substeps, _ = Timing(float(rollout.MAX_STEPS), 1.0).resolve(None)
    assert (n_ticks, substeps) == (rollout.MAX_STEPS, 1)


# --- integer initial state -------------------------------------------------------------------


def test_integer_x0_is_cast_to_float():
    ref = simulate(_loop(), jnp.array([1.0, 0.0]), TIMING)
    tr = simulate(_loop(), jnp.array([1, 0]), TIMING)  # was: a scan carry-type error
    assert tr.x.dtype == ref.x.dtype == jnp.float64
    np.testing.assert_array_equal(np.asarray(tr.x), np.asarray(ref.x))
    acc, x_final = fold(_loop(), np.array([1, 0]), TIMING, _ticks_sum, 0.0)
    np.testing.assert_array_equal(np.asarray(x_final), np.asarray(ref.x_final))


def test_float32_x0_stays_float32():
    tr = simulate(_loop(), jnp.array([1.0, 0.0], jnp.float32), TIMING)
    assert tr.x.dtype == jnp.float32
