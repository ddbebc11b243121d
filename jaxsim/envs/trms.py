"""The TRMS tracking task of the ``trms_lqr_tuning`` study as a brax env.

Scenario, trim point, references and per-step loss are the study's own
(:class:`jaxsim.problem.trms.TRMSTuning`, reused, not re-derived): the reward of a step is
``−TRMSTuning.step_loss`` — per-step ITAE + ρ·energy + κ·saturation excess over one controller
period — so ``−Σ rewards`` over the horizon is the study's loss of that simulation without the
stability penalty (which only applies to linear designs).

Differences from the study's LQG loop, by design of an RL benchmark: the policy observes the true
state (no sensor noise, no observer), and actions in ``[−1, 1]²`` map to ``[−u_max, u_max]`` V.
Observation ``(x − x_eq (7,), r − y (2,))``: angles and rates, motor states, tracking error.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.envs.plant_env import PlantEnv, Task
from jaxsim.plants.trms import trms_plant
from jaxsim.problem.trms import Scenario, TRMSTuning


def trms_task(problem: Any = None, exact_friction: bool = False, x0_spread: Any = 0.0) -> Task:
    """The :class:`~jaxsim.envs.plant_env.Task` of a ``TRMSTuning`` problem (default: the study's
    default scenario); ``x0_spread`` perturbs the trim state on reset (e.g. ``(0.05, 0.05, 0, …)``)."""
    if problem is None:
        problem = TRMSTuning(Scenario())
    plant = trms_plant(problem.plant_params(exact_friction))
    u_max = plant.params.u_max
    x_eq = problem.x_eq

    def step_loss(t: jax.Array, r: jax.Array, y: jax.Array, u: jax.Array) -> jax.Array:
        return problem.step_loss(t, r, y, u, u_max)

    def observe(x: jax.Array, r: jax.Array, t: jax.Array) -> jax.Array:
        return jnp.concatenate([x - x_eq, r - plant.h(x)])

    timing = problem.timing  # the study's own periods, so env steps are the study's ticks
    _, substeps, _ = timing.resolve(None)
    return Task(
        plant=plant,
        step_loss=step_loss,
        u_low=-u_max,
        u_high=u_max,
        dt=timing.ts,
        substeps=substeps,
        x0=x_eq,
        x0_spread=x0_spread,
        reference=problem.reference,
        observe=observe,
    )


def trms_env(problem: Any = None, exact_friction: bool = False, x0_spread: Any = 0.0) -> PlantEnv:
    """:class:`~jaxsim.envs.plant_env.PlantEnv` of :func:`trms_task`."""
    return PlantEnv(trms_task(problem, exact_friction, x0_spread))
