"""A tuning or robustness question as one object: :class:`Problem`.

A problem says how parameters ``θ`` (a dict declared by a :class:`~jaxsim.problem.space.ParamSpace`)
and a *draw* (a dict of scenario values: operating point, plant parameters) build a closed loop
(:class:`Scenario`), which objective (a :class:`~jaxsim.core.costs.Objective` of running costs)
scores one rollout, over which fixed scenarios the loss averages, and which uncertainty
(:mod:`jaxsim.montecarlo` distributions) a robustness Monte Carlo draws from::

    problem = Problem(
        name="dc_motor_pi", space=space,
        objective=combine(itae=itae(), energy=(1e-3, control_energy())),
        build=lambda p, d: Scenario(loop_of(p, d["K"], d["T"]), jnp.zeros(2), Timing(2.0, 1e-3, 1e-2)),
        nominal={"K": 10.0, "T": 0.1},
        uncertainty={"K": mc.deviation(10.0, 0.2, relative=True), "T": mc.deviation(0.1, 0.2, relative=True)},
    )
    problem.loss(space.init)              # the tuning loss (jit it, or let a tuner do it)
    problem.evaluate(params).terms        # every cost term of one rollout (study metrics)

Gradient tuners (:func:`optim.tune`), swarms and searches (:func:`optim.pso`, ...), robust
objectives, Monte Carlo (:func:`jaxsim.montecarlo.monte_carlo`) and brax envs
(:meth:`jaxsim.envs.PlantEnv.from_problem`) all take a problem.

Draws: ``evaluate(params, draw)`` builds with ``{**nominal, **draw}``; ``scenarios`` is a dict of
arrays with a common leading axis ``S`` (fixed operating points, or draws of the uncertainty from
:meth:`Problem.robust`), and ``loss`` is ``reduce`` over the ``S`` totals.  An entry ``"key"`` in
``scenarios`` (raw ``uint32[2]`` keys, ``(S, 2)``) gives each scenario its own noise key; otherwise
every scenario uses the problem's fixed ``key`` (common random numbers: every tuner sees the same
noise).  Monte Carlo, by contrast, draws fresh noise for every run.

Everything derived is pure and ``jit``-able; :attr:`Problem.jitted` holds the problem's own jitted
``loss``/``evaluate``/``simulate`` (compiled once per problem object, reused by every caller).
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass, field
from typing import Any, Callable, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.costs import Breakdown, Objective, rollout_cost
from jaxsim.core.integrators import RK4, Solver
from jaxsim.core.rollout import ClosedLoop, Tick, Timing, Trajectory, simulate
from jaxsim.montecarlo.distributions import draw as draw_space
from jaxsim.montecarlo.distributions import is_distribution, validate_space
from jaxsim.problem.reducers import mean
from jaxsim.problem.space import ParamSpace


class Scenario(NamedTuple):
    """What ``build(params, draw)`` returns: a closed loop, its initial plant state ``x0 (n,)``, the
    time grid (static), an optional noise key (``None``: the problem's) and the solver (static)."""

    loop: ClosedLoop
    x0: jax.Array
    timing: Timing
    key: jax.Array | None = None
    solver: Solver = RK4


def penalised(f: jax.Array, g: jax.Array, weight: float) -> jax.Array:
    """``f + (weight/2)·Σ max(0, g)²``: the quadratic exterior penalty of the constraints ``g ≤ 0``
    (any shape) added to the objective ``f`` (scalar)."""
    return f + 0.5 * weight * jnp.sum(jnp.maximum(g, 0.0) ** 2)


def _leading(name: str, tree: dict[str, Any]) -> int:
    sizes = {np.shape(v)[0] if np.ndim(v) else None for v in jax.tree_util.tree_leaves(tree)}
    if None in sizes or len(sizes) != 1 or 0 in sizes:
        raise ValueError(f"{name}: every leaf needs the same non-empty leading (scenario) axis, got sizes {sizes}")
    return sizes.pop()


def _key(key: Any) -> jax.Array:
    """An int seed or a PRNG key (raw or typed) as a key."""
    if isinstance(key, (int, np.integer)) and not isinstance(key, bool):
        return jax.random.PRNGKey(int(key))
    return key


@dataclass(frozen=True, eq=False)
class Problem:
    """See the module docstring.  Fields:

    name: label (results, figures).  space: the parameter space.
    objective: running costs scoring one rollout (``None`` for a :meth:`from_loss` problem).
    build: ``(params, draw) -> Scenario``.
    scenarios: fixed draws the loss reduces over (dict of ``(S, …)`` arrays; ``{}``: the nominal one).
    uncertainty: name → :mod:`jaxsim.montecarlo` distribution (robustness Monte Carlo, :meth:`robust`).
    nominal: every draw's default values (must hold each uncertain name: the nominal scenario).
    constraints: ``params -> g``, design-level constraints ``g ≤ 0`` (tuners: penalty or augmented
        Lagrangian; searches: the penalty ``(penalty_weight/2)·Σ max(0, g)²``).
    reduce: scenario totals ``(S,)`` → scalar (:func:`mean`, ``optim.worst_case``, ``optim.cvar``).
    loss_fn: ``(params, draw, key) -> scalar or Breakdown`` for problems whose loss is not a rollout.
    key: the fixed noise key.  penalty_weight: ``w`` of the constraint penalty.
    terms_fn: ``params -> (loss, g)`` when the loss and the constraints come out of one computation
        (:meth:`from_terms`): :meth:`loss_and_violation` then runs it once instead of twice.
    """

    name: str
    space: ParamSpace
    objective: Objective | None = None
    build: Callable[[Any, dict[str, Any]], Scenario] | None = None
    scenarios: dict[str, Any] = field(default_factory=dict)
    uncertainty: dict[str, Any] = field(default_factory=dict)
    nominal: dict[str, Any] = field(default_factory=dict)
    constraints: Callable[[Any], jax.Array] | None = None
    reduce: Callable[[jax.Array], jax.Array] = mean
    loss_fn: Callable[[Any, dict[str, Any], jax.Array], Any] | None = None
    key: Any = field(default_factory=lambda: jax.random.PRNGKey(0))
    penalty_weight: float = 100.0
    terms_fn: Callable[[Any], tuple[jax.Array, jax.Array]] | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"name: must be a non-empty string, got {self.name!r}")
        if not isinstance(self.space, ParamSpace):
            raise ValueError(f"space: expected a ParamSpace, got {type(self.space).__name__}")
        if self.loss_fn is None:
            if self.build is None or self.objective is None:
                raise ValueError("build/objective: a Problem needs build and objective (or use Problem.from_loss)")
            if not callable(self.build):
                raise ValueError(f"build: must be callable (params, draw) -> Scenario, got {type(self.build).__name__}")
        elif not callable(self.loss_fn):
            raise ValueError(f"loss_fn: must be callable, got {type(self.loss_fn).__name__}")
        for name in ("scenarios", "uncertainty", "nominal"):
            if not isinstance(getattr(self, name), dict):
                raise ValueError(f"{name}: must be a dict, got {type(getattr(self, name)).__name__}")
        if self.scenarios:
            _leading("scenarios", self.scenarios)
        bad = [k for k, v in self.uncertainty.items() if not is_distribution(v)]
        if bad:
            raise ValueError(f"uncertainty: {', '.join(bad)} must be jaxsim.montecarlo distributions")
        validate_space(self.uncertainty)
        missing = [k for k in self.uncertainty if k not in self.nominal]
        if missing:
            raise ValueError(
                f"nominal: needs a nominal value for every uncertain parameter; missing {', '.join(missing)}"
            )
        if self.constraints is not None and not callable(self.constraints):
            raise ValueError("constraints: must be callable params -> g (feasible iff g ≤ 0) or None")
        if self.terms_fn is not None and not callable(self.terms_fn):
            raise ValueError("terms_fn: must be callable params -> (loss, g) or None")
        if not callable(self.reduce):
            raise ValueError("reduce: must be callable losses (S,) -> scalar")
        w = float(self.penalty_weight)
        if not np.isfinite(w) or w <= 0:
            raise ValueError(f"penalty_weight: must be finite and positive, got {self.penalty_weight!r}")

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_loss(cls, name: str, space: ParamSpace, loss_fn: Callable[..., Any], **kwargs: Any) -> "Problem":
        """A problem whose loss is any function ``loss_fn(params, draw, key) -> scalar or Breakdown``
        (estimation studies, surrogates); the other fields as in the constructor."""
        return cls(name=name, space=space, loss_fn=loss_fn, **kwargs)

    @classmethod
    def from_terms(
        cls, name: str, space: ParamSpace, terms_fn: Callable[[Any], tuple[jax.Array, jax.Array]], **kwargs: Any
    ) -> "Problem":
        """A problem whose loss and constraints come out of one computation (one simulation scores
        the design and checks its limits): ``terms_fn(params) -> (loss scalar, g)``, feasible iff
        ``g ≤ 0``.  The tuners and :meth:`penalised_loss` call it once per evaluation; a
        :meth:`from_loss` problem with ``constraints`` calling the same simulation would run it twice
        (XLA does not merge the two loops: twice the time and the compilation)."""
        if not callable(terms_fn):
            raise ValueError(f"terms_fn: must be callable params -> (loss, g), got {type(terms_fn).__name__}")
        return cls(
            name=name,
            space=space,
            loss_fn=lambda p, d, k: terms_fn(p)[0],
            constraints=lambda p: terms_fn(p)[1],
            terms_fn=terms_fn,
            **kwargs,
        )

    def replace(self, **changes: Any) -> "Problem":
        """A copy with fields changed (its jitted functions are compiled afresh)."""
        return dataclasses.replace(self, **changes)

    # ------------------------------------------------------------------ evaluation
    @property
    def n_scenarios(self) -> int:
        """Scenarios one loss evaluation simulates (1 without ``scenarios``)."""
        return _leading("scenarios", self.scenarios) if self.scenarios else 1

    @property
    def sims_per_eval(self) -> int:
        """Simulations one loss evaluation costs (accounting of the tuners): :attr:`n_scenarios`."""
        return self.n_scenarios

    def _draw(self, draw: dict[str, Any] | None) -> dict[str, Any]:
        return {**self.nominal, **(draw or {})}

    def scenario(self, params: Any, draw: dict[str, Any] | None = None) -> Scenario:
        """``build(params, {**nominal, **draw})``."""
        if self.build is None:
            raise ValueError(f"problem {self.name!r} was made with from_loss: it has no closed loop to build")
        sc = self.build(params, self._draw(draw))
        if not isinstance(sc, Scenario):
            raise ValueError(f"build: must return a Scenario(loop, x0, timing), got {type(sc).__name__}")
        return sc

    def evaluate(self, params: Any, draw: dict[str, Any] | None = None, key: jax.Array | None = None) -> Breakdown:
        """Every cost term of one scenario (``Breakdown(terms, total)``); ``key`` overrides the noise key."""
        if self.loss_fn is not None:
            out = self.loss_fn(params, self._draw(draw), self.key if key is None else key)
            if isinstance(out, Breakdown):
                return out
            value = jnp.asarray(out)
            return Breakdown({"loss": value}, value)
        sc = self.scenario(params, draw)
        return rollout_cost(self.objective, sc.loop, sc.x0, sc.timing, self._noise_key(sc, key), sc.solver)

    def _noise_key(self, sc: Scenario, key: jax.Array | None) -> jax.Array:
        """The noise key of a rollout: ``key`` if given, else the scenario's, else the problem's."""
        return key if key is not None else (sc.key if sc.key is not None else self.key)

    def _per_scenario(self, fn: Callable[[dict[str, Any] | None, jax.Array | None], jax.Array]) -> jax.Array:
        """``fn(draw, key)`` stacked over the scenarios (a leading axis ``S``; ``(1, …)`` for the nominal
        one, ``fn(None, None)``); ``key`` is the scenario's own noise key or ``None``."""
        if not self.scenarios:
            return fn(None, None)[None]
        draws = dict(self.scenarios)
        keys = draws.pop("key", None)
        if keys is None:
            return jax.vmap(lambda d: fn(d, None))(draws)
        return jax.vmap(fn)(draws, keys)

    def scenario_totals(self, params: Any) -> jax.Array:
        """``(S,)`` totals of every scenario (``(1,)`` for the nominal one)."""
        return self._per_scenario(lambda d, k: self.evaluate(params, d, k).total)

    def loss(self, params: Any) -> jax.Array:
        """The tuning loss: ``reduce`` over the scenario totals (the nominal total without scenarios).
        Constraints are not included (the tuners handle them)."""
        if not self.scenarios:
            return self.evaluate(params).total
        return self.reduce(self.scenario_totals(params))

    @property
    def least_squares(self) -> bool:
        """Whether :meth:`residuals` exists: a rollout objective whose every term is a sum of squares
        (:mod:`jaxsim.core.costs`: ``ise``, ``control_energy``, ``saturation_excess``, ``penalty``),
        averaged over the scenarios (``reduce`` = :func:`~jaxsim.problem.reducers.mean`)."""
        return self.objective is not None and self.objective.residual is not None and self.reduce is mean

    def residuals(self, params: Any) -> jax.Array:
        """The loss as a sum of squares, ``loss(params) = Σ residuals(params)²`` (to rounding): the
        objective's per-tick residuals of every scenario, flattened to ``(S·N·k,)`` and scaled by
        ``1/√S`` — what Gauss–Newton / :func:`optim.least_squares.levenberg_marquardt` need.

        Raises ``ValueError`` unless :attr:`least_squares` (an ITAE or IAE term, a ``loss_fn``, or a
        reduce other than the mean has no residual form)."""
        if not self.least_squares:
            why = (
                "it was made with from_loss"
                if self.objective is None
                else "its reduce is not the mean"
                if self.objective.residual is not None
                else f"a term of {', '.join(self.objective.names)} is not a sum of squares (ITAE/IAE are not)"
            )
            raise ValueError(f"problem {self.name!r}: no residual form of the loss ({why})")

        def one(draw: dict[str, Any] | None, key: jax.Array | None) -> jax.Array:
            sc = self.scenario(params, draw)
            timing = dataclasses.replace(sc.timing, save_every=1)
            tr = simulate(sc.loop, sc.x0, timing, self._noise_key(sc, key), sc.solver)
            ts = jnp.asarray(timing.ts, tr.t.dtype)
            ticks = Tick(*tr[: len(Tick._fields)])
            return jnp.ravel(jax.vmap(lambda tick: self.objective.residual(tick, ts))(ticks))

        per = self._per_scenario(one)
        return jnp.ravel(per) / jnp.sqrt(per.shape[0])

    def violation(self, params: Any) -> jax.Array:
        """``g(params)`` flattened (``(0,)`` without constraints)."""
        if self.constraints is None:
            return jnp.zeros((0,))
        return jnp.ravel(jnp.asarray(self.constraints(params)))

    def loss_and_violation(self, params: Any) -> tuple[jax.Array, jax.Array]:
        """``(loss, g)`` with ``g`` flattened (``(0,)`` without constraints): one call of ``terms_fn``
        for a :meth:`from_terms` problem without scenarios, else :meth:`loss` and :meth:`violation`."""
        if self.terms_fn is not None and not self.scenarios:
            f, g = self.terms_fn(params)
            return jnp.asarray(f), jnp.ravel(jnp.asarray(g))
        return self.loss(params), self.violation(params)

    def penalised_loss(self, params: Any) -> jax.Array:
        """``loss + (penalty_weight/2)·Σ max(0, g)²`` (what the swarm and the searches minimise)."""
        if self.constraints is None:
            return self.loss(params)
        return penalised(*self.loss_and_violation(params), self.penalty_weight)

    def search_loss(self, z: jax.Array) -> jax.Array:
        """:meth:`penalised_loss` at the search-coordinate point ``z (d,)`` (PSO, grid, random search)."""
        return self.penalised_loss(self.space.from_search(z))

    def simulate(self, params: Any, draw: dict[str, Any] | None = None, key: jax.Array | None = None) -> Trajectory:
        """The stored trajectory of one scenario (figures)."""
        sc = self.scenario(params, draw)
        return simulate(sc.loop, sc.x0, sc.timing, self._noise_key(sc, key), sc.solver)

    # ------------------------------------------------------------------ uncertainty
    def sample(self, key: Any, n: int) -> dict[str, jax.Array]:
        """``n`` draws of ``uncertainty`` (dict of ``(n, …)`` arrays).  Draw ``i`` is the one the
        Monte-Carlo engine gives run ``i`` with the same key (``draw(space, fold_in(fold_in(key, i), 0))``)."""
        if not self.uncertainty:
            raise ValueError(f"problem {self.name!r} declares no uncertainty to sample")
        n = int(n)
        if n < 1:
            raise ValueError(f"n: must be a positive integer, got {n}")
        key = _key(key)

        def one(i):
            k = jax.random.fold_in(jax.random.fold_in(key, i.astype(jnp.uint32)), 0)
            return draw_space(self.uncertainty, k)

        return jax.vmap(one)(jnp.arange(n))

    def robust(self, n: int, key: Any, reducer: Callable[[jax.Array], jax.Array] = mean) -> "Problem":
        """The problem whose loss is ``reducer`` over ``n`` fixed draws of the uncertainty (times the
        existing scenarios, if any: every draw at every operating point)."""
        both = [k for k in self.scenarios if k in self.uncertainty]
        if both:
            raise ValueError(
                f"{both[0]}: is both a fixed scenario value and uncertain; drop it from one of scenarios/uncertainty"
            )
        draws = self.sample(key, n)
        if self.scenarios:
            s = self.n_scenarios
            draws = {k: jnp.repeat(v, s, axis=0) for k, v in draws.items()}
            fixed = {k: jnp.tile(jnp.asarray(v), (n,) + (1,) * (jnp.ndim(v) - 1)) for k, v in self.scenarios.items()}
            draws = {**fixed, **draws}
        return self.replace(scenarios=draws, reduce=reducer)

    PARAMS_KEY = "_params"
    """Name under which :meth:`monte_carlo_spec` puts the parameters into the Monte-Carlo space."""

    def monte_carlo_spec(self, params: Any) -> tuple[Callable[[jax.Array, Any], dict[str, jax.Array]], dict[str, Any]]:
        """``(fn, space)`` for :func:`jaxsim.montecarlo.monte_carlo`: ``fn(key, draw)`` is one run's
        :class:`~jaxsim.core.costs.Breakdown` terms plus ``"total"`` with fresh noise ``key``;
        ``space`` is ``{**nominal, **uncertainty, "_params": params}`` (the parameters travel as a fixed
        entry of the space, so one compiled kernel serves every ``params`` of this problem)."""
        if self.PARAMS_KEY in self.nominal:
            raise ValueError(f"nominal: {self.PARAMS_KEY!r} is reserved for the parameters in Monte Carlo")
        return self._mc_metric, {**self.nominal, **self.uncertainty, self.PARAMS_KEY: params}

    @functools.cached_property
    def _mc_metric(self) -> Callable[[jax.Array, dict[str, Any]], dict[str, jax.Array]]:
        def metric(key: jax.Array, draw: dict[str, Any]) -> dict[str, jax.Array]:
            draw = dict(draw)
            params = draw.pop(self.PARAMS_KEY)
            b = self.evaluate(params, draw, key)
            return {**b.terms, "total": b.total}

        metric.__qualname__ = f"Problem[{self.name}].metric"
        return metric

    # ------------------------------------------------------------------ compiled functions
    @functools.cached_property
    def jitted(self) -> "Jitted":
        """This problem's jitted ``loss``, ``evaluate``, ``simulate``, ``simulate_batch`` (one params,
        a batched dict of draws), ``search_loss``, batched ``search_losses`` and ``value_and_grad`` of
        the loss (compiled on first use, then reused for any params: no recompilation per call;
        ``evaluate``/``simulate`` compile once whether ``draw``/``key`` are left out or passed as None)."""
        return Jitted(
            loss=jax.jit(self.loss),
            evaluate=_with_optional_args(jax.jit(self.evaluate)),
            simulate=_with_optional_args(jax.jit(self.simulate)),
            simulate_batch=jax.jit(jax.vmap(self.simulate, in_axes=(None, 0))),
            search_loss=jax.jit(self.search_loss),
            search_losses=jax.jit(jax.vmap(self.search_loss)),
            value_and_grad=jax.jit(jax.value_and_grad(self.loss)),
        )


def _with_optional_args(fn: Callable) -> Callable:
    """``fn(params, draw=None, key=None)`` always called with all three arguments: to ``jax.jit``
    ``f(p)`` and ``f(p, None)`` are different signatures, so each would be compiled (a study's
    response table and its figure compiled the same rollout twice)."""

    def call(params: Any, draw: dict[str, Any] | None = None, key: jax.Array | None = None) -> Any:
        return fn(params, draw, key)

    return call


class Jitted(NamedTuple):
    """The jitted functions of one :class:`Problem` (see :attr:`Problem.jitted`)."""

    loss: Callable
    evaluate: Callable
    simulate: Callable
    simulate_batch: Callable
    search_loss: Callable
    search_losses: Callable
    value_and_grad: Callable
