"""The resolvent ``(sI − A)⁻¹ R`` at many complex points, through one Schur decomposition of ``A``.

``A = Z T Zᴴ`` (complex Schur form, ``T`` upper triangular) turns every frequency's linear solve
into a back substitution, ``(sI − T) x = Zᴴ r``, which is a few elementwise array operations per
matrix entry: cheap to compile (a batched LU solve costs seconds of XLA compilation per use) and
to run on a dense frequency grid, and backward stable like an LU solve.  The Schur form itself is
never differentiated: :func:`resolve` is a ``lax.custom_linear_solve`` whose derivatives come from
the operator ``(sI − A)`` (``d[(sI − A)⁻¹R] = (sI − A)⁻¹ (dR + dA X − ds X)``), so derivatives of
any order with respect to ``A``, ``R`` and ``s``, forward and reverse, are exact.

The Schur decomposition is LAPACK's (``jax.scipy.linalg.schur``), which JAX runs on CPU.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp


def _triangular(t: jax.Array, r: jax.Array, s: jax.Array, upper: bool) -> jax.Array:
    """Solve ``(sᵢ I − T) xᵢ = rᵢ`` (``upper``) or ``(sᵢ I − Tᵀ) xᵢ = rᵢ`` for every ``i``, with
    ``t (n, n)`` upper triangular, ``r (N, n, k)``, ``s (N,)``; returns ``(N, n, k)``."""
    n = t.shape[0]
    x: list[jax.Array] = [None] * n  # type: ignore[list-item]
    order = reversed(range(n)) if upper else range(n)
    for i in order:
        acc = r[:, i, :]
        for j in range(i + 1, n) if upper else range(i):
            acc = acc + (t[i, j] if upper else t[j, i]) * x[j]
        x[i] = acc / (s - t[i, i])[:, None]
    return jnp.stack(x, axis=1)


def schur_factors(a: jax.Array) -> tuple[jax.Array, jax.Array]:
    """``(T, Z)`` with ``A = Z T Zᴴ`` (complex Schur form of ``stop_gradient(A)``); compute once and pass
    to :func:`resolve` / :func:`transfer` when evaluating the same system at several places."""
    cdtype = jnp.result_type(a, jnp.complex64)
    return jax.scipy.linalg.schur(jax.lax.stop_gradient(a).astype(cdtype), output="complex")


def resolve(a: jax.Array, r: jax.Array, s: jax.Array, factors: tuple[jax.Array, jax.Array] | None = None) -> jax.Array:
    """``(sᵢ I − A)⁻¹ rᵢ`` for ``a (n, n)``, ``r (N, n, k)`` and ``s (N,)`` complex → ``(N, n, k)``.

    A ``lax.custom_linear_solve``: the Schur-form solves are never differentiated; derivatives
    (any order, forward and reverse) come from the operator ``x ↦ (sI − A) x``, transposes from the
    Schur form of ``Aᵀ = Z̄ Tᵀ Zᵀ``.  ``factors``: :func:`schur_factors` of ``a`` if already known.
    At an eigenvalue of ``A`` the result is inf/NaN (no error)."""
    cdtype = jnp.result_type(a, r, s, jnp.complex64)
    a, r, s = a.astype(cdtype), r.astype(cdtype), s.astype(cdtype)
    t, z = schur_factors(a) if factors is None else factors
    s0 = jax.lax.stop_gradient(s)

    def matvec(x):
        return s[:, None, None] * x - jnp.einsum("ij,njk->nik", a, x)

    def solve(_, rhs):
        return jnp.einsum("ij,njk->nik", z, _triangular(t, jnp.einsum("ji,njk->nik", z.conj(), rhs), s0, True))

    def transpose_solve(_, rhs):
        return jnp.einsum("ij,njk->nik", z.conj(), _triangular(t, jnp.einsum("ji,njk->nik", z, rhs), s0, False))

    return jax.lax.custom_linear_solve(matvec, r, solve, transpose_solve)


def transfer(
    a: jax.Array,
    b: jax.Array,
    c: jax.Array,
    d: jax.Array,
    s: jax.Array,
    factors: tuple[jax.Array, jax.Array] | None = None,
) -> jax.Array:
    """``C (sI − A)⁻¹ B + D`` at the points ``s`` (any shape ``S``) → ``S + (p, m)`` complex."""
    cdtype = jnp.result_type(a, b, c, d, s, jnp.complex64)
    shape = s.shape
    flat = s.reshape(-1).astype(cdtype)
    if a.shape[0] == 0:
        g = jnp.broadcast_to(d.astype(cdtype), flat.shape + d.shape)
    else:
        x = resolve(a, jnp.broadcast_to(b.astype(cdtype), flat.shape + b.shape), flat, factors)
        g = jnp.einsum("ij,njk->nik", c.astype(cdtype), x) + d.astype(cdtype)
    return g.reshape(shape + d.shape)
