"""Step-tracking envs for the second-order plants of the fuzzy-PID paper
(:mod:`jaxsim.plants.second_order`): unit step reference, reward = −ITAE increment
``t·|r − y|·dt`` (the loss of the paper's PID studies), input ``u ∈ [−u_max, u_max]``.

Observation ``(y, ẏ, r − y)``; episodes start at rest (``x0 = 0``) unless ``x0_spread`` is given.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.metrics import itae_integrand
from jaxsim.core.signals import Step
from jaxsim.envs.plant_env import PlantEnv, Task
from jaxsim.plants.second_order import AstaticParams, StaticParams, astatic_plant, static_plant


def itae_step(dt: float):
    """``(t, r, y, u) -> t·Σ|r − y|·dt``: the ITAE accrued over one period (rectangle rule)."""

    def loss(t: jax.Array, r: jax.Array, y: jax.Array, u: jax.Array) -> jax.Array:
        return jnp.sum(itae_integrand(t, r - y)) * dt

    return loss


def _task(plant, amplitude: float, u_max: float, dt: float, substeps: int, x0_spread: Any) -> Task:
    return Task(
        plant=plant,
        step_loss=itae_step(dt),
        u_low=-u_max,
        u_high=u_max,
        dt=dt,
        x0=jnp.zeros(2),
        x0_spread=x0_spread,
        reference=Step(amplitude),
        substeps=substeps,
    )


def static_second_order_env(
    params: StaticParams | None = None,
    amplitude: float = 1.0,
    u_max: float = 10.0,
    dt: float = 0.01,
    substeps: int = 1,
    x0_spread: Any = 0.0,
) -> PlantEnv:
    """Env of ``K/((T1 s + 1)(T2 s + 1))`` (paper defaults ``K = 2, T1 = 0.1, T2 = 0.5``)."""
    return PlantEnv(_task(static_plant(params), amplitude, u_max, dt, substeps, x0_spread))


def astatic_second_order_env(
    params: AstaticParams | None = None,
    amplitude: float = 1.0,
    u_max: float = 10.0,
    dt: float = 0.01,
    substeps: int = 1,
    x0_spread: Any = 0.0,
) -> PlantEnv:
    """Env of ``K/(s (T s + 1))`` (paper defaults ``K = 2, T = 0.1``)."""
    return PlantEnv(_task(astatic_plant(params), amplitude, u_max, dt, substeps, x0_spread))
