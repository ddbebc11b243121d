"""Running costs: objectives accumulated tick by tick inside :func:`jaxsim.core.rollout.fold`.

A :class:`RunningCost` is an optax-like triple of pure functions (plus an optional fourth):

* ``init() -> acc`` — the accumulator (a pytree of scalars);
* ``update(acc, tick, ts) -> acc`` — one controller tick (:class:`~jaxsim.core.rollout.Tick`) of
  period ``ts`` (s);
* ``finish(acc) -> scalar`` — the cost of the whole rollout;
* ``rate(tick, ts) -> scalar`` — only for *additive* costs (``finish(acc) = Σ rate``): the
  increment of one tick; a brax env's reward is ``−rate`` (:meth:`jaxsim.envs.PlantEnv.from_problem`);
* ``residual(tick, ts) -> (k,)`` — only for *sums of squares* (``rate = Σ residual²``: ISE, control
  energy, saturation excess, penalties): the residuals of one tick, which let Gauss–Newton /
  Levenberg–Marquardt work on the rollout (:meth:`jaxsim.problem.Problem.residuals`).

Integrals use the rectangle rule on the ticks (``Σ integrand(t_k)·ts``), the rule of
:mod:`jaxsim.core.metrics`, whose integrands they share: a running ITAE over ``fold`` equals
``metrics.itae`` of the ``simulate`` trajectory of the same loop.  The error is ``e = r − y`` on the
true output; ``channels`` selects output (error) or input indices (``None``: all, summed).

:func:`combine` composes costs like ``optax.chain`` composes transforms::

    objective = combine(itae=itae(), energy=(1e-3, control_energy()))
    breakdown = objective.finish(acc)        # Breakdown(terms={"itae": …, "energy": …}, total=…)

``terms`` holds every cost unweighted (reported as study metrics), ``total`` the weighted sum (the
tuning loss); ``objective.rate`` exists iff every term is additive.
"""

from __future__ import annotations

from typing import Any, Callable, NamedTuple, Sequence

import jax
import jax.numpy as jnp

from jaxsim.core import metrics
from jaxsim.core.integrators import RK4, Solver
from jaxsim.core.rollout import ClosedLoop, Tick, Timing, fold

Channels = int | Sequence[int] | None


class RunningCost(NamedTuple):
    """``init() -> acc``, ``update(acc, tick, ts) -> acc``, ``finish(acc) -> scalar``; ``rate(tick, ts)``
    for additive costs and ``residual(tick, ts)`` for sums of squares (``None`` otherwise).  See the
    module docstring."""

    init: Callable[[], Any]
    update: Callable[[Any, Tick, jax.Array], Any]
    finish: Callable[[Any], jax.Array]
    rate: Callable[[Tick, jax.Array], jax.Array] | None = None
    residual: Callable[[Tick, jax.Array], jax.Array] | None = None


class Breakdown(NamedTuple):
    """Result of an :class:`Objective`: every term unweighted (``terms``) and the weighted ``total``."""

    terms: dict[str, jax.Array]
    total: jax.Array


class Objective(NamedTuple):
    """A :class:`RunningCost` whose ``finish`` returns a :class:`Breakdown` (built by :func:`combine`).

    ``names``/``weights``: the terms in order and their weights in ``total``; ``residual``: the
    weighted residuals of every term, concatenated (``None`` unless every term is a sum of squares
    with a non-negative weight).
    """

    init: Callable[[], Any]
    update: Callable[[Any, Tick, jax.Array], Any]
    finish: Callable[[Any], Breakdown]
    rate: Callable[[Tick, jax.Array], jax.Array] | None
    names: tuple[str, ...]
    weights: tuple[float, ...]
    residual: Callable[[Tick, jax.Array], jax.Array] | None = None


def _zero() -> jax.Array:
    return jnp.zeros((), jnp.result_type(float))


def _select(v: jax.Array, channels: Channels) -> jax.Array:
    if channels is None:
        return v
    return v[jnp.asarray(channels)]


def additive(
    rate: Callable[[Tick, jax.Array], jax.Array], residual: Callable[[Tick, jax.Array], jax.Array] | None = None
) -> RunningCost:
    """The running cost ``Σ_k rate(tick_k, ts)`` (accumulator: one scalar); ``residual`` (optional)
    with ``rate = Σ residual²`` marks it a sum of squares."""
    return RunningCost(
        init=_zero,
        update=lambda acc, tick, ts: acc + rate(tick, ts),
        finish=lambda acc: acc,
        rate=rate,
        residual=residual,
    )


def _error(tick: Tick, channels: Channels) -> jax.Array:
    return _select(tick.r - tick.y, channels)


def iae(channels: Channels = None) -> RunningCost:
    """``∫ Σ|r − y| dt`` (error units × s)."""
    return additive(lambda tick, ts: jnp.sum(metrics.iae_integrand(_error(tick, channels))) * ts)


def ise(channels: Channels = None) -> RunningCost:
    """``∫ Σ(r − y)² dt`` (error units² × s)."""
    return additive(
        lambda tick, ts: jnp.sum(metrics.ise_integrand(_error(tick, channels))) * ts,
        lambda tick, ts: jnp.ravel(_error(tick, channels)) * jnp.sqrt(ts),
    )


def itae(channels: Channels = None, clock: Callable[[jax.Array], jax.Array] | None = None) -> RunningCost:
    """``∫ Σ w(t)|r − y| dt`` with ``w = clock(t)`` (default ``w = t``; error units × s²).

    ``clock(t)`` may return one weight per channel, e.g. the time since each channel's last reference
    switch (the ITAE of every step of a square wave)."""
    weight = (lambda t: t) if clock is None else clock
    return additive(lambda tick, ts: jnp.sum(metrics.itae_integrand(weight(tick.t), _error(tick, channels))) * ts)


def control_energy(offset: Any = 0.0, channels: Channels = None) -> RunningCost:
    """``∫ Σ(u − offset)² dt`` on the commanded input (input units² × s; ``offset`` e.g. a trim input)."""
    return additive(
        lambda tick, ts: jnp.sum(metrics.energy_integrand(_select(tick.u, channels), offset)) * ts,
        lambda tick, ts: jnp.ravel(_select(tick.u, channels) - offset) * jnp.sqrt(ts),
    )


def saturation_excess(u_max: Any, channels: Channels = None) -> RunningCost:
    """``∫ Σ max(0, |u| − u_max)² dt`` on the commanded input (input units² × s)."""
    return additive(
        lambda tick, ts: jnp.sum(metrics.saturation_excess_integrand(_select(tick.u, channels), u_max)) * ts,
        lambda tick, ts: jnp.ravel(jnp.maximum(jnp.abs(_select(tick.u, channels)) - u_max, 0.0)) * jnp.sqrt(ts),
    )


def penalty(g: Callable[[Tick], jax.Array], weight: float = 1.0) -> RunningCost:
    """``weight·∫ Σ max(0, g(tick))² dt``: a soft path constraint ``g ≤ 0`` (e.g. ``|y| − y_max``); a sum
    of squares (with residuals) for a non-negative ``weight``."""
    residual = None
    if float(weight) >= 0:

        def residual(tick, ts):
            return jnp.ravel(jnp.maximum(jnp.asarray(g(tick)), 0.0)) * jnp.sqrt(weight * ts)

    return additive(lambda tick, ts: weight * jnp.sum(jnp.maximum(jnp.asarray(g(tick)), 0.0) ** 2) * ts, residual)


def terminal(fn: Callable[[Tick], jax.Array]) -> RunningCost:
    """``fn(last tick)``: a cost of the last tick of the horizon (time ``t_final − ts``: ticks are
    recorded at their start), e.g. ``lambda tick: (tick.r[0] - tick.y[0]) ** 2``.  Not additive."""
    return RunningCost(
        init=_zero, update=lambda acc, tick, ts: jnp.asarray(fn(tick), acc.dtype).reshape(()), finish=lambda acc: acc
    )


class _SoftmaxAcc(NamedTuple):
    """Online ``Σ softmax(v/τ)·v``: running max ``m``, ``s = Σ e^{(v−m)/τ}``, ``w = Σ e^{(v−m)/τ}·v``."""

    m: jax.Array
    s: jax.Array
    w: jax.Array


def _softmax_init() -> _SoftmaxAcc:
    z = _zero()
    return _SoftmaxAcc(z - jnp.inf, z, z)


def _softmax_push(acc: _SoftmaxAcc, v: jax.Array, temperature: float) -> _SoftmaxAcc:
    m = jnp.maximum(acc.m, v)
    old = jnp.exp((acc.m - m) / temperature)
    new = jnp.exp((v - m) / temperature)
    return _SoftmaxAcc(m, acc.s * old + new, acc.w * old + new * v)


def _target(tick: Tick, channel: int, y_final: Any) -> jax.Array:
    return tick.r[channel] if y_final is None else jnp.asarray(y_final)


def soft_overshoot(temperature: float = 0.5, channel: int = 0, y_final: Any = None) -> RunningCost:
    """Smooth overshoot of output ``channel`` in percent, online: equals
    :func:`jaxsim.core.metrics.soft_overshoot` of the same samples (``temperature`` τ in percent).

    ``y_final``: the final value the overshoot is measured from (default: the tick's reference, which
    for a step reference is its final value).  The accumulator is a running max and a log-sum-exp,
    so nothing is stored per tick.  Not additive."""

    def update(acc, tick, ts):
        v = metrics.overshoot_samples(tick.y[channel], _target(tick, channel, y_final))
        return _softmax_push(acc, v, temperature)

    def finish(acc):
        return temperature * jax.nn.softplus(acc.w / acc.s / temperature)

    return RunningCost(init=_softmax_init, update=update, finish=finish)


def soft_settling_time(
    band: float = 0.02,
    band_temperature: float = 0.002,
    time_temperature: float = 0.02,
    channel: int = 0,
    y_final: Any = None,
) -> RunningCost:
    """Smooth settling time (s) of output ``channel``, online: equals
    :func:`jaxsim.core.metrics.soft_settling_time` of the same samples (``y_final`` as in
    :func:`soft_overshoot`).  Not additive."""

    def update(acc, tick, ts):
        v = metrics.settling_samples(
            tick.t + ts, tick.y[channel], _target(tick, channel, y_final), band, band_temperature
        )
        return _softmax_push(acc, v, time_temperature)

    return RunningCost(init=_softmax_init, update=update, finish=lambda acc: acc.w / acc.s)


def _as_term(name: str, value: Any) -> tuple[float, Any]:
    if isinstance(value, tuple) and not hasattr(value, "init"):
        if len(value) != 2:
            raise ValueError(f"{name}: expected a RunningCost or (weight, RunningCost), got a tuple of {len(value)}")
        weight, cost = value
    else:
        weight, cost = 1.0, value
    if not all(callable(getattr(cost, f, None)) for f in ("init", "update", "finish")):
        raise ValueError(f"{name}: expected a RunningCost (init/update/finish), got {type(cost).__name__}")
    try:
        weight = float(weight)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: the weight must be a number, got {weight!r}") from None
    if not jnp.isfinite(weight):
        raise ValueError(f"{name}: the weight must be finite, got {weight!r}")
    return weight, cost


def combine(**terms: Any) -> Objective:
    """An :class:`Objective` from named terms, each a :class:`RunningCost` or ``(weight, RunningCost)``.

    ``finish`` returns ``Breakdown(terms={name: unweighted value}, total=Σ weight·value)``; a term
    that is itself an :class:`Objective` contributes its ``total``.  ``rate`` is the weighted sum of
    the terms' rates when every term is additive, else ``None``.
    """
    if not terms:
        raise ValueError("combine: needs at least one term")
    names = tuple(terms)
    pairs = [_as_term(n, v) for n, v in terms.items()]
    weights = tuple(w for w, _ in pairs)
    costs = tuple(c for _, c in pairs)

    def value(cost: Any, acc: Any) -> jax.Array:
        out = cost.finish(acc)
        return out.total if isinstance(out, Breakdown) else out

    def init():
        return tuple(c.init() for c in costs)

    def update(acc, tick, ts):
        return tuple(c.update(a, tick, ts) for c, a in zip(costs, acc))

    def finish(acc) -> Breakdown:
        values = {n: value(c, a) for n, c, a in zip(names, costs, acc)}
        total = sum(w * values[n] for n, w in zip(names, weights))
        return Breakdown(values, jnp.asarray(total))

    rate = None
    if all(c.rate is not None for c in costs):

        def rate(tick, ts):
            return sum(w * c.rate(tick, ts) for w, c in zip(weights, costs))

    residual = None
    if all(c.residual is not None for c in costs) and all(w >= 0 for w in weights):

        def residual(tick, ts):
            return jnp.concatenate([jnp.sqrt(w) * jnp.ravel(c.residual(tick, ts)) for w, c in zip(weights, costs)])

    return Objective(init, update, finish, rate, names, weights, residual)


def accumulate(cost: RunningCost | Objective, ticks: Tick, ts: Any) -> Any:
    """``finish`` of ``cost`` folded over stacked ticks (leading time axis, e.g. a
    :class:`~jaxsim.core.rollout.Trajectory`'s fields): the running cost of a recorded rollout."""

    def body(acc, tick):
        return cost.update(acc, tick, ts), None

    acc, _ = jax.lax.scan(body, cost.init(), ticks)
    return cost.finish(acc)


def rollout_cost(
    cost: RunningCost | Objective,
    loop: ClosedLoop,
    x0: jax.Array,
    timing: Timing,
    key: jax.Array | None = None,
    solver: Solver = RK4,
) -> Any:
    """``finish`` of ``cost`` over one rollout of ``loop`` (:func:`~jaxsim.core.rollout.fold`: nothing
    stored per tick); a :class:`Breakdown` for an :class:`Objective`, else a scalar."""
    ts = timing.ts
    acc, _ = fold(loop, x0, timing, lambda a, tick: cost.update(a, tick, ts), cost.init(), key=key, solver=solver)
    return cost.finish(acc)
