"""Coulomb (dry) friction stepped exactly and event-free: the implicit catch-up step.

Over a step of length ``dt`` a sliding velocity loses at most ``b = dt·f_max`` to friction
(``f_max``: the friction force over the mass, a deceleration).  Given the velocity ``s`` the body
would have at the end of the step without friction, the friction impulse is the projection of ``s``
on ``[−b, b]``, and the new velocity is ``s − clip(s, −b, b)``: zero (stick) when ``|s| ≤ b``, else
``s`` reduced by the full friction.  This is the backward-Euler step of the set-valued law
``v̇ ∈ a − f_max·Sgn(v)`` (Moreau's catch-up); it needs no event detection and is exact whenever the
velocity keeps its sign over the step or comes to rest in it.  ``exact=False`` replaces the projection
by ``b·tanh(s/b)`` (smooth, for gradients through sticking; the same scale, no extra parameter).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp


def friction_impulse(s_free: jax.Array, b: jax.Array, exact: bool = True) -> jax.Array:
    """The velocity taken by friction in one step: ``clip(s_free, −b, b)`` (``b·tanh(s_free/b)`` when
    ``exact=False``).  ``s_free``: the end-of-step velocity without friction; ``b = dt·f_max ≥ 0``."""
    return jnp.clip(s_free, -b, b) if exact else b * jnp.tanh(s_free / b)


def catch_up(s_free: jax.Array, b: jax.Array, exact: bool = True) -> jax.Array:
    """The end-of-step velocity under Coulomb friction: ``s_free − friction_impulse(s_free, b)``."""
    return s_free - friction_impulse(s_free, b, exact)


def slide(v0: jax.Array, decel: jax.Array, dt: jax.Array) -> tuple[jax.Array, jax.Array]:
    """A body starting at velocity ``v0`` with no force but Coulomb friction (deceleration ``decel > 0``)
    for ``dt``: ``(displacement, end velocity)``, exact — it slides for ``min(|v0|/decel, dt)`` and stays."""
    t = jnp.minimum(jnp.abs(v0) / decel, dt)
    return v0 * t - jnp.sign(v0) * 0.5 * decel * t * t, catch_up(v0, decel * dt)


__all__ = ["friction_impulse", "catch_up", "slide"]
