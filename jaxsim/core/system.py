"""The parts a closed loop is built from: plant, controller, sensor, estimator.

Parameters are validated by the factory functions that build the parts (the public boundary),
not on every pytree unflatten: gradients and optimiser states share these structures.

Each part bundles its parameters (a pytree: arrays a user may tune or vmap over) with the pure
functions that use them (static metadata, part of the jit cache key).  Plant and controller
modules build these bundles from their own ``Params`` dataclass and functions, e.g.
``jaxsim.plants.second_order.static_plant()`` or ``jaxsim.control.pid.pid(...)``.

Signatures (``x`` plant state ``(n,)``, ``u`` plant input ``(m,)``, ``y`` output ``(p,)``,
``r`` reference ``(k,)``, ``t`` time, ``dt`` step or period in the same unit):

* plant: ``dynamics(params, x, u, t) -> ẋ``, ``output(params, x) -> y``, and, for a plant with
  direct feedthrough (a biproper transfer function, ``D ≠ 0``), ``feedthrough(params, u) -> D u``
  added to the output;
* controller: ``init(params, r0, y0) -> state``, ``step(params, state, r, y, dt, t) -> (state, u)``
  (``t`` the tick time, see :class:`Controller`);
* sensor: ``measure(params, key, y, t) -> y_meas``;
* estimator: ``init(params, y0) -> state``, ``predict(params, state, u, dt) -> state``,
  ``update(params, state, y_meas) -> state``, ``read(params, state) -> what the controller sees``.
"""

from __future__ import annotations

from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.pytree import pytree_dataclass, static_field
from jaxsim.core.validation import is_concrete


@pytree_dataclass
class Plant:
    """A plant: parameters plus ``dynamics`` and ``output`` functions.

    ``feedthrough`` (optional, static like the other functions) adds a direct input-to-output term:
    ``y = output(params, x) + feedthrough(params, u)`` — ``D u`` for an LTI plant built by
    :func:`jaxsim.lti.ss` / ``tf`` / ``zpk``.  Without it (the default) ``y = output(params, x)``.
    In a closed loop the sampler reads ``y_k`` with the input held over the previous period
    (see :mod:`jaxsim.core.rollout`), so a feedthrough creates no algebraic loop.
    """

    params: Any
    dynamics: Callable[[Any, jax.Array, jax.Array, jax.Array], jax.Array] = static_field()
    output: Callable[[Any, jax.Array], jax.Array] = static_field()
    n_states: int = static_field()
    n_inputs: int = static_field()
    n_outputs: int = static_field()
    name: str = static_field(default="plant")
    feedthrough: Callable[[Any, jax.Array], jax.Array] | None = static_field(default=None)

    def f(self, x: jax.Array, u: jax.Array, t: jax.Array) -> jax.Array:
        """``ẋ = dynamics(params, x, u, t)``."""
        return self.dynamics(self.params, x, u, t)

    def h(self, x: jax.Array, u: jax.Array | None = None) -> jax.Array:
        """``y = output(params, x)``, plus ``feedthrough(params, u)`` for a plant that has one.

        ``u`` ``(m,)`` is ignored by a plant without feedthrough and required by one with it
        (``ValueError`` otherwise: dropping ``D u`` silently would give a wrong output).
        """
        y = self.output(self.params, x)
        if self.feedthrough is None:
            return y
        if u is None:
            raise ValueError(f"u: plant {self.name!r} has a feedthrough term, so h(x, u) needs the input u")
        return y + self.feedthrough(self.params, u)


@pytree_dataclass
class Controller:
    """A discrete-time controller run at its own period with zero-order hold on its output.

    ``init(params, r0, y0) -> state`` gives the state before the first tick from the reference
    ``r0 (k,)`` and what the controller sees at ``t = 0`` (``y0``).

    ``step(params, state, r, y, dt, t) -> (state, u)`` is one tick:

    * ``r`` ``(k,)``: the reference at the tick;
    * ``y``: what the controller sees — the held measurement ``(p,)``, or the estimator's
      ``read(...)`` (any pytree, e.g. a NamedTuple) when the loop has an estimator;
    * ``dt``: the controller period ``Ts`` (s), the interval ``u`` is held for;
    * ``t``: the tick time ``t_k = k·Ts`` (s) — for time-varying laws, start-up gates and gain
      schedules (ignore it otherwise);
    * returns the new state and ``u (m,)``, held constant (zero-order hold) until ``t_k + Ts``.

    Both are pure; ``params`` is a pytree (tunable, vmappable), the functions are static.
    """

    params: Any
    init: Callable[[Any, jax.Array, Any], Any] = static_field()
    step: Callable[[Any, Any, jax.Array, Any, Any, jax.Array], tuple[Any, jax.Array]] = static_field()
    name: str = static_field(default="controller")


def _gaussian_measure(params: Any, key: jax.Array, y: jax.Array, t: jax.Array) -> jax.Array:
    std = jnp.asarray(params)
    return y + std * jax.random.normal(key, y.shape, dtype=y.dtype)


@pytree_dataclass
class Sensor:
    """A sensor delivering ``measure(params, key, y, t)`` every ``period`` (None: every tick)."""

    params: Any = 0.0
    measure: Callable[[Any, jax.Array, jax.Array, jax.Array], jax.Array] = static_field(default=_gaussian_measure)
    period: float | None = static_field(default=None)
    name: str = static_field(default="sensor")


def gaussian_sensor(std: Any = 0.0, period: float | None = None) -> Sensor:
    """Additive white Gaussian noise of standard deviation ``std`` (scalar or ``(p,)``)."""
    if is_concrete(std):  # NumPy, not jnp: jnp ops on constants are staged inside jit
        std_np = np.asarray(std, dtype=float)
        if not np.all(np.isfinite(std_np) & (std_np >= 0)):
            raise ValueError(f"std: must be finite and non-negative, got {std!r}")
    std_arr = jnp.asarray(std)
    return Sensor(params=std_arr, measure=_gaussian_measure, period=period, name="gaussian")


@pytree_dataclass
class Estimator:
    """An estimator that predicts every controller tick and updates when a measurement arrives."""

    params: Any
    init: Callable[[Any, jax.Array], Any] = static_field()
    predict: Callable[[Any, Any, jax.Array, Any], Any] = static_field()
    update: Callable[[Any, Any, jax.Array], Any] = static_field()
    read: Callable[[Any, Any], jax.Array] = static_field()
    name: str = static_field(default="estimator")


def subtract_input_disturbance(u: jax.Array, d: jax.Array) -> jax.Array:
    """Plant input ``u − d``: the disturbance acts at the plant input (fuzzy-PID paper's sign)."""
    return u - d


def add_input_disturbance(u: jax.Array, d: jax.Array) -> jax.Array:
    """Plant input ``u + d``."""
    return u + d
