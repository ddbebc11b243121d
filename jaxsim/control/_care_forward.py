"""Forward solve of the CARE ``Aᵀ X + X A − X G X + Q = 0`` (``G = B R⁻¹ Bᵀ``), never differentiated.

1. Balance: a state scaling by powers of two (:mod:`jaxsim.control._symplectic_balance`), so that
   the result does not depend on the caller's state units.
2. Fast path: the matrix sign function of the Hamiltonian ``H = [[A, −G], [−Q, −Aᵀ]]``, iterated on
   the symmetric matrix ``J H`` with determinant scaling (Byers 1987); the stable invariant subspace
   ``ker(sign H + I)`` gives ``X`` by least squares; then Newton–Kleinman steps in defect-correction
   form (``A_clᵀ ΔX + ΔX A_cl = −Res(X)``) polish it.  Kept if finite, with relative residual
   ≤ ``VALID_RESIDUAL`` and an asymptotically stable closed loop.
3. Otherwise — typically ``H`` has eigenvalues on (or within rounding of) the imaginary axis, where
   the sign function is undefined and the outcome of step 2 depends on the last bit — the maximal
   solution is computed: the CARE with ``Q + cI ≻ 0`` (hyperbolic Hamiltonian, solved as in step 2)
   gives a stabilising start, from which Newton–Kleinman decreases monotonically to the maximal
   solution (linearly when its closed loop is marginally stable).  A fast result whose closed loop
   is only marginally stable is refined the same way.  Kept if finite, with relative residual
   ≤ ``VALID_RESIDUAL`` and no closed-loop eigenvalue beyond the marginal band; else NaN.
   Steps 2 and 3 are one loop (:func:`jaxsim.control._riccati_common.solve_with_fallback`).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
from jax.scipy.linalg import lu_factor, lu_solve

from jaxsim.control import _bartels_stewart as bs
from jaxsim.control._riccati_common import (
    care_measures,
    gain_matrix,
    relative_shift,
    solve_with_fallback,
    sym,
)
from jaxsim.control._symplectic_balance import balancing_exponents, scale_problem, unscale_solution

SIGN_TOL = 1e-13  # relative change at which the sign iteration stops
MAX_ITER = 100


def _jmj(m: jax.Array, n: int) -> jax.Array:
    """``J M J`` for ``J = [[0, I], [−I, 0]]`` without multiplications."""
    m11, m12, m21, m22 = m[:n, :n], m[:n, n:], m[n:, :n], m[n:, n:]
    return jnp.block([[-m22, m21], [m12, -m11]])


class _SignState(NamedTuple):
    w: jax.Array
    k: jax.Array
    change: jax.Array
    prev_change: jax.Array


def _hamiltonian_sign(a: jax.Array, g: jax.Array, q: jax.Array, active: jax.Array) -> jax.Array:
    """``W = J·sign(H)`` (symmetric), by the scaled Newton iteration on ``J H``; runs while ``active``."""
    n = a.shape[0]
    w0 = jnp.block([[-q, -a.T], [-a, g]])  # J H, symmetric
    eye = jnp.eye(2 * n, dtype=a.dtype)
    inf = jnp.asarray(jnp.inf, a.dtype)

    def body(s: _SignState) -> _SignState:
        lu, piv = lu_factor(s.w)
        log_det = jnp.sum(jnp.log(jnp.abs(jnp.diag(lu))))
        c = jnp.where(s.change > 1e-2, jnp.exp(log_det / (2 * n)), 1.0)  # |det(W/c)| = 1
        w_inv = lu_solve((lu, piv), eye)
        w_new = sym(0.5 * (s.w / c + c * _jmj(w_inv, n)))
        change = jnp.sum(jnp.abs(w_new - s.w)) / jnp.sum(jnp.abs(w_new))
        return _SignState(w_new, s.k + 1, change, s.change)

    def cond(s: _SignState) -> jax.Array:
        stagnated = (s.change < 1e-6) & (s.change >= 0.5 * s.prev_change)
        return active & (s.k < MAX_ITER) & (s.change > SIGN_TOL) & ~stagnated & ~jnp.isnan(s.change)

    return jax.lax.while_loop(cond, body, _SignState(w0, jnp.asarray(0), inf, inf)).w


def _sign_solution(a: jax.Array, g: jax.Array, q: jax.Array, active: jax.Array) -> jax.Array:
    n = a.shape[0]
    w = _hamiltonian_sign(a, g, q, active)
    # sign(H) = −J W; [I; X] spans ker(sign(H) + I):  [−W22; W12 + I] X = [W21 − I; −W11]
    eye = jnp.eye(n, dtype=a.dtype)
    lhs = jnp.concatenate([-w[n:, n:], w[:n, n:] + eye], axis=0)
    rhs = jnp.concatenate([w[n:, :n] - eye, -w[:n, :n]], axis=0)
    return sym(jnp.linalg.lstsq(lhs, rhs)[0])


def _solve_balanced(a: jax.Array, g: jax.Array, q: jax.Array) -> tuple[jax.Array, jax.Array]:
    """``(X, stability margin)`` on balanced data; ``X`` NaN if no solution passed the test."""
    eye = jnp.eye(a.shape[0], dtype=a.dtype)
    return solve_with_fallback(
        first_guess=lambda c, active: _sign_solution(a, g, q + c * eye, active),
        residual=lambda x: a.T @ x + x @ a - x @ g @ x + q,
        correction=lambda x, res: bs.continuous_lyapunov((a - g @ x).T, -res),
        measures=lambda x: care_measures(x, a, g, q),
        shift=relative_shift(q, a, g),
        template=a,
    )


def care_forward(a: jax.Array, b: jax.Array, q: jax.Array, r: jax.Array) -> tuple[jax.Array, jax.Array]:
    """The CARE's stabilising (or, failing that, maximal) solution, NaN if none was found, and its
    closed loop's stability margin (:func:`~jaxsim.control._riccati_common.stability_margin`)."""
    g = gain_matrix(b, r)
    e = balancing_exponents(a, g, q)
    ab, bb, qb = scale_problem(a, b, q, e)
    gb = gain_matrix(bb, r)
    x, margin = _solve_balanced(ab, gb, qb)
    return unscale_solution(x, e), margin
