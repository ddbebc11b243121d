"""Controllability and observability matrices: python-control's ``ctrb`` and ``obsv``."""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.validation import check_finite, check_positive_int, check_square


def _matrices(a: Any, other: Any, names: tuple[str, str], rows: bool) -> tuple[jax.Array, jax.Array]:
    a = jnp.atleast_2d(jnp.asarray(a, dtype=float))
    check_square(names[0], a)
    n = a.shape[0]
    m = jnp.asarray(other, dtype=float)
    if m.ndim <= 1:
        m = m.reshape((1, -1) if rows else (-1, 1))
    if m.ndim != 2 or (m.shape[1] if rows else m.shape[0]) != n:
        want = f"(p, {n})" if rows else f"({n}, m)"
        raise ValueError(f"{names[1]}: expected shape {want}, got {tuple(m.shape)}")
    check_finite(names[0], a)
    check_finite(names[1], m)
    return a, m


def _powers(a: jax.Array, m: jax.Array, t: int, left: bool) -> list[jax.Array]:
    blocks = [m]
    for _ in range(t - 1):
        blocks.append(blocks[-1] @ a if left else a @ blocks[-1])
    return blocks


def ctrb(A: Any, B: Any, t: int | None = None) -> jax.Array:  # noqa: N803
    """``[B, AB, …, A^{t−1}B]``, shape ``(n, t·m)`` (``t = n`` by default)."""
    a, b = _matrices(A, B, ("A", "B"), rows=False)
    t = a.shape[0] if t is None else check_positive_int("t", t)
    return jnp.concatenate(_powers(a, b, t, left=False), axis=1)


def obsv(A: Any, C: Any, t: int | None = None) -> jax.Array:  # noqa: N803
    """``[C; CA; …; CA^{t−1}]``, shape ``(t·p, n)`` (``t = n`` by default)."""
    a, c = _matrices(A, C, ("A", "C"), rows=True)
    t = a.shape[0] if t is None else check_positive_int("t", t)
    return jnp.concatenate(_powers(a, c, t, left=True), axis=0)
