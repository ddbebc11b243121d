"""The Sylvester equation ``A X + X B = C``, batchable and differentiated implicitly.

Convention as ``scipy.linalg.solve_sylvester``; a unique solution exists iff
``λᵢ(A) + μⱼ(B) ≠ 0``.  Forward solve: Bartels–Stewart with two complex Schur decompositions;
derivatives through ``lax.custom_linear_solve`` (tangents solve the same equation, cotangents the
adjoint one ``Aᵀ Y + Y Bᵀ = C̄``), never through the Schur iterations.

A singular equation (some ``λᵢ(A) + μⱼ(B)`` zero to round-off, see
:mod:`jaxsim.control._bartels_stewart`) raises ``ValueError`` naming the pair on concrete input and
gives an all-NaN ``X`` inside ``jit``/``vmap``.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxsim.control import _bartels_stewart as bs
from jaxsim.core.validation import check_finite, check_square, is_concrete


def solve_sylvester(a: jax.Array, b: jax.Array, c: jax.Array) -> jax.Array:
    """Solve ``A X + X B = C`` for ``X``.

    Args:
        a: ``(n, n)`` real matrix.
        b: ``(k, k)`` real matrix.
        c: ``(n, k)`` right-hand side.

    Returns:
        ``X`` of shape ``(n, k)``; all NaN for a singular equation under ``jit``.

    Raises:
        ValueError: shapes, non-finite entries, or (concrete ``a``, ``b``) some ``λᵢ(A) + μⱼ(B)``
            zero to round-off (the message names the pair).
    """
    a, b, c = jnp.asarray(a), jnp.asarray(b), jnp.asarray(c)
    check_square("a", a)
    check_square("b", b)
    if c.shape != (a.shape[0], b.shape[0]):
        raise ValueError(f"c: expected shape ({a.shape[0]}, {b.shape[0]}), got {tuple(c.shape)}")
    for name, m in (("a", a), ("b", b), ("c", c)):
        check_finite(name, m)
    dtype = jnp.result_type(a, b, c, float)
    a, b, c = a.astype(dtype), b.astype(dtype), c.astype(dtype)
    concrete = is_concrete((a, b))
    if concrete:
        bs.check_unique("sylvester", a, b)
    x = jax.lax.custom_linear_solve(
        lambda x: a @ x + x @ b,
        c,
        solve=lambda _, rhs: bs.sylvester(a, b, rhs),
        transpose_solve=lambda _, rhs: bs.sylvester(a.T, b.T, rhs),
    )
    return x if concrete else bs.nan_if_singular("sylvester", x, a, b)
