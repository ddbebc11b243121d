"""Symplectic balancing of a Riccati equation: a state scaling by powers of two.

A change of state units ``x = D x̃`` (``D = diag(d)``) maps a Riccati problem ``(A, G, Q)`` with
``G = B R⁻¹ Bᵀ`` to ``(D⁻¹AD, D⁻¹GD⁻¹, DQD)`` and its solution to ``X̃ = D X D``.  It is a diagonal
*symplectic* similarity ``diag(D⁻¹, D)`` of the Hamiltonian ``[[A, −G], [−Q, −Aᵀ]]`` (and of the
discrete symplectic pencil), so it changes no eigenvalue — but a badly scaled problem (position in
nanometres, states spanning twelve decades) defeats the sign-function / doubling iterations and
every rank or stability threshold.

:func:`balancing_exponents` chooses ``d = 2^e`` (integers ``e``, so the scaling itself is exact in
floating point) that minimise the Frobenius norm of the scaled Hamiltonian's off-diagonal part,

    f(e) = Σ_{i≠j} A_ij² 4^{e_j−e_i} + Σ_{ij} G_ij² 4^{−e_i−e_j} + Σ_{ij} Q_ij² 4^{e_i+e_j},

a convex function of the real exponents.  A scaling of the *input* problem by ``T = diag(t)``
translates ``f`` by ``log₂ t``, so the minimiser moves with it: the balanced problem is the same,
up to the rounding of ``e`` to integers, whatever state units the caller chose.  This is the
property that makes the solvers' verdict and accuracy independent of units.

Where the data do not pin a coordinate down (only terms that push one way, e.g. ``A = 0, Q = 0``),
``f`` has no finite minimiser: such a coordinate is left where it is when nothing pulls back at
all, and otherwise stops at ``|e| = MAX_EXPONENT``.  (A regularising "spring" towards ``e = 0``
would break the unit invariance: data spanning 24 decades leave some coordinates with terms far
below any fixed fraction of the others.)

The minimiser is found by damped Jacobi sweeps in the spirit of Osborne's balancing: each
coordinate's function is ``α/t + βt + γ/t² + δt²`` (``t = 4^{e_i}``), whose minimiser with the
quartic terms frozen is ``t² = (α + 2γ/t)/(β + 2δt)``; every exponent moves half-way there, all at
once (a few matrix–vector products per sweep).  A bounded loop keeps it jittable and vmappable.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

MAX_ITER = 200  # sweeps, at most
STEP_TOL = 0.02  # stop when no exponent moves more than this (log₂ units; they are rounded anyway)
MAX_EXPONENT = 100.0  # |e| bound: squares of 2^±100-scaled entries stay far inside float64's range


class _State(NamedTuple):
    e: jax.Array
    moved: jax.Array
    k: jax.Array


def balancing_exponents(a: jax.Array, g: jax.Array, q: jax.Array) -> jax.Array:
    """Integer exponents ``e`` (``(n,)``, float dtype) of the balancing scaling ``D = diag(2^e)``.

    Args:
        a: ``(n, n)`` state matrix; g: ``(n, n)`` ``B R⁻¹ Bᵀ`` (or ``B Bᵀ``: only magnitudes matter);
        q: ``(n, n)`` state weight.  Non-finite entries give zero exponents (no scaling).
    """
    n = a.shape[0]
    finite = jnp.all(jnp.isfinite(a)) & jnp.all(jnp.isfinite(g)) & jnp.all(jnp.isfinite(q))
    eye = jnp.eye(n, dtype=a.dtype)
    a2 = jnp.where(finite, a * a, 0.0) * (1.0 - eye)
    g2 = jnp.where(finite, g * g, 0.0)
    q2 = jnp.where(finite, q * q, 0.0)
    g_off, q_off = g2 * (1.0 - eye), q2 * (1.0 - eye)
    g_diag, q_diag = jnp.diag(g2), jnp.diag(q2)
    ln4 = jnp.log(4.0)

    def body(s: _State) -> _State:
        t = jnp.exp(ln4 * s.e)  # d_i²; coordinate i's function is α/t_i + β t_i + γ/t_i² + δ t_i²
        alpha = a2 @ t + 2 * g_off @ (1 / t)
        beta = a2.T @ (1 / t) + 2 * q_off @ t
        # its minimiser, with the quartic terms frozen at the current t_i: t_i² = (α + 2γ/t_i)/(β + 2δ t_i)
        target = 0.5 * (jnp.log(alpha + 2 * g_diag / t) - jnp.log(beta + 2 * q_diag * t)) / ln4
        e = jnp.clip(0.5 * (s.e + target), -MAX_EXPONENT, MAX_EXPONENT)  # damped Jacobi step
        e = jnp.where(jnp.isfinite(e), e, s.e)
        return _State(e, jnp.max(jnp.abs(e - s.e), initial=0.0), s.k + 1)

    def cond(s: _State) -> jax.Array:
        return (s.moved > STEP_TOL) & (s.k < MAX_ITER)

    zero = jnp.zeros(n, dtype=a2.dtype)
    e = jax.lax.while_loop(cond, body, _State(zero, jnp.asarray(jnp.inf, a2.dtype), jnp.asarray(0))).e
    return jnp.round(e)


def scale_problem(a, b, q, e):
    """``(D⁻¹AD, D⁻¹B, DQD)`` for ``D = diag(2^e)`` (exact: powers of two)."""
    d = jnp.exp2(e)
    return a * (d[None, :] / d[:, None]), b / d[:, None], q * (d[:, None] * d[None, :])


def unscale_solution(x, e):
    """``X = D⁻¹ X̃ D⁻¹`` (exact)."""
    d = jnp.exp2(-e)
    return x * (d[:, None] * d[None, :])


@jax.jit
def balance_pair(a: jax.Array, b: jax.Array) -> tuple[jax.Array, jax.Array]:
    """``(D⁻¹AD, D⁻¹B)`` with the balancing of ``(A, BBᵀ, 0)``: a pair in state units that make its
    rank and eigenvalue thresholds independent of the units the caller chose."""
    e = balancing_exponents(a, b @ b.T, jnp.zeros_like(a))
    ab, bb, _ = scale_problem(a, b, jnp.zeros_like(a), e)
    return ab, bb
