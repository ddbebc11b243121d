"""Pieces shared by the CARE and DARE forward solvers: residuals, gains, Newton refinement.

All functions are pure JAX (jit/vmap-able) and take float arrays of matching dtype.
"""

from __future__ import annotations

from typing import Callable, NamedTuple

import jax
import jax.numpy as jnp
from jax.scipy.linalg import cho_factor, cho_solve

VALID_RESIDUAL = 1e-6  # relative residual above which a result is declared failed (NaN)
MARGINAL = 1e-5  # closed-loop stability margin below which a result is "marginal" (see stability_margin)


def sym(m: jax.Array) -> jax.Array:
    return 0.5 * (m + m.T)


def fro(m: jax.Array) -> jax.Array:
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
    """``K = (R + Bᵀ X B)⁻¹ Bᵀ X A`` (``(m, n)``); NaN where ``R + BᵀXB`` is not positive definite."""
    bx = b.T @ x
    return cho_solve(cho_factor(r + bx @ b), bx @ a)


def dare_residual(x: jax.Array, a: jax.Array, b: jax.Array, q: jax.Array, r: jax.Array) -> jax.Array:
    """``Aᵀ X A − X − Aᵀ X B (R + BᵀXB)⁻¹ Bᵀ X A + Q`` (``(n, n)``)."""
    return a.T @ x @ a - x - (a.T @ x @ b) @ dare_gain(x, a, b, r) + q


def relative_residual(res: jax.Array, *terms: jax.Array, floor: jax.Array = 0.0) -> jax.Array:
    """``‖res‖_F / max(Σ‖term‖_F, floor)`` — the residual relative to the size of the equation's terms
    (``floor``: a scale of the data, for degenerate equations whose terms all vanish at X = 0)."""
    scale = jnp.maximum(sum(fro(t) for t in terms), floor)
    return fro(res) / jnp.maximum(scale, jnp.finfo(res.dtype).tiny)


def stability_margin(acl: jax.Array, discrete: bool, scale: jax.Array = 0.0) -> jax.Array:
    """How far the closed loop's spectrum lies inside the stability boundary (positive: stable).

    Discrete time: ``1 − max |λ|``.  Continuous time: the smallest damping-like ratio
    ``−Re λ / max(|λ|, 1e-8 (‖A_cl‖₂ + scale))`` — scale-free, so a fast well-damped loop and a slow
    one score alike, while an eigenvalue within rounding of the imaginary axis (or of zero, at the
    problem's own ``scale``) scores ≈ 0.  NaN input gives NaN."""
    lam = jnp.linalg.eigvals(acl)
    if discrete:
        return 1.0 - jnp.max(jnp.abs(lam))
    floor = jnp.maximum(1e-8 * (jnp.linalg.norm(acl, 2) + scale), jnp.finfo(acl.dtype).tiny)
    return jnp.min(-lam.real / jnp.maximum(jnp.abs(lam), floor))


def data_scale(a: jax.Array, g: jax.Array, q: jax.Array) -> jax.Array:
    """``‖A‖ + ‖G‖ + ‖Q‖`` (Frobenius): the size of the (balanced) Hamiltonian's data."""
    return fro(a) + fro(g) + fro(q)


def care_measures(x, a, g, q) -> tuple[jax.Array, jax.Array]:
    """(relative residual, stability margin) of a CARE solution (balanced data, ``G = B R⁻¹ Bᵀ``)."""
    res = a.T @ x + x @ a - x @ g @ x + q
    eps = jnp.finfo(x.dtype).eps
    scale = data_scale(a, g, q)
    rel = relative_residual(res, q, a.T @ x, x @ a, x @ g @ x, floor=eps * scale)
    return rel, stability_margin(a - g @ x, discrete=False, scale=scale)


def dare_measures(x, a, b, q, r) -> tuple[jax.Array, jax.Array]:
    """(relative residual, stability margin) of a DARE solution (balanced data)."""
    k = dare_gain(x, a, b, r)
    res = a.T @ x @ a - x - (a.T @ x @ b) @ k + q
    eps = jnp.finfo(x.dtype).eps
    rel = relative_residual(res, q, x, a.T @ x @ a, a.T @ x @ b @ k, floor=eps * data_scale(a, b @ b.T, q))
    return rel, stability_margin(a - b @ k, discrete=True)


def relative_shift(q: jax.Array, a: jax.Array, g: jax.Array) -> jax.Array:
    """A positive ``c`` making ``Q + c I ≻ 0`` with a margin of the problem's own size (balanced data)."""
    lam_min = jnp.linalg.eigvalsh(q)[0]
    size = jnp.linalg.norm(q, 2) + jnp.linalg.norm(a, 2) + jnp.linalg.norm(g, 2)
    return jnp.maximum(-lam_min, 0.0) + jnp.maximum(size, jnp.finfo(q.dtype).tiny)


class _NewtonState(NamedTuple):
    x: jax.Array
    best: jax.Array
    best_norm: jax.Array
    stalls: jax.Array
    k: jax.Array


def newton(
    x0: jax.Array, residual: Callable, correction: Callable, max_steps: jax.Array, patience: int = 4
) -> jax.Array:
    """Newton (defect-correction) steps ``x ← x + correction(x, residual(x))``; returns the iterate
    with the smallest ``‖residual‖`` (``x0`` included).

    Newton–Kleinman (CARE) and Hewer (DARE) iterations from a stabilising start decrease
    monotonically to the maximal solution: quadratically when it is stabilising, linearly (rate ½,
    ``‖Res‖`` falling by about 4 per step) when its closed loop has eigenvalues on the stability
    boundary.  The loop stops after ``max_steps`` (may be traced) or once ``‖Res‖`` has not improved
    for ``patience`` steps.
    """

    def norm(x):
        v = fro(residual(x))
        return jnp.where(jnp.isfinite(v), v, jnp.inf)

    def cond(s: _NewtonState):
        return (s.k < max_steps) & (s.stalls < patience) & (s.best_norm > 0)

    def body(s: _NewtonState):
        x = sym(s.x + correction(s.x, residual(s.x)))
        rn = norm(x)
        better = rn < s.best_norm
        return _NewtonState(
            x,
            jnp.where(better, x, s.best),
            jnp.where(better, rn, s.best_norm),
            jnp.where(better, 0, s.stalls + 1),
            s.k + 1,
        )

    n0 = norm(x0)
    return jax.lax.while_loop(cond, body, _NewtonState(x0, x0, n0, jnp.asarray(0), jnp.asarray(0))).best


class _Attempt(NamedTuple):
    k: jax.Array
    x: jax.Array
    ok: jax.Array
    margin: jax.Array


POLISH_STEPS = 3  # Newton steps after the sign / doubling iteration of the first attempt
MAX_NEWTON = 80  # Newton steps of the second attempt (linear convergence near the boundary)


def solve_with_fallback(
    first_guess: Callable,
    residual: Callable,
    correction: Callable,
    measures: Callable,
    shift: jax.Array,
    template: jax.Array,
) -> tuple[jax.Array, jax.Array]:
    """The two-attempt scheme of both Riccati solvers, as one loop (one compiled body).

    Attempt 1: ``first_guess(0, True)`` (sign function / doubling) and ``POLISH_STEPS`` Newton
    steps; kept if finite, with relative residual ≤ ``VALID_RESIDUAL`` and a stable closed loop.
    Attempt 2 only when attempt 1 failed or is marginal: a failed one restarts from
    ``first_guess(shift, True)`` — the equation with ``Q + shift·I ≻ 0``, whose solution is
    stabilising — and a marginal one continues from its result; then up to ``MAX_NEWTON`` Newton
    steps down to the maximal solution, kept if its closed loop is stable up to the marginal band.

    ``first_guess(c, active)`` returns the start for ``Q + cI`` (computing nothing when not
    ``active``); ``measures(x) -> (relative residual, stability margin)``.  Returns ``(X or NaN,
    margin)``.  Under ``vmap`` the second attempt costs nothing unless a member needs it.
    """

    def body(s: _Attempt) -> _Attempt:
        retry = s.k > 0
        restart = ~retry | ~s.ok
        x0 = jnp.where(restart, first_guess(jnp.where(retry, shift, 0.0), restart), s.x)
        x = newton(x0, residual, correction, jnp.where(retry, MAX_NEWTON, POLISH_STEPS))
        rel, margin = measures(x)
        band = jnp.where(retry, -MARGINAL, 0.0)
        ok = jnp.all(jnp.isfinite(x)) & (rel <= VALID_RESIDUAL) & (margin > band)
        return _Attempt(s.k + 1, x, ok, margin)

    def cond(s: _Attempt) -> jax.Array:
        return (s.k == 0) | ((s.k == 1) & ~(s.ok & (s.margin >= MARGINAL)))

    nan = jnp.asarray(jnp.nan, template.dtype)
    s = jax.lax.while_loop(cond, body, _Attempt(jnp.asarray(0), jnp.zeros_like(template), jnp.asarray(False), nan))
    return jnp.where(s.ok, s.x, jnp.nan), s.margin
