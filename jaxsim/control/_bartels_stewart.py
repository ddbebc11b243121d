"""Bartels–Stewart kernels: linear matrix equations solved in complex Schur coordinates.

With ``A = U T Uᴴ`` (complex Schur form, ``T`` upper triangular), each equation becomes a triangular
one that is solved column by column with ``n`` triangular solves (``O(n³)`` in all):

* Sylvester ``A X + X B = C``           → ``T Y + Y S = F``,     ``B = V S Vᴴ``, ``F = Uᴴ C V``;
* continuous Lyapunov ``A X + X Aᴴ = Q`` → ``T Y + Y Tᴴ = F``,    ``F = Uᴴ Q U``;
* discrete Lyapunov ``A X Aᴴ − X + Q = 0`` → ``T Y Tᴴ − Y + F = 0``.

These are the plain forward solves (no derivative rules): the public solvers in
:mod:`jaxsim.control.lyapunov` and :mod:`jaxsim.control.sylvester` wrap them in
``lax.custom_linear_solve`` so that derivatives come from the adjoint equation.  They run under
``jit``/``vmap``; the Schur decomposition is LAPACK's, hence CPU only in JAX.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from jax.scipy.linalg import schur, solve_triangular


def _complex_schur(a: jax.Array) -> tuple[jax.Array, jax.Array]:
    t, u = schur(a.astype(jnp.result_type(a, jnp.complex64)), output="complex")
    return t, u


def _real_if(x: jax.Array, like: tuple[jax.Array, ...]) -> jax.Array:
    return x if any(jnp.iscomplexobj(m) for m in like) else x.real


def sylvester(a: jax.Array, b: jax.Array, c: jax.Array) -> jax.Array:
    """Solve ``A X + X B = C`` (``A (n, n)``, ``B (k, k)``, ``C (n, k)``)."""
    t, u = _complex_schur(a)
    s, v = _complex_schur(b)
    f = u.conj().T @ c @ v
    n, k = f.shape
    eye = jnp.eye(n, dtype=t.dtype)

    def column(j, y):
        rhs = f[:, j] - y @ s[:, j]  # columns ≥ j of y are still zero
        yj = solve_triangular(t + s[j, j] * eye, rhs, lower=False)
        return y.at[:, j].set(yj)

    y = jax.lax.fori_loop(0, k, column, jnp.zeros_like(f))
    return _real_if(u @ y @ v.conj().T, (a, b, c))


def continuous_lyapunov(a: jax.Array, q: jax.Array) -> jax.Array:
    """Solve ``A X + X Aᴴ = Q`` (``A, Q (n, n)``) with one Schur decomposition."""
    t, u = _complex_schur(a)
    f = u.conj().T @ q @ u
    n = f.shape[0]
    eye = jnp.eye(n, dtype=t.dtype)

    def column(i, y):
        j = n - 1 - i  # backwards: column j couples to columns > j through Tᴴ
        rhs = f[:, j] - y @ t[j, :].conj()  # columns ≤ j of y are still zero
        yj = solve_triangular(t + t[j, j].conj() * eye, rhs, lower=False)
        return y.at[:, j].set(yj)

    y = jax.lax.fori_loop(0, n, column, jnp.zeros_like(f))
    return _real_if(u @ y @ u.conj().T, (a, q))


def discrete_lyapunov(a: jax.Array, q: jax.Array) -> jax.Array:
    """Solve ``A X Aᴴ − X + Q = 0`` (``A, Q (n, n)``) with one Schur decomposition."""
    t, u = _complex_schur(a)
    f = u.conj().T @ q @ u
    n = f.shape[0]
    eye = jnp.eye(n, dtype=t.dtype)

    def column(i, y):
        j = n - 1 - i
        rhs = -f[:, j] - t @ (y @ t[j, :].conj())  # columns ≤ j of y are still zero
        yj = solve_triangular(t[j, j].conj() * t - eye, rhs, lower=False)
        return y.at[:, j].set(yj)

    y = jax.lax.fori_loop(0, n, column, jnp.zeros_like(f))
    return _real_if(u @ y @ u.conj().T, (a, q))
