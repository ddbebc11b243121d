"""Forward solve of the DARE ``Aᵀ X A − X − Aᵀ X B (R + BᵀXB)⁻¹ Bᵀ X A + Q = 0``, never differentiated.

``R`` need only be positive *semi*-definite: the equation needs ``R + BᵀXB ≻ 0`` at the solution.

1. Balance the state units (:mod:`jaxsim.control._symplectic_balance`).
2. A singular (or nearly singular) ``R`` is handled by the substitution ``X = Y + cI``: ``Y`` solves
   a DARE with ``R' = R + c BᵀB ≻ 0``, a cross term ``S' = c AᵀB`` and ``Q' = Q + c(AᵀA − I)``,
   which is brought to standard form by ``Â = A − B R'⁻¹ S'ᵀ``, ``Q̂ = Q' − S' R'⁻¹ S'ᵀ``.  With a
   well-conditioned ``R`` the shift is ``c = 0`` and nothing changes.
3. Fast path: structure-preserving doubling (SDA, Chu–Fan–Lin 2005) on the standard form, then
   Hewer–Newton steps in defect-correction form (one Stein solve each) on the original equation.
   Kept if finite, with relative residual ≤ ``VALID_RESIDUAL`` and a Schur-stable closed loop.
4. Otherwise (unit-circle eigenvalues of the symplectic pencil, where the doubling is undefined),
   the maximal solution: SDA for ``Q + cI ≻ 0`` gives a stabilising start, from which Hewer's
   iteration decreases monotonically to it (a marginal fast result is refined the same way).
   Kept if it passes the same test with a marginal band on the closed-loop spectral radius; else
   NaN.  Steps 3 and 4 are one loop (:func:`jaxsim.control._riccati_common.solve_with_fallback`).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
from jax.scipy.linalg import cho_factor, cho_solve, lu_factor, lu_solve

from jaxsim.control import _bartels_stewart as bs
from jaxsim.control._riccati_common import (
    dare_gain,
    dare_measures,
    dare_residual,
    relative_shift,
    solve_with_fallback,
    sym,
)
from jaxsim.control._symplectic_balance import balancing_exponents, scale_problem, unscale_solution

SDA_TOL = 1e-13  # relative change at which the doubling stops
MAX_ITER = 100
SINGULAR_R = 1e-8  # λ_min(R) / ‖R‖ below which R is treated as singular (shift c > 0)


def balancing_gain(b: jax.Array, r: jax.Array) -> jax.Array:
    """``B R⁻¹ Bᵀ``, with a singular ``R`` regularised by ``‖R‖ I`` (only magnitudes matter)."""
    w = jnp.linalg.eigvalsh(r)
    reg = jnp.where(w[0] > SINGULAR_R * w[-1], 0.0, jnp.maximum(w[-1], 1.0))
    return b @ cho_solve(cho_factor(r + reg * jnp.eye(r.shape[0], dtype=r.dtype)), b.T)


class _SDAState(NamedTuple):
    a: jax.Array
    g: jax.Array
    h: jax.Array
    k: jax.Array
    change: jax.Array


def _doubling(a: jax.Array, g: jax.Array, q: jax.Array, active: jax.Array) -> jax.Array:
    """Structure-preserving doubling ``H_k → X`` (quadratic convergence); runs while ``active``."""
    n = a.shape[0]
    eye = jnp.eye(n, dtype=a.dtype)

    def body(s: _SDAState) -> _SDAState:
        lu = lu_factor(eye + s.g @ s.h)
        y_a = lu_solve(lu, s.a)  # (I + G H)⁻¹ A
        y_g = lu_solve(lu, s.g)  # (I + G H)⁻¹ G
        a_new = s.a @ y_a
        g_new = sym(s.g + s.a @ y_g @ s.a.T)
        h_new = sym(s.h + s.a.T @ s.h @ y_a)
        change = jnp.sum(jnp.abs(h_new - s.h)) / jnp.maximum(jnp.sum(jnp.abs(h_new)), 1e-300)
        return _SDAState(a_new, g_new, h_new, s.k + 1, change)

    def cond(s: _SDAState) -> jax.Array:
        return active & (s.k < MAX_ITER) & (s.change > SDA_TOL) & ~jnp.isnan(s.change)

    inf = jnp.asarray(jnp.inf, a.dtype)
    return jax.lax.while_loop(cond, body, _SDAState(a, g, q, jnp.asarray(0), inf)).h


def _r_shift(b: jax.Array, r: jax.Array, q: jax.Array, a: jax.Array) -> jax.Array:
    """``c = 0`` for a well-conditioned ``R``, else a shift of the problem's size (balanced data)."""
    w = jnp.linalg.eigvalsh(r)
    singular = w[0] <= SINGULAR_R * jnp.maximum(w[-1], jnp.finfo(r.dtype).tiny)
    return jnp.where(singular, relative_shift(q, a, b @ b.T), 0.0)


def _sda_solution(a, b, q, r, c, active):
    """``X = Y + cI`` with ``Y`` from the shifted standard-form DARE (see the module docstring)."""
    n = a.shape[0]
    eye = jnp.eye(n, dtype=a.dtype)
    r_s = r + c * (b.T @ b)
    factor = cho_factor(r_s)
    s_t = c * (b.T @ a)  # S'ᵀ = c BᵀA
    a_hat = a - b @ cho_solve(factor, s_t)
    q_hat = sym(q + c * (a.T @ a - eye) - s_t.T @ cho_solve(factor, s_t))
    g_hat = sym(b @ cho_solve(factor, b.T))
    return _doubling(a_hat, g_hat, q_hat, active) + c * eye


def _solve_balanced(a: jax.Array, b: jax.Array, q: jax.Array, r: jax.Array) -> tuple[jax.Array, jax.Array]:
    """``(X, stability margin)`` on balanced data; ``X`` NaN if no solution passed the test."""
    eye = jnp.eye(a.shape[0], dtype=a.dtype)
    c_r = _r_shift(b, r, q, a)

    def correction(x, res):
        return bs.discrete_lyapunov((a - b @ dare_gain(x, a, b, r)).T, res)

    return solve_with_fallback(
        first_guess=lambda c, active: _sda_solution(a, b, q + c * eye, r, c_r, active),
        residual=lambda x: dare_residual(x, a, b, q, r),
        correction=correction,
        measures=lambda x: dare_measures(x, a, b, q, r),
        shift=relative_shift(q, a, b @ b.T),
        template=a,
    )


def dare_forward(a: jax.Array, b: jax.Array, q: jax.Array, r: jax.Array) -> tuple[jax.Array, jax.Array]:
    """The DARE's stabilising (or, failing that, maximal) solution, NaN if none was found, and its
    closed loop's stability margin."""
    g = balancing_gain(b, r)
    e = balancing_exponents(a, g, q)
    ab, bb, qb = scale_problem(a, b, q, e)
    x, margin = _solve_balanced(ab, bb, qb, r)
    return unscale_solution(x, e), margin
