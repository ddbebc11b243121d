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

Uniqueness (:func:`check_unique`, :func:`nan_if_singular`): each equation has a unique solution iff
no eigenvalue pair ``(λ_i, μ_j)`` (``μ = λ(B)``, or ``λ(A)`` again for Lyapunov) makes its operator
singular — ``λ_i + μ_j = 0`` (Sylvester, continuous Lyapunov) or ``λ_i μ_j = 1`` (Stein).  A pair
counts as singular when it is within round-off of that: ``|λ_i + μ_j| ≤ c·n·ε·(‖A‖ + ‖B‖)`` or
``|λ_i μ_j − 1| ≤ c·n·ε·(1 + ‖A‖²)`` (``c`` = :data:`SINGULAR_SLACK`, ``n`` the larger size, ``ε``
the dtype's machine epsilon, Frobenius norms) — the size of the eigenvalue errors of a backward
stable eigensolver on a well-conditioned spectrum.  Nearly singular equations above that (or with
ill-conditioned, e.g. defective, eigenvalues) are solved, with the accuracy their conditioning allows.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from jax.scipy.linalg import schur, solve_triangular

SINGULAR_SLACK = 10.0

# kind -> (the equation in words, what must not vanish)
_EQUATIONS = {
    "continuous": ("the continuous Lyapunov equation A X + X Aᵀ = Q", "λ_i + λ_j"),
    "discrete": ("the discrete Lyapunov (Stein) equation A X Aᵀ − X + Q = 0", "λ_i·λ_j − 1"),
    "sylvester": ("the Sylvester equation A X + X B = C", "λ_i + μ_j"),
}


def _gaps(xp, kind: str, lam, mu):
    """``|λ_i + μ_j|`` (or ``|λ_i μ_j − 1|`` for Stein), shape ``(n, k)``; ``xp`` is np or jnp."""
    if kind == "discrete":
        return xp.abs(lam[:, None] * mu[None, :] - 1)
    return xp.abs(lam[:, None] + mu[None, :])


def _tolerance(kind: str, n: int, eps: float, norm_a, norm_b):
    if kind == "discrete":
        return SINGULAR_SLACK * n * eps * (1 + norm_a * norm_b)
    return SINGULAR_SLACK * n * eps * (norm_a + norm_b)


def _fmt(z: complex) -> str:
    z = complex(z)
    return f"{z.real:.6g}" if z.imag == 0 else f"{z.real:.6g}{z.imag:+.6g}j"


def check_unique(kind: str, a: np.ndarray, b: np.ndarray | None = None) -> None:
    """Raise ``ValueError`` naming the eigenvalue pair when the equation ``kind`` (``"continuous"``,
    ``"discrete"``, ``"sylvester"``) has no unique solution; ``a``, ``b`` concrete (NumPy)."""
    a = np.asarray(a)
    b = a if b is None else np.asarray(b)
    lam = np.linalg.eigvals(a)
    mu = lam if b is a else np.linalg.eigvals(b)
    gaps = _gaps(np, kind, lam, mu)
    eps = float(np.finfo(np.result_type(a, b, float)).eps)
    tol = _tolerance(kind, max(a.shape[0], b.shape[0]), eps, float(np.linalg.norm(a)), float(np.linalg.norm(b)))
    i, j = np.unravel_index(np.argmin(gaps), gaps.shape)
    if gaps[i, j] > tol:
        return
    equation, expr = _EQUATIONS[kind]
    if kind == "sylvester":
        pair, names = f"λ_i = {_fmt(lam[i])} of a and μ_j = {_fmt(mu[j])} of b", "a, b"
    else:
        pair, names = f"eigenvalues λ_i = {_fmt(lam[i])} and λ_j = {_fmt(mu[j])} of a", "a"
    raise ValueError(
        f"{names}: {equation} is singular: {pair} give |{expr}| = {gaps[i, j]:.3g} ≤ {tol:.3g} "
        f"(round-off tolerance), so it has no unique solution (it needs {expr} ≠ 0 for all i, j)"
    )


def nan_if_singular(kind: str, x: jax.Array, a: jax.Array, b: jax.Array | None = None) -> jax.Array:
    """``x``, or all NaN where the equation is singular by :func:`check_unique`'s test — the traced
    (``jit``/``vmap``) counterpart of that check.  The test is not differentiated."""
    a = jax.lax.stop_gradient(a)
    b = a if b is None else jax.lax.stop_gradient(b)
    lam = jnp.linalg.eigvals(a)
    mu = lam if b is a else jnp.linalg.eigvals(b)
    eps = float(jnp.finfo(jnp.result_type(a, b)).eps)
    tol = _tolerance(kind, max(a.shape[0], b.shape[0]), eps, jnp.linalg.norm(a), jnp.linalg.norm(b))
    singular = jnp.min(_gaps(jnp, kind, lam, mu)) <= tol
    return jnp.where(singular, jnp.nan, x)


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
