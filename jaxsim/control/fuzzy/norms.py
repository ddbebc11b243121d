"""Triangular norms (fuzzy AND) and conorms (fuzzy OR), pairwise and as reductions.

* t-norms: ``"min"`` (Zadeh) and ``"product"`` (algebraic product);
* s-norms: ``"max"`` (Zadeh) and ``"probor"`` (probabilistic sum ``a + b − a·b``).

Reductions fold a norm along an axis; an empty axis gives the norm's identity (1 for a t-norm,
0 for an s-norm).
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

T_NORMS = ("min", "product")
S_NORMS = ("max", "probor")


def check_tnorm(name: str, value: str) -> None:
    if value not in T_NORMS:
        raise ValueError(f"{name}: t-norm must be one of {T_NORMS}, got {value!r}")


def check_snorm(name: str, value: str) -> None:
    if value not in S_NORMS:
        raise ValueError(f"{name}: s-norm must be one of {S_NORMS}, got {value!r}")


def tnorm(kind: str, a: Any, b: Any) -> jax.Array:
    """``T(a, b)``: ``min(a, b)`` or ``a·b``."""
    check_tnorm("kind", kind)
    return jnp.minimum(a, b) if kind == "min" else jnp.asarray(a) * b


def snorm(kind: str, a: Any, b: Any) -> jax.Array:
    """``S(a, b)``: ``max(a, b)`` or ``a + b − a·b``."""
    check_snorm("kind", kind)
    return jnp.maximum(a, b) if kind == "max" else jnp.asarray(a) + b - jnp.asarray(a) * b


def tnorm_reduce(kind: str, x: Any, axis: int = -1) -> jax.Array:
    """Fold the t-norm along ``axis`` (identity 1)."""
    check_tnorm("kind", kind)
    x = jnp.asarray(x)
    return jnp.min(x, axis=axis, initial=1.0) if kind == "min" else jnp.prod(x, axis=axis)


def snorm_reduce(kind: str, x: Any, axis: int = -1) -> jax.Array:
    """Fold the s-norm along ``axis`` (identity 0)."""
    check_snorm("kind", kind)
    x = jnp.asarray(x)
    return jnp.max(x, axis=axis, initial=0.0) if kind == "max" else 1.0 - jnp.prod(1.0 - x, axis=axis)
