"""Algebraic Riccati equations (CARE, DARE): float64 forward solves, implicit derivatives.

Conventions are SciPy's (``solve_continuous_are`` / ``solve_discrete_are``), with ``R ≻ 0``:

* CARE: ``Aᵀ X + X A − X B R⁻¹ Bᵀ X + Q = 0``;
* DARE: ``Aᵀ X A − X − Aᵀ X B (R + Bᵀ X B)⁻¹ Bᵀ X A + Q = 0``;

and the *stabilising* solution is returned (``A − B R⁻¹ Bᵀ X`` Hurwitz, resp.
``A − B (R + BᵀXB)⁻¹ BᵀXA`` Schur).

Forward solves (never differentiated):

* CARE — matrix sign function of the Hamiltonian ``H = [[A, −G], [−Q, −Aᵀ]]`` (``G = B R⁻¹ Bᵀ``),
  iterated on the symmetric matrix ``J H`` with determinant scaling (Byers 1987); the stable
  invariant subspace ``ker(sign H + I)`` gives ``X`` by least squares; then Newton–Kleinman
  steps in defect-correction form (``A_clᵀ ΔX + ΔX A_cl = −Res(X)``, one Lyapunov solve each) polish
  the result to the accuracy the problem's conditioning allows.
* DARE — structure-preserving doubling (SDA, Chu–Fan–Lin 2005), then Hewer–Newton steps in
  defect-correction form (one Stein solve each).

A result is kept only if it is finite, its relative residual is below ``1e-6`` and its closed
loop is stable; otherwise the solvers return NaN (inside ``jit``/``vmap``) or raise ``ValueError``
(on concrete inputs, together with a PBH stabilisability test before solving).

Derivatives (``custom_jvp``, so forward and reverse mode): differentiating ``F(X, θ) = 0`` gives
``F_X[dX] = −F_θ[dθ]`` where ``F_X`` is the Lyapunov operator ``dX ↦ A_clᵀ dX + dX A_cl`` (CARE) or
the Stein operator ``dX ↦ A_clᵀ dX A_cl − dX`` (DARE).  ``F_θ[dθ]`` is the JVP of the residual at
fixed ``X``, and the linear solve is :mod:`jaxsim.control.lyapunov`'s, whose transpose is the
adjoint Lyapunov/Stein equation — so a reverse-mode gradient costs one extra Lyapunov solve.

The forward solves use LAPACK's Schur decomposition and eigenvalues (through
:mod:`jaxsim.control.lyapunov` and the closed-loop stability check), which JAX provides on CPU only.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax.scipy.linalg import cho_factor, cho_solve, lu_factor, lu_solve

from jaxsim.control import _bartels_stewart as bs
from jaxsim.control.lyapunov import continuous_lyapunov_unchecked, discrete_lyapunov_unchecked
from jaxsim.control.pbh import check_stabilizable
from jaxsim.core.validation import (
    check_finite,
    check_positive_definite,
    check_positive_semidefinite,  # noqa: F401  (re-exported: lqr and kalman_gain import it from here)
    check_square,
    check_symmetric,
    is_concrete,
)

SIGN_TOL = 1e-13  # relative change at which the sign / doubling iterations stop
MAX_ITER = 100
NEWTON_STEPS = 3  # defect-correction steps after the sign / doubling iteration
VALID_RESIDUAL = 1e-6  # relative residual above which a result is declared failed (NaN)


def _sym(m: jax.Array) -> jax.Array:
    return 0.5 * (m + m.T)


def _fro(m: jax.Array) -> jax.Array:
    return jnp.sqrt(jnp.sum(m * m))


def gain_matrix(b: jax.Array, r: jax.Array) -> jax.Array:
    """``G = B R⁻¹ Bᵀ`` through a Cholesky factor of ``R`` (exactly symmetric)."""
    low = jnp.linalg.cholesky(r)
    y = jax.scipy.linalg.solve_triangular(low, b.T, lower=True)
    return y.T @ y


def care_residual(x: jax.Array, a: jax.Array, b: jax.Array, q: jax.Array, r: jax.Array) -> jax.Array:
    """``Aᵀ X + X A − X B R⁻¹ Bᵀ X + Q`` (``(n, n)``)."""
    return a.T @ x + x @ a - x @ gain_matrix(b, r) @ x + q


def dare_gain(x: jax.Array, a: jax.Array, b: jax.Array, r: jax.Array) -> jax.Array:
    """``K = (R + Bᵀ X B)⁻¹ Bᵀ X A`` (``(m, n)``)."""
    bx = b.T @ x
    return cho_solve(cho_factor(r + bx @ b), bx @ a)


def dare_residual(x: jax.Array, a: jax.Array, b: jax.Array, q: jax.Array, r: jax.Array) -> jax.Array:
    """``Aᵀ X A − X − Aᵀ X B (R + BᵀXB)⁻¹ Bᵀ X A + Q`` (``(n, n)``)."""
    return a.T @ x @ a - x - (a.T @ x @ b) @ dare_gain(x, a, b, r) + q


def relative_residual(res: jax.Array, *terms: jax.Array) -> jax.Array:
    """``‖res‖_F / Σ‖term‖_F`` — the residual relative to the size of the equation's terms."""
    scale = sum(_fro(t) for t in terms)
    return _fro(res) / jnp.maximum(scale, jnp.finfo(res.dtype).tiny)


# ----------------------------------------------------------------------------- CARE forward


def _jmj(m: jax.Array, n: int) -> jax.Array:
    """``J M J`` for ``J = [[0, I], [−I, 0]]`` without multiplications."""
    m11, m12, m21, m22 = m[:n, :n], m[:n, n:], m[n:, :n], m[n:, n:]
    return jnp.block([[-m22, m21], [m12, -m11]])


class _SignState(NamedTuple):
    w: jax.Array
    k: jax.Array
    change: jax.Array
    prev_change: jax.Array


def _hamiltonian_sign(a: jax.Array, g: jax.Array, q: jax.Array) -> jax.Array:
    """``W = J·sign(H)`` (symmetric), by the scaled Newton iteration on ``J H``."""
    n = a.shape[0]
    w0 = jnp.block([[-q, -a.T], [-a, g]])  # J H, symmetric
    eye = jnp.eye(2 * n, dtype=a.dtype)
    inf = jnp.asarray(jnp.inf, a.dtype)

    def body(s: _SignState) -> _SignState:
        lu, piv = lu_factor(s.w)
        log_det = jnp.sum(jnp.log(jnp.abs(jnp.diag(lu))))
        c = jnp.where(s.change > 1e-2, jnp.exp(log_det / (2 * n)), 1.0)  # |det(W/c)| = 1
        w_inv = lu_solve((lu, piv), eye)
        w_new = _sym(0.5 * (s.w / c + c * _jmj(w_inv, n)))
        change = jnp.sum(jnp.abs(w_new - s.w)) / jnp.sum(jnp.abs(w_new))
        return _SignState(w_new, s.k + 1, change, s.change)

    def cond(s: _SignState) -> jax.Array:
        stagnated = (s.change < 1e-6) & (s.change >= 0.5 * s.prev_change)
        return (s.k < MAX_ITER) & (s.change > SIGN_TOL) & ~stagnated & ~jnp.isnan(s.change)

    return jax.lax.while_loop(cond, body, _SignState(w0, jnp.asarray(0), inf, inf)).w


def _care_initial(a: jax.Array, g: jax.Array, q: jax.Array) -> jax.Array:
    n = a.shape[0]
    w = _hamiltonian_sign(a, g, q)
    # sign(H) = −J W; [I; X] spans ker(sign(H) + I):  [−W22; W12 + I] X = [W21 − I; −W11]
    eye = jnp.eye(n, dtype=a.dtype)
    lhs = jnp.concatenate([-w[n:, n:], w[:n, n:] + eye], axis=0)
    rhs = jnp.concatenate([w[n:, :n] - eye, -w[:n, :n]], axis=0)
    return _sym(jnp.linalg.lstsq(lhs, rhs)[0])


def _polish(x0, residual, correction, steps):
    """Defect-correction steps ``x ← x + correction(x, residual(x))``, kept only if they help."""

    def norm(x):
        v = _fro(residual(x))
        return jnp.where(jnp.isfinite(v), v, jnp.inf)

    def body(_, state):
        x, rn = state
        x_new = _sym(x + correction(x, residual(x)))
        rn_new = norm(x_new)
        better = rn_new < rn
        return jnp.where(better, x_new, x), jnp.where(better, rn_new, rn)

    return jax.lax.fori_loop(0, steps, body, (x0, norm(x0)))[0]


def _care_forward(a, b, q, r):
    g = gain_matrix(b, r)
    x0 = _care_initial(a, g, q)
    residual = lambda x: a.T @ x + x @ a - x @ g @ x + q  # noqa: E731
    correction = lambda x, res: bs.continuous_lyapunov((a - g @ x).T, -res)  # noqa: E731
    x = _polish(x0, residual, correction, NEWTON_STEPS)
    rel = relative_residual(residual(x), q, a.T @ x, x @ a, x @ g @ x)
    stable = jnp.max(jnp.linalg.eigvals(a - g @ x).real) < 0
    ok = jnp.all(jnp.isfinite(x)) & (rel <= VALID_RESIDUAL) & stable
    return jnp.where(ok, x, jnp.nan)


# ----------------------------------------------------------------------------- DARE forward


class _SDAState(NamedTuple):
    a: jax.Array
    g: jax.Array
    h: jax.Array
    k: jax.Array
    change: jax.Array


def _dare_initial(a: jax.Array, g: jax.Array, q: jax.Array) -> jax.Array:
    """Structure-preserving doubling: ``H_k → X`` quadratically."""
    n = a.shape[0]
    eye = jnp.eye(n, dtype=a.dtype)

    def body(s: _SDAState) -> _SDAState:
        lu = lu_factor(eye + s.g @ s.h)
        y_a = lu_solve(lu, s.a)  # (I + G H)⁻¹ A
        y_g = lu_solve(lu, s.g)  # (I + G H)⁻¹ G
        a_new = s.a @ y_a
        g_new = _sym(s.g + s.a @ y_g @ s.a.T)
        h_new = _sym(s.h + s.a.T @ s.h @ y_a)
        change = jnp.sum(jnp.abs(h_new - s.h)) / jnp.maximum(jnp.sum(jnp.abs(h_new)), 1e-300)
        return _SDAState(a_new, g_new, h_new, s.k + 1, change)

    def cond(s: _SDAState) -> jax.Array:
        return (s.k < MAX_ITER) & (s.change > SIGN_TOL) & ~jnp.isnan(s.change)

    inf = jnp.asarray(jnp.inf, a.dtype)
    return jax.lax.while_loop(cond, body, _SDAState(a, g, q, jnp.asarray(0), inf)).h


def _dare_forward(a, b, q, r):
    x0 = _dare_initial(a, gain_matrix(b, r), q)
    residual = lambda x: dare_residual(x, a, b, q, r)  # noqa: E731

    def correction(x, res):
        acl = a - b @ dare_gain(x, a, b, r)
        return bs.discrete_lyapunov(acl.T, res)

    x = _polish(x0, residual, correction, NEWTON_STEPS)
    k = dare_gain(x, a, b, r)
    rel = relative_residual(residual(x), q, x, a.T @ x @ a, a.T @ x @ b @ k)
    stable = jnp.max(jnp.abs(jnp.linalg.eigvals(a - b @ k))) < 1
    ok = jnp.all(jnp.isfinite(x)) & (rel <= VALID_RESIDUAL) & stable
    return jnp.where(ok, x, jnp.nan)


# ----------------------------------------------------------------------------- implicit derivatives


@jax.custom_jvp
def _care(a, b, q, r):
    return _care_forward(a, b, q, r)


@_care.defjvp
def _care_jvp(primals, tangents):
    a, b, q, r = primals
    x = _care(a, b, q, r)
    _, rhs = jax.jvp(lambda *p: care_residual(x, *p), primals, tangents)
    acl = a - gain_matrix(b, r) @ x
    return x, _sym(continuous_lyapunov_unchecked(acl.T, -rhs))


@jax.custom_jvp
def _dare(a, b, q, r):
    return _dare_forward(a, b, q, r)


@_dare.defjvp
def _dare_jvp(primals, tangents):
    a, b, q, r = primals
    x = _dare(a, b, q, r)
    _, rhs = jax.jvp(lambda *p: dare_residual(x, *p), primals, tangents)
    acl = a - b @ dare_gain(x, a, b, r)
    return x, _sym(discrete_lyapunov_unchecked(acl.T, rhs))


# ----------------------------------------------------------------------------- public API


def _as_2d(name: str, m, rows: int | None = None) -> jax.Array:
    m = jnp.asarray(m)
    if m.ndim == 0:
        m = m.reshape(1, 1)
    if m.ndim == 1 and rows is not None:
        m = m.reshape(rows, -1)
    if m.ndim != 2:
        raise ValueError(f"{name}: expected a 2-D matrix, got shape {tuple(m.shape)}")
    return m


def prepare_riccati_inputs(a, b, q, r, names=("a", "b", "q", "r")):
    """Shape, finiteness, symmetry and ``R ≻ 0`` checks; returns float arrays, ``q``/``r`` symmetrised."""
    na, nb, nq, nr = names
    a = _as_2d(na, a)
    check_square(na, a)
    n = a.shape[0]
    b = _as_2d(nb, b, rows=n)
    q = _as_2d(nq, q)
    r = _as_2d(nr, r)
    if b.shape[0] != n:
        raise ValueError(f"{nb}: expected {n} rows to match {na}, got shape {tuple(b.shape)}")
    m = b.shape[1]
    if q.shape != (n, n):
        raise ValueError(f"{nq}: expected shape ({n}, {n}), got {tuple(q.shape)}")
    if r.shape != (m, m):
        raise ValueError(f"{nr}: expected shape ({m}, {m}), got {tuple(r.shape)}")
    for name, v in zip(names, (a, b, q, r)):
        check_finite(name, v)
    check_symmetric(nq, q)
    check_symmetric(nr, r)
    check_positive_definite(nr, r)
    dtype = jnp.result_type(a, b, q, r, float)
    return a.astype(dtype), b.astype(dtype), _sym(q.astype(dtype)), _sym(r.astype(dtype))


def _raise_if_failed(x: jax.Array, what: str, names) -> None:
    if is_concrete(x) and not bool(jnp.all(jnp.isfinite(x))):
        raise ValueError(
            f"({', '.join(names)}): {what} has no stabilising solution that could be computed "
            "(its Hamiltonian/symplectic pencil has eigenvalues on the stability boundary — e.g. a "
            "mode there is unobservable from q — or the problem is too ill-conditioned)"
        )


def solve_continuous_are(a, b, q, r, *, names=("a", "b", "q", "r")) -> jax.Array:
    """Stabilising solution ``X`` of ``Aᵀ X + X A − X B R⁻¹ Bᵀ X + Q = 0``.

    Args:
        a: ``(n, n)``; b: ``(n, m)``; q: ``(n, n)`` symmetric; r: ``(m, m)`` symmetric positive
            definite (a scalar is accepted for ``m = 1``).
        names: argument names used in error messages (callers such as :func:`lqr` pass theirs).

    Returns:
        ``X`` of shape ``(n, n)``, symmetric.  Differentiable (implicitly) in all four inputs;
        under ``jit``/``vmap`` a failed solve gives NaN instead of an exception.
    """
    a, b, q, r = prepare_riccati_inputs(a, b, q, r, names)
    if is_concrete((a, b)):
        check_stabilizable(names[0], np.asarray(a), names[1], np.asarray(b))
    x = _care(a, b, q, r)
    _raise_if_failed(x, "the CARE", names)
    return x


def solve_discrete_are(a, b, q, r, *, names=("a", "b", "q", "r")) -> jax.Array:
    """Stabilising solution ``X`` of ``Aᵀ X A − X − Aᵀ X B (R + BᵀXB)⁻¹ Bᵀ X A + Q = 0``.

    Shapes and behaviour as :func:`solve_continuous_are` (discrete-time stability: ``|λ| < 1``).
    """
    a, b, q, r = prepare_riccati_inputs(a, b, q, r, names)
    if is_concrete((a, b)):
        check_stabilizable(names[0], np.asarray(a), names[1], np.asarray(b), discrete=True)
    x = _dare(a, b, q, r)
    _raise_if_failed(x, "the DARE", names)
    return x
