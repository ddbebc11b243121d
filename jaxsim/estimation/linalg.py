"""Small-matrix Cholesky factorisation and triangular solves, unrolled for sizes ≤ ``UNROLL_MAX``.

Kalman filters factor tiny innovation covariances (``p`` = 1…4) at every step of every run.  Under
``vmap`` on a CPU, XLA calls LAPACK once per batch element for ``cholesky``/``triangular_solve``;
unrolled scalar formulas instead become element-wise operations over the whole batch (SIMD) and
are several times faster.  Larger matrices fall through to ``jnp.linalg``/``jax.scipy.linalg``.
Results equal LAPACK's to rounding.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

UNROLL_MAX = 4


def cholesky(a: jax.Array) -> jax.Array:
    """Lower Cholesky factor of a symmetric positive-definite ``(k, k)`` matrix."""
    k = a.shape[-1]
    if k > UNROLL_MAX:
        return jnp.linalg.cholesky(a)
    low = [[None] * k for _ in range(k)]
    for j in range(k):
        d = a[..., j, j] - sum((low[j][m] ** 2 for m in range(j)), jnp.zeros_like(a[..., j, j]))
        low[j][j] = jnp.sqrt(d)
        for i in range(j + 1, k):
            s = a[..., i, j] - sum((low[i][m] * low[j][m] for m in range(j)), jnp.zeros_like(a[..., i, j]))
            low[i][j] = s / low[j][j]
    zero = jnp.zeros_like(a[..., 0, 0])
    return jnp.stack([jnp.stack([low[i][j] if j <= i else zero for j in range(k)], axis=-1) for i in range(k)], axis=-2)


def solve_lower(low: jax.Array, b: jax.Array) -> jax.Array:
    """``L⁻¹ b`` for lower-triangular ``L (k, k)`` and ``b (k,)`` or ``(k, r)``."""
    k = low.shape[-1]
    if k > UNROLL_MAX:
        return jax.scipy.linalg.solve_triangular(low, b, lower=True)
    vec = b.ndim == 1
    bb = b[:, None] if vec else b
    rows = []
    for i in range(k):
        s = bb[i] - sum((low[i, m] * rows[m] for m in range(i)), jnp.zeros_like(bb[i]))
        rows.append(s / low[i, i])
    x = jnp.stack(rows)
    return x[:, 0] if vec else x


def solve_upper_transposed(low: jax.Array, b: jax.Array) -> jax.Array:
    """``L⁻ᵀ b`` for lower-triangular ``L (k, k)``."""
    k = low.shape[-1]
    if k > UNROLL_MAX:
        return jax.scipy.linalg.solve_triangular(low, b, lower=True, trans=1)
    vec = b.ndim == 1
    bb = b[:, None] if vec else b
    rows: list = [None] * k
    for i in reversed(range(k)):
        s = bb[i] - sum((low[m, i] * rows[m] for m in range(i + 1, k)), jnp.zeros_like(bb[i]))
        rows[i] = s / low[i, i]
    x = jnp.stack(rows)
    return x[:, 0] if vec else x


def cho_solve(low: jax.Array, b: jax.Array) -> jax.Array:
    """``A⁻¹ b`` given the lower Cholesky factor ``L`` of ``A``."""
    return solve_upper_transposed(low, solve_lower(low, b))


def matmul(a: jax.Array, b: jax.Array) -> jax.Array:
    """``a @ b`` for small matrices as a broadcast multiply-and-sum (fuses into element-wise loops
    over a vmapped batch instead of one tiny GEMM per batch element); large ones use ``@``."""
    if a.ndim != 2 or b.ndim != 2 or max(a.shape + b.shape) > 2 * UNROLL_MAX:
        return a @ b
    return jnp.sum(a[:, :, None] * b[None, :, :], axis=1)
