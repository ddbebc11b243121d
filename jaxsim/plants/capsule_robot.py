"""Capsule robot: a body on a rough plane moved by an internal mass (seed 004 #1, Chernousko's
lecture; spec part 1 §B5).

A body of mass ``M`` slides along a line with Coulomb friction (coefficient ``k``); inside it a mass
``m`` moves with the relative coordinate ``ξ ∈ [0, L]`` imposed by a drive.  Momentum balance::

    (M + m)·ẍ + m·ξ̈ = F,      |F| ≤ k(M + m)g,      F = −k(M + m)g·sgn ẋ while sliding

so the body velocity ``w = ẋ`` obeys ``ẇ = −μ·ξ̈ + f`` with ``|f| ≤ kg`` and ``μ = m/(M + m)``.

The input is the relative velocity ``u = ξ̇``, held over each step of length ``dt`` (velocity
control; acceleration control is its limit as a staircase with jumps ``ξ̈·dt``).  At the start of a
step ``u`` jumps by ``Δu``: the internal impulse changes ``w`` by ``−μ·Δu`` (friction, being bounded,
gives no impulse); then the body slides under friction alone, stopping if it can.  :func:`step` does
both exactly (:mod:`jaxsim.core.dry_friction`), so for piecewise-constant ``u`` the rollout is exact,
event-free and differentiable (stick–slip included).  A jump ``Δu`` with ``μ|Δu| ≤ kg·dt`` leaves a
body at rest in place: a relative acceleration up to ``kg/μ`` (:func:`hold_acceleration`) never
moves a resting body.

Natural units: speed ``√(μkgL)`` (:func:`speed_unit`), time ``√(μL/(kg))`` (:func:`time_unit`).  In
them the equations lose ``μ``, ``k``, ``g`` and ``L`` entirely (body jump ``−Δu``, deceleration 1,
stroke 1 when ``u`` is measured in ``L`` per time unit), so every optimal average speed under
constraints stated in these units is a pure number times ``√(μkgL)``.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.dry_friction import slide
from jaxsim.core.pytree import pytree_dataclass
from jaxsim.core.validation import check_positive_int


@pytree_dataclass
class Params:
    """Body mass ``M`` (kg), internal mass ``m`` (kg), Coulomb coefficient ``k``, stroke ``L`` (m),
    gravity ``g`` (m/s²).  Defaults: the spec's example values (assumed: the lecture gives none)."""

    M: Any = 1.0
    m: Any = 0.2
    k: Any = 0.3
    L: Any = 0.05
    g: Any = 9.81


def mass_ratio(p: Params) -> Any:
    """``μ = m/(M + m)``."""
    return p.m / (p.M + p.m)


def speed_unit(p: Params) -> Any:
    """``√(μkgL)`` (m/s): the scale of every optimal average body speed."""
    return jnp.sqrt(mass_ratio(p) * p.k * p.g * p.L)


def time_unit(p: Params) -> Any:
    """``√(μL/(kg))`` (s)."""
    return jnp.sqrt(mass_ratio(p) * p.L / (p.k * p.g))


def mass_speed_unit(p: Params) -> Any:
    """``√(kgL/μ)`` (m/s): the internal mass's speed scale (stroke per time unit)."""
    return jnp.sqrt(p.k * p.g * p.L / mass_ratio(p))


def hold_acceleration(p: Params) -> Any:
    """``kg/μ`` (m/s²): the largest relative acceleration a resting body withstands."""
    return p.k * p.g / mass_ratio(p)


def step(p: Params, state: jax.Array, du: jax.Array, dt: Any) -> jax.Array:
    """``state = [x, w]`` (m, m/s) → the state one step later, the relative velocity having jumped by
    ``du`` (m/s) at the step's start.  Exact: impulse ``−μ·du``, then Coulomb sliding for ``dt``."""
    dx, w = slide(state[1] - mass_ratio(p) * du, p.k * p.g, dt)
    return jnp.stack([state[0] + dx, w])


def rollout(p: Params, u: jax.Array, dt: Any, u_before: Any = 0.0, w0: Any = 0.0) -> jax.Array:
    """Body states ``(N, 2)`` (``[x, w]`` at each step's end) under the relative velocities ``u (N,)``
    held over steps of ``dt``, from ``x = 0``, body velocity ``w0`` and relative velocity ``u_before``."""
    du = jnp.diff(u, prepend=jnp.asarray(u_before, u.dtype)[None])

    def tick(s, d):
        s = step(p, s, d, dt)
        return s, s

    return jax.lax.scan(tick, jnp.stack([jnp.zeros((), u.dtype), jnp.asarray(w0, u.dtype)]), du)[1]


def periodic_speed(p: Params, u: jax.Array, dt: Any, periods: int = 3) -> jax.Array:
    """Average body speed (m/s) over the last of ``periods`` repetitions of the periodic gait ``u (N,)``
    (the body starting at rest, the mass moving at ``u[-1]`` as if a period had just ended)."""
    periods = check_positive_int("periods", periods)
    n = u.shape[0]
    states = rollout(p, jnp.tile(u, periods), dt, u_before=u[-1])
    x_end, x_start = states[-1, 0], states[-n - 1, 0] if periods > 1 else 0.0
    return (x_end - x_start) / (n * dt)


__all__ = [
    "Params",
    "mass_ratio",
    "speed_unit",
    "time_unit",
    "mass_speed_unit",
    "hold_acceleration",
    "step",
    "rollout",
    "periodic_speed",
]
