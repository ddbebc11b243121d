"""Pose-regulation env for the 6-DOF AUV of seed 002 (:mod:`jaxsim.plants.auv`).

Task: drive the AUV from rest at the origin to a fixed pose ``η* = (x, y, z, φ, θ, ψ)`` and hold it.
Reward ``−(‖η* − η‖² + ρ ‖τ/τ_scale‖²)·dt`` per step — the form of the ``auv_formation`` study's
tuning loss (squared tracking error + ρ·(τ/100 N)², ρ = 1e-3) with a fixed target instead of the
leader (a brax env has no leader predictor).  Actions in ``[−1, 1]⁶`` map to ``±tau_max``
(assumed ±100 N / N·m: the paper has no thruster model or saturation).  Observation
``(x (12,), r − x (12,))`` with ``r = (η*, 0)``; euler-angle errors are not wrapped (targets stay
well inside ±π).
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.signals import Constant
from jaxsim.envs.plant_env import PlantEnv, Task
from jaxsim.plants.auv import N_STATES, AUVParams, auv_plant

DEFAULT_TARGET = (2.0, 1.0, 0.5, 0.0, 0.0, 0.5)  # m, m, m (down), rad, rad, rad


def pose_loss(dt: float, effort_weight: float, tau_scale: float):
    """``(t, r, y, u) -> (‖r[:6] − y[:6]‖² + ρ ‖u/τ_scale‖²)·dt``."""

    def loss(t: jax.Array, r: jax.Array, y: jax.Array, u: jax.Array) -> jax.Array:
        return (jnp.sum((r[:6] - y[:6]) ** 2) + effort_weight * jnp.sum((u / tau_scale) ** 2)) * dt

    return loss


def auv_env(
    params: AUVParams | None = None,
    target: Any = DEFAULT_TARGET,
    tau_max: float = 100.0,
    effort_weight: float = 1e-3,
    dt: float = 0.05,
    substeps: int = 5,
    x0_spread: Any = 0.0,
) -> PlantEnv:
    """Env of the AUV regulating to ``target`` (control period ``dt`` s, RK4 at ``dt/substeps``)."""
    target = jnp.asarray(target, float)
    if target.shape != (6,):
        raise ValueError(f"target: expected a pose of shape (6,), got {tuple(target.shape)}")
    r = jnp.concatenate([target, jnp.zeros(6)])
    return PlantEnv(
        Task(
            plant=auv_plant(params),
            step_loss=pose_loss(dt, effort_weight, 100.0),
            u_low=-tau_max,
            u_high=tau_max,
            dt=dt,
            x0=jnp.zeros(N_STATES),
            x0_spread=x0_spread,
            reference=Constant(r),
            substeps=substeps,
        )
    )
