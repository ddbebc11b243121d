"""Euclidean norm with a finite gradient at the origin.

``jnp.sqrt(jnp.sum(x²))`` has gradient ``x/‖x‖ = 0/0 = NaN`` at ``x = 0``.  The "double where"
feeds ``sqrt`` a harmless 1 where the squared norm is 0 and returns 0 there, so the value is exact
everywhere and the gradient at the origin is the zero subgradient.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp


def safe_norm(x: Any, axis: int = -1) -> jax.Array:
    """``‖x‖₂`` along ``axis`` (same units as ``x``); gradient 0, not NaN, where ``x = 0``."""
    x = jnp.asarray(x)
    sq = jnp.sum(x * x, axis=axis)
    nonzero = sq > 0
    return jnp.where(nonzero, jnp.sqrt(jnp.where(nonzero, sq, 1.0)), 0.0)
