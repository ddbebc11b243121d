"""Dynamic bicycle model with linear tyres at constant forward speed (seed 004 part 1 §B6).

State ``x = [X, Y, ψ, v_y, r]`` (m, m, rad, m/s, rad/s): position in the navigation frame, heading,
body lateral velocity, yaw rate.  Input ``u = [δ, M_z]``: front steering angle (rad) and the yaw
moment of differential braking (N·m).  Forward speed ``V`` (m/s) is held constant.  Tyres are linear,
``F_yf = C_f α_f``, ``F_yr = C_r α_r`` with ``α_f = δ − (v_y + l_f r)/V``, ``α_r = −(v_y − l_r r)/V``.

Parameters are ASSUMED (the paper used IPG CarMaker; none are given): a mid-size car, spec §B6
"m ≈ 1500 kg, I_z ≈ 2500 kg·m², l_f/l_r ≈ 1.2/1.6 m, cornering stiffness ≈ 8e4 N/rad".
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.pytree import pytree_dataclass


@pytree_dataclass
class BicycleParams:
    """``m`` kg, ``Iz`` kg·m², ``lf``, ``lr`` m, ``Cf``, ``Cr`` N/rad, ``V`` m/s."""

    m: Any = 1500.0
    Iz: Any = 2500.0
    lf: Any = 1.2
    lr: Any = 1.6
    Cf: Any = 8.0e4
    Cr: Any = 8.0e4
    V: Any = 10.0


def tyre_forces(p: BicycleParams, x: jax.Array, delta: jax.Array) -> tuple[jax.Array, jax.Array]:
    """Front and rear lateral tyre forces (N) of the linear tyre."""
    vy, r = x[3], x[4]
    return p.Cf * (delta - (vy + p.lf * r) / p.V), -p.Cr * (vy - p.lr * r) / p.V


def dynamics(p: BicycleParams, x: jax.Array, u: jax.Array, t: Any = 0.0) -> jax.Array:
    """``Ẋ = V cos ψ − v_y sin ψ``, ``Ẏ = V sin ψ + v_y cos ψ``, ``ψ̇ = r``,
    ``m (v̇_y + V r) = F_yf + F_yr``, ``I_z ṙ = l_f F_yf − l_r F_yr + M_z``."""
    psi, vy, r = x[2], x[3], x[4]
    ff, fr = tyre_forces(p, x, u[0])
    return jnp.stack(
        [
            p.V * jnp.cos(psi) - vy * jnp.sin(psi),
            p.V * jnp.sin(psi) + vy * jnp.cos(psi),
            r,
            (ff + fr) / p.m - p.V * r,
            (p.lf * ff - p.lr * fr + u[1]) / p.Iz,
        ]
    )


def rk4_step(p: BicycleParams, x: jax.Array, u: jax.Array, dt: float) -> jax.Array:
    """One RK4 step of :func:`dynamics` with the input held."""
    k1 = dynamics(p, x, u)
    k2 = dynamics(p, x + 0.5 * dt * k1, u)
    k3 = dynamics(p, x + 0.5 * dt * k2, u)
    k4 = dynamics(p, x + dt * k3, u)
    return x + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)


def understeer_gradient(p: BicycleParams) -> jax.Array:
    """``K_us = m/L·(l_r/C_f − l_f/C_r)`` (rad·s²/m)."""
    L = p.lf + p.lr
    return p.m / L * (p.lr / p.Cf - p.lf / p.Cr)


def steady_yaw_rate(p: BicycleParams, delta: Any) -> jax.Array:
    """Steady-state cornering ``r = V/(L + K_us V²)·δ`` (rad/s)."""
    return p.V / (p.lf + p.lr + understeer_gradient(p) * p.V**2) * delta
