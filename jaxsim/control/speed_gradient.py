"""Adaptive speed-gradient energy control of pendulum-like axes (seed 004 #15, spec ``seed004_part1.md`` §B2).

Each controlled axis is the reduced model (1)/(2) of the spec (reconstructed; the paper's symbols are lost)::

    q̈ = −a1·q̇ − a0·sin q + b·w·cos q          (a0 known, a1 and b unknown and positive)

with energy (4)/(5) ``V = q̇²/2 + a0(1 − cos q)`` and goal ``Q = ½(V − V*)²`` summed over the axes (6).
The speed-gradient laws (7)–(10) (reconstructed) are, per axis::

    w      = [â·q̇ − γ1·(V − V*)·q̇] / cos q
    dâ/dt  = −γ2·(V − V*)·q̇²

``â`` compensates the damping ``a1·q̇`` (its ideal value ``a1/b``).  On the reduced model the function
``L = Q + (b/(2γ2))(â − a1/b)²`` has ``dL/dt = −γ1·b·(V − V*)²·q̇² ≤ 0`` (:func:`lyapunov`).

Arrays: ``q, qd, a_hat`` are ``(n_axes,)`` (rad, rad/s, virtual-input units per rad/s); the gains are
broadcast against them.  ``cos q`` is floored at ``cos_floor`` in magnitude (the law is singular at
``q = ±90°``); the floor is a documented departure from (7)/(9).
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.pytree import pytree_dataclass
from jaxsim.core.validation import check_positive


@pytree_dataclass
class SpeedGradientGains:
    """Gains of laws (7)–(10), one entry per axis (or scalars).  No paper values exist (spec §B2)."""

    gamma1: Any = 1.0  # virtual-input units per (energy · rad/s): proportional speed-gradient gain
    gamma2: Any = 1.0  # adaptation gain of â
    v_star: Any = 0.0  # target energy V* (rad²/s²)
    a0: Any = 1.0  # known pendulum coefficient a0 (1/s²)
    cos_floor: Any = 0.1  # |cos q| floor of the division in (7)/(9)


def validate_gains(g: SpeedGradientGains) -> None:
    """Raise ``ValueError`` naming the offending field (concrete inputs only)."""
    for name in ("gamma1", "gamma2", "cos_floor"):
        check_positive(name, getattr(g, name))
    for name in ("v_star", "a0"):
        check_positive(name, getattr(g, name), allow_zero=True)


def energy(q: jax.Array, qd: jax.Array, a0: Any) -> jax.Array:
    """Pendulum energy (4)/(5) ``V = q̇²/2 + a0(1 − cos q)`` per axis (rad²/s²)."""
    return 0.5 * qd**2 + a0 * (1.0 - jnp.cos(q))


def amplitude(v: jax.Array, a0: Any) -> jax.Array:
    """Swing amplitude (rad) of energy ``v`` on the undamped pendulum: ``arccos(1 − v/a0)`` (``v ≤ 2a0``)."""
    return jnp.arccos(jnp.clip(1.0 - v / a0, -1.0, 1.0))


def _safe_cos(q: jax.Array, floor: Any) -> jax.Array:
    c = jnp.cos(q)
    return jnp.where(c >= 0, jnp.maximum(c, floor), jnp.minimum(c, -floor))


def control(g: SpeedGradientGains, q: jax.Array, qd: jax.Array, a_hat: jax.Array) -> jax.Array:
    """Virtual inputs (7)/(9) ``w = [â q̇ − γ1 (V − V*) q̇] / cos q`` per axis."""
    err = energy(q, qd, g.a0) - g.v_star
    return (a_hat * qd - g.gamma1 * err * qd) / _safe_cos(q, g.cos_floor)


def adaptation(g: SpeedGradientGains, q: jax.Array, qd: jax.Array) -> jax.Array:
    """Adaptation laws (8)/(10) ``dâ/dt = −γ2 (V − V*) q̇²`` per axis."""
    return -g.gamma2 * (energy(q, qd, g.a0) - g.v_star) * qd**2


def reduced_dynamics(g: SpeedGradientGains, a1: Any, b: Any, x: jax.Array, t: jax.Array | None = None) -> jax.Array:
    """Closed loop of the reduced model (1)–(2) with laws (7)–(10).

    ``x = (q (n,), q̇ (n,), â (n,))`` flattened to ``(3n,)``; ``a1, b`` the true damping and input gain.
    """
    n = x.shape[-1] // 3
    q, qd, a_hat = x[:n], x[n : 2 * n], x[2 * n :]
    w = control(g, q, qd, a_hat)
    qdd = -a1 * qd - g.a0 * jnp.sin(q) + b * w * jnp.cos(q)
    return jnp.concatenate([qd, qdd, adaptation(g, q, qd)])


def lyapunov(g: SpeedGradientGains, a1: Any, b: Any, x: jax.Array) -> jax.Array:
    """``L = Σ_axes ½(V − V*)² + (b/(2γ2))(â − a1/b)²`` for a reduced-model state ``x (3n,)`` (or ``(…, 3n)``)."""
    n = x.shape[-1] // 3
    q, qd, a_hat = x[..., :n], x[..., n : 2 * n], x[..., 2 * n :]
    err = energy(q, qd, g.a0) - g.v_star
    return jnp.sum(0.5 * err**2 + b / (2.0 * g.gamma2) * (a_hat - a1 / b) ** 2, axis=-1)
