"""Continuous and discrete Lyapunov equations, batchable and differentiated implicitly.

Conventions are SciPy's (``scipy.linalg.solve_continuous_lyapunov`` / ``solve_discrete_lyapunov``):

* continuous: ``A X + X Aᵀ = Q``; a unique solution exists iff ``λᵢ(A) + λⱼ(A) ≠ 0`` for all i, j;
* discrete (Stein): ``A X Aᵀ − X + Q = 0``; unique iff ``λᵢ(A) λⱼ(A) ≠ 1``.

Forward solve: Bartels–Stewart in complex Schur coordinates (``O(n³)``, any spectrum satisfying
the condition above; LAPACK Schur, so CPU).  Derivatives: the solution is defined through
``lax.custom_linear_solve`` — the tangent solves the same equation with the differentiated
right-hand side, and the cotangent solves the *adjoint* equation (``A`` replaced by ``Aᵀ``); the
Schur iterations are never differentiated.  Works under ``jit``, ``vmap``, ``grad``, ``jacfwd``.

Singular equations (``A = 0``, eigenvalues ``±iω`` or a zero eigenvalue in the continuous case, a
reciprocal pair ``λ_i λ_j = 1`` — e.g. eigenvalues on the unit circle — in the discrete case; tested
to round-off, see :mod:`jaxsim.control._bartels_stewart`) raise ``ValueError`` naming the eigenvalue
pair when ``a`` is concrete; inside ``jit``/``vmap`` they return an all-NaN ``X``.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxsim.control import _bartels_stewart as bs
from jaxsim.core.validation import check_finite, check_square, is_concrete


def _check(kind: str, a: jax.Array, q: jax.Array) -> tuple[jax.Array, jax.Array]:
    a = jnp.asarray(a)
    q = jnp.asarray(q)
    check_square("a", a)
    if q.shape != a.shape:
        raise ValueError(f"q: expected shape {tuple(a.shape)} to match a, got {tuple(q.shape)}")
    check_finite("a", a)
    check_finite("q", q)
    dtype = jnp.result_type(a, q, float)
    a, q = a.astype(dtype), q.astype(dtype)
    if is_concrete(a):
        bs.check_unique(kind, a)
    return a, q


def solve_continuous_lyapunov(a: jax.Array, q: jax.Array) -> jax.Array:
    """Solve ``A X + X Aᵀ = Q`` for ``X``.

    Args:
        a: ``(n, n)`` real matrix.
        q: ``(n, n)`` right-hand side (symmetric ``q`` gives a symmetric ``X``).

    Returns:
        ``X`` of shape ``(n, n)``; all NaN for a singular equation under ``jit``.

    Raises:
        ValueError: shapes, non-finite entries, or (concrete ``a``) a singular equation: some
            ``λ_i + λ_j`` (eigenvalues of ``a``) zero to round-off; the message names the pair.
    """
    a, q = _check("continuous", a, q)
    x = continuous_lyapunov_unchecked(a, q)
    return x if is_concrete(a) else bs.nan_if_singular("continuous", x, a)


def continuous_lyapunov_unchecked(a: jax.Array, q: jax.Array) -> jax.Array:
    """:func:`solve_continuous_lyapunov` without input checks, for callers whose ``a`` may be NaN by
    design (the tangent equations of a failed Riccati solve propagate NaN instead of raising)."""
    return jax.lax.custom_linear_solve(
        lambda x: a @ x + x @ a.T,
        q,
        solve=lambda _, rhs: bs.continuous_lyapunov(a, rhs),
        transpose_solve=lambda _, rhs: bs.continuous_lyapunov(a.T, rhs),
    )


def solve_discrete_lyapunov(a: jax.Array, q: jax.Array) -> jax.Array:
    """Solve ``A X Aᵀ − X + Q = 0`` for ``X`` (shapes as in :func:`solve_continuous_lyapunov`).

    Singular when some ``λ_i λ_j = 1`` (to round-off): ``ValueError`` naming the pair for a
    concrete ``a``, an all-NaN ``X`` under ``jit``.
    """
    a, q = _check("discrete", a, q)
    x = discrete_lyapunov_unchecked(a, q)
    return x if is_concrete(a) else bs.nan_if_singular("discrete", x, a)


def discrete_lyapunov_unchecked(a: jax.Array, q: jax.Array) -> jax.Array:
    """:func:`solve_discrete_lyapunov` without input checks (see :func:`continuous_lyapunov_unchecked`)."""
    return jax.lax.custom_linear_solve(
        lambda x: x - a @ x @ a.T,
        q,
        solve=lambda _, rhs: bs.discrete_lyapunov(a, rhs),
        transpose_solve=lambda _, rhs: bs.discrete_lyapunov(a.T, rhs),
    )
