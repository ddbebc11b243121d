"""A plant of the toolkit as a brax environment (``brax.envs.base.Env``).

One generic wrapper, :class:`PlantEnv`, built from a :class:`Task` — the plant (its pure
``dynamics``/``output`` functions), the control period, the solver, the reference signal, the input
limits, the per-step loss and the observation.  The per-plant modules of this package
(:mod:`jaxsim.envs.second_order`, :mod:`jaxsim.envs.trms`, ...) only build tasks, and
:meth:`PlantEnv.from_problem` builds one from a :class:`~jaxsim.problem.Problem`: its scenario's
plant, reference, disturbance, initial state and timing, and the reward ``−objective.rate`` (the
running cost of one tick, so ``−Σ rewards`` over the horizon is the problem's total for the
policy's inputs).

One env step is one controller tick of :func:`jaxsim.core.rollout.simulate` without sensor,
estimator or disturbance: at tick ``k`` (time ``t_k = k·dt``) the action ``a ∈ [−1, 1]^m`` is mapped
affinely onto ``[u_low, u_high]`` (``a = −1 → u_low``, ``a = +1 → u_high``; actions outside are
clipped), the reward is ``−step_loss(t_k, r(t_k), y_k, u_k)`` (or ``−tick_loss(tick_k, dt)`` on the
whole :class:`~jaxsim.core.rollout.Tick`), and the plant integrates ``substeps`` solver steps with
``u_k`` held (:func:`jaxsim.core.rollout.hold_input`, the same plant step as ``simulate``, the task's
disturbance entering through ``actuate``).  The observation is ``observe(x_{k+1}, r(t_{k+1}), t_{k+1})``.

``done`` is set only when the task's ``terminate(x)`` says so or the state is no longer finite;
episode truncation (a time limit) is left to brax's ``EpisodeWrapper`` (``brax.envs.wrappers.
training.wrap``), as for brax's own environments.  ``state.metrics["loss"]`` is the step loss.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from brax.envs.base import Env, State

from jaxsim.core.integrators import RK4, Solver
from jaxsim.core.rollout import Tick, hold_input
from jaxsim.core.signals import Constant
from jaxsim.core.system import Plant, subtract_input_disturbance
from jaxsim.core.validation import check_positive

StepLoss = Callable[[jax.Array, jax.Array, jax.Array, jax.Array], jax.Array]
Observe = Callable[[jax.Array, jax.Array, jax.Array], jax.Array]


def observe_state_and_error(plant: Plant) -> Observe:
    """Observation ``(x, r − y)`` of shape ``(n + p,)``: the plant state and the tracking error."""

    def observe(x: jax.Array, r: jax.Array, t: jax.Array) -> jax.Array:
        return jnp.concatenate([x, r - plant.h(x)])

    return observe


@dataclass(frozen=True)
class Task:
    """Everything :class:`PlantEnv` needs (units those of the plant; time in s).

    Attributes:
        plant: the plant (``dynamics``, ``output``, parameters).
        step_loss: ``(t, r (k,), y (p,), u (m,)) -> scalar`` loss accrued over one control period
            starting at ``t``; the reward is its negative.  ``None`` when ``tick_loss`` is given.
        u_low, u_high: ``(m,)`` input limits onto which actions in ``[−1, 1]`` are mapped.
        dt: control period (one env step).
        x0: ``(n,)`` nominal initial state.
        x0_spread: ``(n,)`` or scalar half-width of the uniform perturbation of ``x0`` on reset.
        reference: ``r(t) -> (k,)`` signal (default: zero).
        observe: ``(x, r, t) -> (d,)`` observation (default :func:`observe_state_and_error`).
        substeps: solver steps per control period (integration step ``dt/substeps``).
        solver: fixed-step solver (default RK4).
        terminate: optional ``x -> bool`` failure condition (ends the episode).
        tick_loss: optional ``(tick, dt) -> scalar`` loss of one tick from the whole
            :class:`~jaxsim.core.rollout.Tick` (state included); replaces ``step_loss``.
        disturbance: ``d(t)`` signal entering the plant input through ``actuate(u, d)`` (default zero).
        actuate: how the disturbance enters (default ``u − d``, as in :class:`~jaxsim.core.rollout.ClosedLoop`).
    """

    plant: Plant
    step_loss: StepLoss
    u_low: Any
    u_high: Any
    dt: float
    x0: Any
    x0_spread: Any = 0.0
    reference: Any = field(default_factory=lambda: Constant(0.0))
    observe: Observe | None = None
    substeps: int = 1
    solver: Solver = RK4
    terminate: Callable[[jax.Array], jax.Array] | None = None
    tick_loss: Callable[[Tick, Any], jax.Array] | None = None
    disturbance: Any = field(default_factory=lambda: Constant(0.0))
    actuate: Callable[[jax.Array, jax.Array], jax.Array] = subtract_input_disturbance

    def __post_init__(self):
        if (self.step_loss is None) == (self.tick_loss is None):
            raise ValueError("step_loss/tick_loss: give exactly one of them")
        check_positive("dt", self.dt)
        if int(self.substeps) != self.substeps or self.substeps < 1:
            raise ValueError(f"substeps: must be a positive integer, got {self.substeps!r}")
        m, n = self.plant.n_inputs, self.plant.n_states
        for name in ("u_low", "u_high"):
            v = np.asarray(getattr(self, name), float)
            if v.shape not in ((), (m,)) or not np.all(np.isfinite(v)):
                raise ValueError(f"{name}: expected finite scalar or shape ({m},), got {getattr(self, name)!r}")
        if not np.all(np.asarray(self.u_high, float) > np.asarray(self.u_low, float)):
            raise ValueError(f"u_high: must exceed u_low elementwise, got {self.u_high!r} ≤ {self.u_low!r}")
        if np.shape(self.x0) != (n,) or not np.all(np.isfinite(np.asarray(self.x0, float))):
            raise ValueError(f"x0: expected finite shape ({n},), got shape {np.shape(self.x0)}")
        spread = np.asarray(self.x0_spread, float)
        if spread.shape not in ((), (n,)) or not np.all(spread >= 0):
            raise ValueError(f"x0_spread: expected non-negative scalar or shape ({n},), got {self.x0_spread!r}")


class PlantState(NamedTuple):
    """``pipeline_state`` of a :class:`PlantEnv`: plant state ``x (n,)`` and tick index ``k``."""

    x: jax.Array
    k: jax.Array


class PlantEnv(Env):
    """A :class:`Task` as a brax ``Env`` (pure, jit- and vmap-compatible ``reset``/``step``)."""

    def __init__(self, task: Task):
        if not isinstance(task, Task):
            raise ValueError(f"task: expected a Task, got {type(task).__name__}")
        self.task = task
        self._observe = task.observe or observe_state_and_error(task.plant)
        m = task.plant.n_inputs
        self._u_low = jnp.broadcast_to(jnp.asarray(task.u_low, float), (m,))
        self._u_high = jnp.broadcast_to(jnp.asarray(task.u_high, float), (m,))

    # ------------------------------------------------------------------ brax API
    def reset(self, rng: jax.Array) -> State:
        task = self.task
        x0 = jnp.asarray(task.x0, float)
        spread = jnp.asarray(task.x0_spread, float)
        x = x0 + spread * jax.random.uniform(rng, x0.shape, x0.dtype, -1.0, 1.0)
        k = jnp.asarray(0, jnp.int32)
        zero = jnp.zeros((), x.dtype)
        return State(
            pipeline_state=PlantState(x, k),
            obs=self._observation(x, k),
            reward=zero,
            done=zero,
            metrics={"loss": zero},
            info={},
        )

    def step(self, state: State, action: jax.Array) -> State:
        task = self.task
        x, k = state.pipeline_state
        t = self.time(k)
        u = self.input(action)
        r, y = task.reference(t), task.plant.h(x)
        if task.tick_loss is not None:
            d = task.disturbance(t)
            tick = Tick(t=t, x=x, y=y, y_meas=y, measured=jnp.asarray(True), u=u, r=r, d=d, x_hat=None)
            loss = task.tick_loss(tick, task.dt)
        else:
            loss = task.step_loss(t, r, y, u)
        x_next = hold_input(
            task.plant,
            x,
            u,
            t,
            jnp.asarray(task.dt / task.substeps, x.dtype),
            int(task.substeps),
            task.solver,
            task.disturbance,
            task.actuate,
        )
        failed = ~jnp.all(jnp.isfinite(x_next))
        if task.terminate is not None:
            failed = failed | task.terminate(x_next)
        done = jnp.maximum(state.done, failed.astype(state.done.dtype))
        k_next = k + 1
        obs = self._observation(x_next, k_next)
        return state.replace(
            pipeline_state=PlantState(x_next, k_next),
            obs=jnp.where(failed, 0.0, obs),
            reward=-loss.astype(state.reward.dtype),
            done=done,
            metrics={**state.metrics, "loss": loss.astype(state.reward.dtype)},
        )

    @classmethod
    def from_problem(
        cls,
        problem: Any,
        params: Any = None,
        draw: dict[str, Any] | None = None,
        *,
        u_low: Any = -1.0,
        u_high: Any = 1.0,
        x0_spread: Any = 0.0,
        observe: Observe | None = None,
        terminate: Callable[[jax.Array], jax.Array] | None = None,
    ) -> "PlantEnv":
        """The env of a :class:`~jaxsim.problem.Problem`'s scenario: the policy replaces its controller.

        ``build(params, draw)`` (default ``space.init`` and the nominal draw) gives the plant,
        reference, disturbance, ``x0``, the control period and substeps; the reward of a step is
        ``−objective.rate(tick, ts)`` (the objective must be additive: every term has a ``rate``).
        Actions in ``[−1, 1]`` map onto ``[u_low, u_high]`` (the problem does not know the input
        limits; by default actions are the inputs).  Sensor and estimator are not used (the policy
        observes ``observe(x, r, t)``, default :func:`observe_state_and_error`).
        """
        objective = getattr(problem, "objective", None)
        if objective is None:
            raise ValueError("problem: needs an objective of running costs (a from_loss problem has none)")
        if objective.rate is None:
            raise ValueError(
                "problem: its objective is not additive (a term has no rate, e.g. a soft overshoot); "
                "an env reward needs the increment of one tick"
            )
        sc = problem.scenario(problem.space.init if params is None else params, draw)
        timing = sc.timing
        _, substeps, _ = timing.resolve(None)
        loop = sc.loop
        task = Task(
            plant=loop.plant,
            step_loss=None,
            u_low=u_low,
            u_high=u_high,
            dt=timing.ts,
            x0=np.asarray(sc.x0, float),
            x0_spread=x0_spread,
            reference=loop.reference,
            observe=observe,
            substeps=substeps,
            solver=sc.solver,
            terminate=terminate,
            tick_loss=objective.rate,
            disturbance=loop.disturbance,
            actuate=loop.actuate,
        )
        return cls(task)

    @property
    def observation_size(self) -> int:
        shape = jax.eval_shape(self.reset, jax.random.PRNGKey(0)).obs.shape
        return int(shape[-1])

    @property
    def action_size(self) -> int:
        return self.task.plant.n_inputs

    @property
    def backend(self) -> str:
        return "jaxsim"

    # ------------------------------------------------------------------ helpers
    def time(self, k: jax.Array) -> jax.Array:
        """Tick time ``t_k = k·dt`` (s)."""
        return k * jnp.asarray(self.task.dt, float)

    def input(self, action: jax.Array) -> jax.Array:
        """Plant input ``(m,)`` for an action in ``[−1, 1]^m`` (clipped first)."""
        a = jnp.clip(jnp.asarray(action), -1.0, 1.0)
        return self._u_low + 0.5 * (a + 1.0) * (self._u_high - self._u_low)

    def action(self, u: jax.Array) -> jax.Array:
        """Inverse of :meth:`input`: the action that commands the input ``u`` (inside the limits)."""
        return 2.0 * (jnp.asarray(u) - self._u_low) / (self._u_high - self._u_low) - 1.0

    def _observation(self, x: jax.Array, k: jax.Array) -> jax.Array:
        t = self.time(k)
        return self._observe(x, self.task.reference(t), t)
