"""Levenberg–Marquardt, the pure kernel: minimise ``Σ f(u)²`` over a flat ``u``.

The step solves ``(JᵀJ + μ D) δ = −Jᵀr`` with Marquardt's scaling ``D`` (the running maximum of the
diagonal of ``JᵀJ``, as MINPACK does, so the iterates do not depend on the units of ``u``); a step
is accepted when the gain ratio ``ρ = (‖r‖² − ‖r(u+δ)‖²) / (‖r‖² − ‖r + Jδ‖²)`` exceeds 10⁻⁴, and
the damping follows Nielsen's rule (``μ ← μ·max(1/3, 1 − (2ρ − 1)³)`` on success, ``μ ← μ·ν,
ν ← 2ν`` on failure).  The run is one ``lax.while_loop``, so the kernel composes with ``jit`` and
``vmap`` (one fit per Monte-Carlo record).

Stopping (:data:`STATUS`): the gradient ``‖Jᵀr‖∞ ≤ gtol``; an accepted step with
``‖δ‖ ≤ xtol·(‖u‖ + xtol)``; an accepted step whose actual and predicted relative reductions are
both ``≤ ftol``; the damping above 10¹⁶ (no step reduces the loss); a non-finite residual at the
start; or ``max_steps`` trials.  Each trial evaluates the residuals with their Jacobian.

:func:`optim.least_squares.levenberg_marquardt` wraps it for parameter pytrees, reparametrisations
and :class:`~jaxsim.problem.Problem` s (compiled once and cached, a ``TuneResult``).
"""

from __future__ import annotations

from typing import Callable, NamedTuple

import jax
import jax.numpy as jnp

__all__ = ["CONVERGED", "LMState", "STATUS", "levenberg_marquardt_solve"]

MAX_DAMPING = 1e16
"""Damping beyond which no step can reduce the loss (the step is then below rounding of ``u``)."""

ACCEPT_RATIO = 1e-4
"""Smallest gain ratio (actual / predicted reduction) of an accepted step."""

STATUS = {
    0: "running",
    1: "gradient norm ≤ gtol",
    2: "step ≤ xtol (relative)",
    3: "relative reduction ≤ ftol",
    4: "max_steps reached",
    5: f"damping above {MAX_DAMPING:g}: no step reduces the loss",
    6: "residuals not finite at the start",
}
CONVERGED = (1, 2, 3)
"""Status codes that mean convergence (as opposed to running out of steps or stalling)."""


class LMState(NamedTuple):
    """The loop's carry: the point ``u (n,)``, its residuals ``r (m,)`` and Jacobian ``J (m, n)``,
    ``cost = Σ r²``, the damping ``mu`` and its growth factor ``nu``, Marquardt's scaling
    ``scale (n,)``, the step counter, evaluations made, the status code (:data:`STATUS`) and the
    cost and evaluation count after each step (``(max_steps + 1,)``; index 0: the start)."""

    u: jax.Array
    r: jax.Array
    J: jax.Array
    cost: jax.Array
    mu: jax.Array
    nu: jax.Array
    scale: jax.Array
    step: jax.Array
    n_evals: jax.Array
    status: jax.Array
    cost_history: jax.Array
    evals_history: jax.Array


def _value_and_jacobian(f: Callable[[jax.Array], jax.Array], forward: bool) -> Callable:
    def with_aux(u: jax.Array) -> tuple[jax.Array, jax.Array]:
        r = f(u)
        return r, r

    jac = jax.jacfwd(with_aux, has_aux=True) if forward else jax.jacrev(with_aux, has_aux=True)

    def value_and_jacobian(u: jax.Array) -> tuple[jax.Array, jax.Array]:
        J, r = jac(u)
        return r, J

    return value_and_jacobian


def levenberg_marquardt_solve(
    f: Callable[[jax.Array], jax.Array],
    u0: jax.Array,
    *,
    max_steps: int,
    damping: float = 1e-3,
    gtol: float = 1e-10,
    xtol: float = 1e-12,
    ftol: float = 1e-12,
    forward: bool | None = None,
) -> LMState:
    """Minimise ``Σ f(u)²`` from ``u0 (n,)`` (``f(u) -> (m,)``); pure, ``jit``/``vmap``-able (the sizes and
    settings are static).  ``forward``: the Jacobian by forward mode (``None``: iff ``n ≤ m``).
    Returns the final :class:`LMState` (``status`` in :data:`STATUS`)."""
    m = jax.eval_shape(f, jnp.asarray(u0)).shape[0]  # the residuals' length (traced once, not run)
    if forward is None:
        forward = u0.shape[0] <= m
    mu0 = damping
    value_and_jacobian = _value_and_jacobian(f, forward)

    def gradient_small(r: jax.Array, J: jax.Array) -> jax.Array:
        return jnp.max(jnp.abs(J.T @ r)) <= gtol

    # The start is the loop's first evaluation (``n_evals == 0``: taken whatever its cost), so the
    # compiled loop holds one copy of the residuals' Jacobian program, not a second one before it.
    def body(s: LMState) -> LMState:
        started = s.n_evals > 0
        g = s.J.T @ s.r
        A = s.J.T @ s.J
        scale = jnp.where(started, jnp.maximum(s.scale, jnp.diagonal(A)), s.scale)
        system = jnp.where(started, A + s.mu * jnp.diag(scale), jnp.eye(A.shape[0], dtype=A.dtype))
        delta = jnp.linalg.solve(system, -g)
        predicted = -(2.0 * delta @ g + delta @ A @ delta)  # ‖r‖² − ‖r + Jδ‖²
        u_new = jnp.where(started, s.u + delta, s.u)
        r_new, J_new = value_and_jacobian(u_new)
        cost_new = r_new @ r_new
        finite = jnp.isfinite(cost_new) & jnp.all(jnp.isfinite(J_new))
        actual = s.cost - cost_new
        ratio = actual / predicted
        accept = ~started | (finite & (predicted > 0) & (ratio > ACCEPT_RATIO))
        mu_ok = s.mu * jnp.maximum(1.0 / 3.0, 1.0 - (2.0 * ratio - 1.0) ** 3)
        mu = jnp.where(started, jnp.where(accept, mu_ok, s.mu * s.nu), s.mu)
        nu = jnp.where(started, jnp.where(accept, 2.0, 2.0 * s.nu), s.nu)
        u, r, J, cost = (
            jnp.where(accept, new, old) for new, old in ((u_new, s.u), (r_new, s.r), (J_new, s.J), (cost_new, s.cost))
        )
        step = s.step + started.astype(s.step.dtype)
        n_evals = s.n_evals + 1
        small_step = started & accept & (jnp.linalg.norm(delta) <= xtol * (jnp.linalg.norm(s.u) + xtol))
        small_gain = started & accept & (actual <= ftol * s.cost) & (predicted <= ftol * s.cost)
        status = jnp.select(
            [~finite & ~started, gradient_small(r, J), small_step, small_gain, mu > MAX_DAMPING, step >= max_steps],
            [6, 1, 2, 3, 5, 4],
            0,
        ).astype(jnp.int32)
        return LMState(
            u,
            r,
            J,
            cost,
            mu,
            nu,
            scale,
            step,
            n_evals,
            status,
            s.cost_history.at[step].set(cost),
            s.evals_history.at[step].set(n_evals),
        )

    def run(u0: jax.Array) -> LMState:
        u0 = jnp.asarray(u0)
        n, dtype = u0.shape[0], u0.dtype
        state = LMState(
            u0,
            jnp.zeros((m,), dtype),
            jnp.zeros((m, n), dtype),
            jnp.asarray(jnp.inf, dtype),
            jnp.asarray(mu0, dtype),
            jnp.asarray(2.0, dtype),
            jnp.zeros_like(u0),
            jnp.asarray(0, jnp.int32),
            jnp.asarray(0, jnp.int32),
            jnp.asarray(0, jnp.int32),
            jnp.full((max_steps + 1,), jnp.inf, dtype),
            jnp.ones((max_steps + 1,), jnp.int32),
        )
        return jax.lax.while_loop(lambda s: s.status == 0, body, state)

    return run(u0)
