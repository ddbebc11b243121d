"""A plant of the toolkit as a brax environment (``brax.envs.base.Env``).

One generic wrapper, :class:`PlantEnv`, built from a :class:`Task` — the plant (its pure
``dynamics``/``output`` functions), the control period, the solver, the reference signal, the input
limits, the per-step loss and the observation.  The per-plant modules of this package
(:mod:`jaxsim.envs.second_order`, :mod:`jaxsim.envs.trms`, ...) only build tasks.

One env step is one controller tick of :func:`jaxsim.core.rollout.simulate` without sensor,
estimator or disturbance: at tick ``k`` (time ``t_k = k·dt``) the action ``a ∈ [−1, 1]^m`` is mapped
affinely onto ``[u_low, u_high]`` (``a = −1 → u_low``, ``a = +1 → u_high``; actions outside are
clipped), the reward is ``−step_loss(t_k, r(t_k), y_k, u_k)``, and the plant integrates ``substeps``
solver steps with ``u_k`` held (:func:`jaxsim.core.rollout.hold_input`, the same plant step as
``simulate``).  The observation is ``observe(x_{k+1}, r(t_{k+1}), t_{k+1})``.

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
from jaxsim.core.rollout import hold_input
from jaxsim.core.signals import Constant
from jaxsim.core.system import Plant
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
            starting at ``t``; the reward is its negative.
        u_low, u_high: ``(m,)`` input limits onto which actions in ``[−1, 1]`` are mapped.
        dt: control period (one env step).
        x0: ``(n,)`` nominal initial state.
        x0_spread: ``(n,)`` or scalar half-width of the uniform perturbation of ``x0`` on reset.
        reference: ``r(t) -> (k,)`` signal (default: zero).
        observe: ``(x, r, t) -> (d,)`` observation (default :func:`observe_state_and_error`).
        substeps: solver steps per control period (integration step ``dt/substeps``).
        solver: fixed-step solver (default RK4).
        terminate: optional ``x -> bool`` failure condition (ends the episode).
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

    def __post_init__(self):
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
        return State(pipeline_state=PlantState(x, k), obs=self._observation(x, k), reward=zero, done=zero,
                     metrics={"loss": zero}, info={})

    def step(self, state: State, action: jax.Array) -> State:
        task = self.task
        x, k = state.pipeline_state
        t = self.time(k)
        u = self.input(action)
        loss = task.step_loss(t, task.reference(t), task.plant.h(x), u)
        x_next = hold_input(task.plant, x, u, t, jnp.asarray(task.dt / task.substeps, x.dtype),
                            int(task.substeps), task.solver)
        failed = ~jnp.all(jnp.isfinite(x_next))
        if task.terminate is not None:
            failed = failed | task.terminate(x_next)
        done = jnp.maximum(state.done, failed.astype(state.done.dtype))
        k_next = k + 1
        obs = self._observation(x_next, k_next)
        return state.replace(pipeline_state=PlantState(x_next, k_next), obs=jnp.where(failed, 0.0, obs),
                             reward=-loss.astype(state.reward.dtype), done=done,
                             metrics={**state.metrics, "loss": loss.astype(state.reward.dtype)})

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
