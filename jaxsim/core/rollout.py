"""The closed-loop rollout: one ``lax.scan`` over controller ticks.

At tick ``k`` (time ``t_k = k·Ts``, ``Ts`` the controller period):

1. the sensor delivers a new measurement if ``k`` is a multiple of ``sensor_period/Ts``
   (otherwise the last one is held); noise keys are ``fold_in(key, k)``.  For a plant with a
   feedthrough term (``y = output(x) + D u``) the sampler reads ``y_k = output(x_k) + D u_{k−1}``:
   the value just before the new ``u_k`` is applied, with the input held over the previous period
   (zero before ``t = 0``).  This is what a sampler wired to a real plant sees, and it avoids the
   algebraic loop ``y_k → u_k → y_k``;
2. the estimator, if any, updates with that measurement — selected by a mask, not a Python
   branch — and the controller sees ``estimator.read(...)``; without an estimator it sees the
   held measurement;
3. the controller computes ``u_k = step(params, state, r(t_k), seen, Ts, t_k)``, held constant
   (zero-order hold) until ``t_{k+1}``;
4. the estimator predicts to ``t_{k+1}``;
5. the plant integrates ``substeps = Ts/dt`` fixed steps of ``dt`` with the chosen solver; the
   disturbance signal is evaluated at every stage time and enters through ``loop.actuate``.

A disturbance that jumps exactly at a grid time is already seen by the last RK4 stage of the step
that ends there (an O(dt) effect on that one step); the exact LTI step (``ExponentialEuler``) sees
it at the next step.

Everything recorded is sampled at the tick start; ``save_every`` decimates what is stored (the
simulation itself still runs every tick).
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass
from typing import Any, Callable, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.integrators import RK4, Solver
from jaxsim.core.loops import fori
from jaxsim.core.pytree import pytree_dataclass, static_field
from jaxsim.core.signals import Constant, check_signal
from jaxsim.core.system import Controller, Estimator, Plant, Sensor, subtract_input_disturbance
from jaxsim.core.validation import check_finite, check_period_multiple, check_positive, check_returns_shape

MAX_STEPS = 2**31 - 1
"""Longest rollout accepted, in plant integration steps ``t_final/dt``: the tick counter ``k``
(and ``t = k·Ts``) stays within int32, the default integer without x64; at that length one
trajectory already takes minutes even for a 2-state plant, and 1e12 steps would seem to hang.
:meth:`Timing.resolve` rejects anything longer with a ``ValueError`` that says so."""


@pytree_dataclass
class ClosedLoop:
    """A closed loop assembled from parts (all pytrees, so a whole loop can be vmapped)."""

    plant: Plant
    controller: Controller
    reference: Any = Constant(0.0)
    disturbance: Any = Constant(0.0)
    sensor: Sensor | None = None
    estimator: Estimator | None = None
    actuate: Callable[[jax.Array, jax.Array], jax.Array] = static_field(default=subtract_input_disturbance)


@dataclass(frozen=True)
class Timing:
    """Time grid of a rollout (all in the model's time unit).

    Attributes:
        t_final: horizon; must be a multiple of the controller period, and ``t_final/dt`` at most
            :data:`MAX_STEPS`.
        dt: plant integration step.
        controller_period: controller period ``Ts`` (default ``dt``); multiple of ``dt``.
        save_every: store one tick in ``save_every``; must divide the number of ticks.
    """

    t_final: float
    dt: float
    controller_period: float | None = None
    save_every: int = 1

    @property
    def ts(self) -> float:
        return float(self.dt if self.controller_period is None else self.controller_period)

    def resolve(self, sensor_period: float | None) -> tuple[int, int, int]:
        """Validate and return ``(n_ticks, substeps, sensor_every)``."""
        check_positive("dt", self.dt)
        check_positive("t_final", self.t_final)
        steps = float(self.t_final) / float(self.dt)
        if steps > MAX_STEPS + 0.5:
            raise ValueError(
                f"t_final: t_final/dt = {steps:.6g} steps exceeds the limit of {MAX_STEPS} "
                "(2**31 − 1) integration steps per rollout; shorten t_final or enlarge dt"
            )
        substeps = check_period_multiple("controller_period", self.ts, self.dt, "dt")
        n_ticks = check_period_multiple("t_final", self.t_final, self.ts, "controller_period")
        sensor_every = 1
        if sensor_period is not None:
            sensor_every = check_period_multiple("sensor_period", sensor_period, self.ts, "controller_period")
        if int(self.save_every) < 1 or n_ticks % int(self.save_every):
            raise ValueError(
                f"save_every: must be a positive divisor of the number of ticks ({n_ticks}), got {self.save_every!r}"
            )
        return n_ticks, substeps, sensor_every


class Trajectory(NamedTuple):
    """Recorded rollout; leading axis = saved ticks ``N`` (``n_ticks / save_every``).

    t: ``(N,)`` tick times; x: ``(N, n)`` plant state; y: ``(N, p)`` true output (with a
    feedthrough term, with the input held over the previous period, as the sensor sees it); y_meas: ``(N, p)``
    measurement held at the tick; measured: ``(N,)`` whether a new measurement arrived at the tick;
    u: ``(N, m)`` controller output; r: ``(N, k)`` reference; d: ``(N, q)`` disturbance at the tick;
    x_hat: what the estimator gave the controller (``None`` leaves when there is no estimator);
    x_final: ``(n,)`` plant state at ``t_final``.
    """

    t: jax.Array
    x: jax.Array
    y: jax.Array
    y_meas: jax.Array
    measured: jax.Array
    u: jax.Array
    r: jax.Array
    d: jax.Array
    x_hat: Any
    x_final: jax.Array


class Tick(NamedTuple):
    """What happened at one controller tick (shapes as in :class:`Trajectory`, without the time axis)."""

    t: jax.Array
    x: jax.Array
    y: jax.Array
    y_meas: jax.Array
    measured: jax.Array
    u: jax.Array
    r: jax.Array
    d: jax.Array
    x_hat: Any


class _Carry(NamedTuple):
    k: jax.Array
    x: jax.Array
    y_held: jax.Array
    ctrl: Any
    est: Any
    u_prev: Any = None  # (m,) input held over the last period; None for a plant without feedthrough


def hold_input(
    plant: Plant,
    x: jax.Array,
    u: jax.Array,
    t0: jax.Array,
    dt: jax.Array,
    substeps: int,
    solver: Solver = RK4,
    disturbance: Any = Constant(0.0),  # noqa: B008  (an immutable default)
    actuate: Callable[[jax.Array, jax.Array], jax.Array] = subtract_input_disturbance,
) -> jax.Array:
    """Plant state after ``substeps`` solver steps of ``dt`` from ``(t0, x)`` with the input ``u``
    held constant (zero-order hold); the disturbance is evaluated at every stage time and enters
    through ``actuate(u, d)``.  The plant step of :func:`simulate` (and of ``jaxsim.envs``).

    Shapes: ``x (n,)``, ``u (m,)``; ``t0`` and the solver step ``dt`` in seconds (the held interval is
    ``substeps · dt``); returns ``x (n,)``."""

    def field(t, z):
        return plant.f(z, actuate(u, disturbance(t)), t)

    def one(i, z):
        return solver.step(field, t0 + i * dt, z, dt)

    return fori(0, substeps, one, x)


def _check_plant(plant: Plant, x0: jax.Array, t0: jax.Array) -> None:
    """``output`` and ``feedthrough`` must return ``(n_outputs,)`` and ``dynamics`` ``(n_states,)``
    (traced, not run)."""
    label = f"plant {plant.name!r}"
    check_returns_shape(f"{label}: output(params, x)", plant.output, plant.params, x0, shape=(plant.n_outputs,))
    u0 = jnp.zeros(plant.n_inputs, x0.dtype)
    if plant.feedthrough is not None:
        check_returns_shape(
            f"{label}: feedthrough(params, u)", plant.feedthrough, plant.params, u0, shape=(plant.n_outputs,)
        )
    check_returns_shape(
        f"{label}: dynamics(params, x, u, t)", plant.dynamics, plant.params, x0, u0, t0, shape=(plant.n_states,)
    )


def _check_step_signature(ctrl: Controller) -> None:
    """``step`` must accept ``(params, state, r, y, dt, t)``: a controller written for the former
    five-argument ``step`` would otherwise fail deep inside the trace with a bare ``TypeError``."""
    try:
        sig = inspect.signature(ctrl.step)
    except (TypeError, ValueError):  # no introspectable signature (a builtin, say): let the trace tell
        return
    try:
        sig.bind(*range(6))
    except TypeError:
        raise ValueError(
            f"controller {ctrl.name!r}: step must accept (params, state, r, y, dt, t) — six positional "
            f"arguments, t the tick time in s — got the signature {sig}"
        ) from None


def _check_input_shapes(loop: ClosedLoop, u: jax.ShapeDtypeStruct, r0: jax.Array, t0: jax.Array) -> None:
    """The controller output (given the reference) and the disturbed plant input must be ``(m,)``."""
    plant, ctrl = loop.plant, loop.controller
    m, p = plant.n_inputs, plant.n_outputs
    if u.shape != (m,):
        if r0.shape != (p,):
            raise ValueError(
                f"reference: the signal has shape {tuple(r0.shape)} at t = 0, but plant {plant.name!r} has "
                f"n_outputs={p}; controller {ctrl.name!r} then returns u of shape {tuple(u.shape)}, "
                f"expected ({m},) (n_inputs={m})"
            )
        raise ValueError(
            f"controller {ctrl.name!r}: step(params, state, r, y, dt, t) returns u of shape {tuple(u.shape)}, "
            f"expected ({m},) for plant {plant.name!r} (n_inputs={m})"
        )
    d0 = jax.eval_shape(loop.disturbance, t0)
    actuated = jax.eval_shape(loop.actuate, u, d0)
    if actuated.shape != (m,):
        raise ValueError(
            f"disturbance: the signal has shape {tuple(d0.shape)} at t = 0; actuate(u, d) then gives a "
            f"plant input of shape {tuple(actuated.shape)}, expected ({m},) (plant {plant.name!r} has "
            f"n_inputs={m})"
        )


def _anchor(leaf: jax.Array) -> jax.Array | None:
    """One element of a traced real, integer or PRNG-key leaf as a float scalar (``None``: nothing to use)."""
    if jax.dtypes.issubdtype(leaf.dtype, jax.dtypes.prng_key):
        leaf = jax.random.key_data(leaf)
    if leaf.size == 0 or not (jnp.issubdtype(leaf.dtype, jnp.floating) or jnp.issubdtype(leaf.dtype, jnp.integer)):
        return None
    return jnp.ravel(leaf)[0].astype(jnp.result_type(float))


def _promote_like(carry: Any, inputs: Any) -> Any:
    """``carry`` unchanged in value, but its floating leaves made to depend on every traced real,
    integer or key leaf of ``inputs``.

    Under ``vmap``, ``jvp`` and reverse-mode AD the loop's transformation rules find which carry
    leaves are batched / carry tangents / are unknown by a fixed-point iteration, re-transforming the
    whole tick body (nested solver loops included) once per round; a carry that starts as dependent
    on the loop's inputs as it ends settles in one round.  Measured on the AUV formation's tuning
    loss, tracing ``value_and_grad`` 13 → 8 s (``python -m experiments.benchmarks.compile_time
    --programs auv_grad [--no-carry-promotion]``).  ``select`` with a constant ``False`` predicate:
    XLA folds it away, and no NaN/inf of an input can leak in.  Eager calls (no tracer among
    ``inputs``) return ``carry`` itself."""
    anchors = [_anchor(leaf) for leaf in jax.tree_util.tree_leaves(inputs) if isinstance(leaf, jax.core.Tracer)]
    anchors = [a for a in anchors if a is not None]
    if not anchors:
        return carry
    anchor = sum(anchors[1:], anchors[0])
    off = jnp.asarray(False)

    def promote(leaf: Any) -> Any:
        if leaf is None or not jnp.issubdtype(jnp.result_type(leaf), jnp.floating):
            return leaf
        leaf = jnp.asarray(leaf)
        return jax.lax.select(
            jnp.broadcast_to(off, leaf.shape), jnp.broadcast_to(anchor.astype(leaf.dtype), leaf.shape), leaf
        )

    return jax.tree_util.tree_map(promote, carry)


def _prepare(loop: ClosedLoop, x0: jax.Array, timing: Timing, key: jax.Array | None, solver: Solver):
    """Validate, then return ``(tick, carry0, n_ticks)`` with ``tick(carry) -> (carry, Tick)``.

    Checked once here, on concrete and traced loops alike: ``x0`` shape, the plant's ``output``,
    ``feedthrough`` (if any) and ``dynamics`` shapes, the controller output shape (blaming the reference when its
    size differs
    from the plant's outputs) and the disturbed plant input.  On concrete values only: ``x0`` and the
    signal parameters finite (:func:`~jaxsim.core.signals.check_signal`); traced NaN propagates.
    """
    sensor_period = None if loop.sensor is None else loop.sensor.period
    n_ticks, substeps, sensor_every = timing.resolve(sensor_period)
    x0 = jnp.asarray(x0)
    if x0.ndim != 1 or x0.shape[0] != loop.plant.n_states:
        raise ValueError(
            f"x0: expected shape ({loop.plant.n_states},) for plant {loop.plant.name!r}, got {tuple(x0.shape)}"
        )
    check_finite("x0", x0)
    check_signal("reference", loop.reference)
    check_signal("disturbance", loop.disturbance)
    key = jax.random.PRNGKey(0) if key is None else key
    dtype = jnp.result_type(x0, float)
    x0 = x0.astype(dtype)  # an integer x0 would make the scan carry change type
    ts = jnp.asarray(timing.ts, dtype)
    h = jnp.asarray(timing.dt, dtype)
    t0 = jnp.asarray(0.0, dtype)
    plant, ctrl, est = loop.plant, loop.controller, loop.estimator
    _check_plant(plant, x0, t0)
    _check_step_signature(ctrl)
    # the input held over the previous period, read by a feedthrough term (zero before t = 0)
    u_prev0 = None if plant.feedthrough is None else jnp.zeros(plant.n_inputs, dtype)

    def measure(x: jax.Array, t: jax.Array, k: jax.Array, u_prev: Any) -> jax.Array:
        y = plant.h(x, u_prev)
        if loop.sensor is None:
            return y
        return loop.sensor.measure(loop.sensor.params, jax.random.fold_in(key, k), y, t)

    def advance_plant(x: jax.Array, u: jax.Array, t0: jax.Array) -> jax.Array:
        return hold_input(plant, x, u, t0, h, substeps, solver, loop.disturbance, loop.actuate)

    def tick(c: _Carry) -> tuple[_Carry, Tick]:
        t = c.k * ts
        every_tick = sensor_every == 1  # static: no masks to compile (and differentiate) when every tick measures
        arrived = jnp.asarray(True) if every_tick else (c.k % sensor_every) == 0
        y_new = measure(c.x, t, c.k, c.u_prev)
        y_held = y_new if every_tick else jnp.where(arrived, y_new, c.y_held)
        r = loop.reference(t)
        if est is None:
            est_state, seen = c.est, y_held
        else:
            updated = est.update(est.params, c.est, y_held)
            if not every_tick:
                updated = jax.tree_util.tree_map(lambda a, b: jnp.where(arrived, a, b), updated, c.est)
            est_state = updated
            seen = est.read(est.params, est_state)
        ctrl_state, u = ctrl.step(ctrl.params, c.ctrl, r, seen, ts, t)
        if est is not None:
            est_state = est.predict(est.params, est_state, u, ts)
        x_next = advance_plant(c.x, u, t)
        rec = Tick(
            t, c.x, plant.h(c.x, c.u_prev), y_held, arrived, u, r, loop.disturbance(t), None if est is None else seen
        )
        u_held = None if c.u_prev is None else jnp.asarray(u, dtype)
        return _Carry(c.k + 1, x_next, y_held, ctrl_state, est_state, u_held), rec

    y0 = measure(x0, t0, jnp.asarray(0), u_prev0)
    r0 = loop.reference(t0)
    carry = _Carry(
        k=jnp.asarray(0),
        x=x0,
        y_held=y0,
        ctrl=ctrl.init(ctrl.params, r0, y0),
        est=None if est is None else est.init(est.params, y0),
        u_prev=u_prev0,
    )
    carry = _promote_like(carry, (loop, x0, key))
    seen0 = y0 if est is None else est.read(est.params, carry.est)
    u0 = jax.eval_shape(lambda c: ctrl.step(ctrl.params, c, r0, seen0, ts, t0)[1], carry.ctrl)
    _check_input_shapes(loop, u0, r0, t0)
    return tick, carry, n_ticks


def simulate(
    loop: ClosedLoop,
    x0: jax.Array,
    timing: Timing,
    key: jax.Array | None = None,
    solver: Solver = RK4,
) -> Trajectory:
    """Roll the closed loop out from plant state ``x0`` (shape ``(n,)``) over ``timing``.

    Pure and differentiable; ``jit``/``vmap`` it from outside (``timing`` and ``solver`` are static).
    ``key`` seeds sensor noise (required only if the sensor is noisy; defaults to ``PRNGKey(0)``).
    For large batches where only a scalar cost is needed, :func:`fold` avoids storing the
    trajectory (several times faster: the stacked outputs dominate memory traffic).

    An integer ``x0`` is cast to float (float64; a float32 ``x0`` stays float32).

    Raises:
        ValueError: before anything runs, naming the culprit: ``t_final/dt`` above
            :data:`MAX_STEPS`; ``x0`` not ``(n_states,)``; the plant's ``output``/``feedthrough``/``dynamics``
            not returning ``(n_outputs,)``/``(n_outputs,)``/``(n_states,)``; a ``reference`` whose size makes the
            controller's ``u`` differ from ``(n_inputs,)`` (or such a controller); a
            ``disturbance`` that changes the plant input's shape.  These shape checks hold under
            ``jit`` too.  On concrete values also: a non-finite ``x0`` or signal parameter
            (``reference.amplitude: must be finite``); under ``jit`` those give a NaN trajectory.
    """
    tick, carry, n_ticks = _prepare(loop, x0, timing, key, solver)
    save_every = int(timing.save_every)

    def saved_block(c: _Carry, _: Any) -> tuple[_Carry, Tick]:
        c, first = tick(c)
        c = fori(1, save_every, lambda _, cc: tick(cc)[0], c)
        return c, first

    carry, recs = jax.lax.scan(saved_block, carry, None, length=n_ticks // save_every)
    return Trajectory(*recs, x_final=carry.x)


def fold(
    loop: ClosedLoop,
    x0: jax.Array,
    timing: Timing,
    fn: Callable[[Any, Tick], Any],
    acc0: Any,
    key: jax.Array | None = None,
    solver: Solver = RK4,
) -> tuple[Any, jax.Array]:
    """Run the rollout folding ``acc = fn(acc, tick)`` over every tick; returns ``(acc, x_final)``.

    Same simulation as :func:`simulate` (``timing.save_every`` is ignored), but nothing is stored
    per tick: use it for running costs such as ``acc + tick.t * |tick.r − tick.y| * Ts`` (ITAE).
    Inputs are checked (and an integer ``x0`` cast) as in :func:`simulate`.
    """
    tick, carry, n_ticks = _prepare(loop, x0, timing, key, solver)

    def body(_: Any, state: tuple[_Carry, Any]) -> tuple[_Carry, Any]:
        c, acc = state
        c, rec = tick(c)
        return c, fn(acc, rec)

    acc0 = _promote_like(acc0, (loop, x0, key))
    carry, acc = jax.lax.fori_loop(0, n_ticks, body, (carry, acc0))
    return acc, carry.x


def tick_times(timing: Timing) -> np.ndarray:
    """The saved tick times of a rollout with this timing, as a NumPy array."""
    n_ticks, _, _ = timing.resolve(None)
    return np.arange(0, n_ticks, int(timing.save_every)) * timing.ts
