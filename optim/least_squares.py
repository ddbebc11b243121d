"""Levenberg–Marquardt for least-squares-shaped losses ``loss(θ) = Σᵢ rᵢ(θ)²``.

Tracking-error losses (``Σ_k (e_k² + ρ u_k²)·ts``) are sums of squares: written as a residual vector
``r = (e_k √ts, √ρ u_k √ts)_k`` they let Gauss–Newton use the Jacobian ``J = ∂r/∂u`` instead of the
gradient alone, and converge in a handful of steps where Adam needs hundreds::

    result = levenberg_marquardt(PIDTuning().residuals, jnp.array([1.0, 1.0, 0.1]))
    result.params, result.loss            # loss = Σ r² at the best point

The step solves ``(JᵀJ + μ D) δ = −Jᵀr`` with Marquardt's scaling ``D`` (the running maximum of the
diagonal of ``JᵀJ``, as MINPACK does, so the iterates do not depend on the units of ``u``); a step
is accepted when the gain ratio ``ρ = (‖r‖² − ‖r(u+δ)‖²) / (‖r‖² − ‖r + Jδ‖²)`` exceeds 10⁻⁴, and
the damping follows Nielsen's rule (``μ ← μ·max(1/3, 1 − (2ρ − 1)³)`` on success, ``μ ← μ·ν,
ν ← 2ν`` on failure).

The whole run is one ``lax.while_loop`` on the device (one host sync), compiled once per residual
function, reparametrisation, settings and shapes and cached (:mod:`optim.compile_cache`): a second
call compiles nothing.  Bounds and positivity come from ``reparam`` as in :func:`optim.tune`: the
solver works on the unconstrained ``u`` with ``θ = apply(reparam, u)``.

Stopping (``TuneResult.message`` says which): the gradient ``‖Jᵀr‖∞ ≤ gtol``; an accepted step with
``‖δ‖ ≤ xtol·(‖u‖ + xtol)``; an accepted step whose actual and predicted relative reductions are
both ``≤ ftol``; the damping above 10¹⁶ (no step reduces the loss); a non-finite residual at the
start; or ``max_steps``.

Accounting as in :func:`optim.tune`: one evaluation of the residuals with their Jacobian counts
``jac_cost`` loss evaluations (1 by default) × ``sims_per_eval``; a rejected trial costs the same
(its Jacobian is computed with its value).  The Jacobian is forward mode when the parameters are
no more than the residuals (``jac="auto"``), else reverse mode.
"""

from __future__ import annotations

import time
from typing import Any, Callable, Literal, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax.flatten_util import ravel_pytree

from jaxsim.problem import Problem
from jaxsim.problem.reparam import apply, check_domain, invert
from optim.compile_cache import LRUCache, callable_key, key_or_none
from optim.results import History, TuneResult, check_int, check_some_loss_finite

JacobianMode = Literal["auto", "forward", "reverse"]

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
_CONVERGED = (1, 2, 3)

_COMPILED = LRUCache()


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


def _solver(
    f: Callable[[jax.Array], jax.Array],
    forward: bool,
    max_steps: int,
    mu0: float,
    gtol: float,
    xtol: float,
    ftol: float,
) -> Callable[[jax.Array], LMState]:
    """The whole run as one function of the flat start ``u0``."""
    value_and_jacobian = _value_and_jacobian(f, forward)

    def gradient_small(r: jax.Array, J: jax.Array) -> jax.Array:
        return jnp.max(jnp.abs(J.T @ r)) <= gtol

    def body(s: LMState) -> LMState:
        g = s.J.T @ s.r
        A = s.J.T @ s.J
        scale = jnp.maximum(s.scale, jnp.diagonal(A))
        delta = jnp.linalg.solve(A + s.mu * jnp.diag(scale), -g)
        predicted = -(2.0 * delta @ g + delta @ A @ delta)  # ‖r‖² − ‖r + Jδ‖²
        u_new = s.u + delta
        r_new, J_new = value_and_jacobian(u_new)
        cost_new = r_new @ r_new
        actual = s.cost - cost_new
        ratio = actual / predicted
        accept = jnp.isfinite(cost_new) & jnp.all(jnp.isfinite(J_new)) & (predicted > 0) & (ratio > ACCEPT_RATIO)
        mu_ok = s.mu * jnp.maximum(1.0 / 3.0, 1.0 - (2.0 * ratio - 1.0) ** 3)
        mu = jnp.where(accept, mu_ok, s.mu * s.nu)
        nu = jnp.where(accept, 2.0, 2.0 * s.nu)
        u, r, J, cost = (
            jnp.where(accept, new, old) for new, old in ((u_new, s.u), (r_new, s.r), (J_new, s.J), (cost_new, s.cost))
        )
        step = s.step + 1
        n_evals = s.n_evals + 1
        small_step = accept & (jnp.linalg.norm(delta) <= xtol * (jnp.linalg.norm(s.u) + xtol))
        small_gain = accept & (actual <= ftol * s.cost) & (predicted <= ftol * s.cost)
        status = jnp.select(
            [gradient_small(r, J), small_step, small_gain, mu > MAX_DAMPING, step >= max_steps],
            [1, 2, 3, 5, 4],
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
        r0, J0 = value_and_jacobian(u0)
        cost0 = r0 @ r0
        finite = jnp.isfinite(cost0) & jnp.all(jnp.isfinite(J0))
        status0 = jnp.where(finite, jnp.where(gradient_small(r0, J0), 1, 0), 6)
        status0 = jnp.where((status0 == 0) & (max_steps == 0), 4, status0)
        state = LMState(
            u0,
            r0,
            J0,
            cost0,
            jnp.asarray(mu0, u0.dtype),
            jnp.asarray(2.0, u0.dtype),
            jnp.zeros_like(u0),
            jnp.asarray(0, jnp.int32),
            jnp.asarray(1, jnp.int32),
            jnp.asarray(status0, jnp.int32),
            jnp.full((max_steps + 1,), cost0),
            jnp.ones((max_steps + 1,), jnp.int32),
        )
        return jax.lax.while_loop(lambda s: s.status == 0, body, state)

    return run


def _check_positive(name: str, value: Any, allow_zero: bool = False) -> float:
    v = float(value)
    if not np.isfinite(v) or v < 0 or (v == 0 and not allow_zero):
        raise ValueError(
            f"{name}: must be a finite {'non-negative' if allow_zero else 'positive'} number, got {value!r}"
        )
    return v


def levenberg_marquardt(
    residuals: Problem | Callable[[Any], jax.Array],
    params0: Any = None,
    *,
    reparam: Any = None,
    max_steps: int = 100,
    damping: float = 1e-3,
    gtol: float = 1e-10,
    xtol: float = 1e-12,
    ftol: float = 1e-12,
    jac: JacobianMode = "auto",
    sims_per_eval: int | None = None,
    jac_cost: float = 1.0,
) -> TuneResult:
    """Minimise ``Σ r(θ)²`` from ``params0`` by Levenberg–Marquardt (see the module docstring).

    ``residuals(params) -> (m,)``: a pure JAX function of a params pytree shaped like ``params0``; or a
    :class:`~jaxsim.problem.Problem` with a residual form (:attr:`~jaxsim.problem.Problem.least_squares`),
    whose ``space.init``, ``space.reparam`` and scenarios per evaluation are the defaults (a problem
    with constraints is refused: use :func:`optim.tune`).
    ``reparam``: as in :func:`optim.tune` (``None``: unconstrained); ``damping``: the initial ``μ``
    (relative to the scaled diagonal of ``JᵀJ``); ``max_steps``: trials (accepted or not).  Returns a
    :class:`~optim.results.TuneResult` whose ``loss`` is ``Σ r²`` at ``params``, ``n_steps`` the
    trials, ``n_evals`` the residual-and-Jacobian evaluations, ``u`` the unconstrained point,
    ``mode`` ``"lm-forward"`` or ``"lm-reverse"``; the history's per-step seconds split the device
    run's time evenly over its steps (one host sync for the whole run).
    """
    if isinstance(residuals, Problem):
        problem = residuals
        if not problem.least_squares:
            problem.residuals(problem.space.init)  # raises, saying why
        if problem.constraints is not None:
            raise ValueError(
                f"problem {problem.name!r}: has constraints, which Levenberg–Marquardt does not take; use tune"
            )
        residuals = problem.residuals
        params0 = problem.space.init if params0 is None else params0
        reparam = problem.space.reparam if reparam is None else reparam
        sims_per_eval = problem.sims_per_eval if sims_per_eval is None else sims_per_eval
    elif not callable(residuals):
        raise ValueError(
            f"residuals: must be a Problem or a callable params -> (m,) array, got {type(residuals).__name__}"
        )
    if params0 is None:
        raise ValueError("params0: required with a residual function (a Problem supplies space.init)")
    max_steps = check_int("max_steps", max_steps, low=0)
    sims_per_eval = check_int("sims_per_eval", 1 if sims_per_eval is None else sims_per_eval)
    damping = _check_positive("damping", damping)
    gtol, xtol, ftol = (
        _check_positive(n, v, allow_zero=True) for n, v in (("gtol", gtol), ("xtol", xtol), ("ftol", ftol))
    )
    jac_cost = _check_positive("jac_cost", jac_cost)
    if jac not in ("auto", "forward", "reverse"):
        raise ValueError(f"jac: must be 'auto', 'forward' or 'reverse', got {jac!r}")
    x0 = jax.tree_util.tree_map(lambda a: jnp.asarray(a, dtype=jnp.result_type(a, float)), params0)
    if not jax.tree_util.tree_leaves(x0):
        raise ValueError("params0: must contain at least one array")
    check_domain(reparam, x0, "params0")
    u0, unravel = ravel_pytree(invert(reparam, x0))

    def flat_residuals(u: jax.Array) -> jax.Array:
        return jnp.ravel(residuals(apply(reparam, unravel(u))))

    out = jax.eval_shape(lambda u: jnp.asarray(residuals(apply(reparam, unravel(u)))), u0)
    if out.ndim != 1 or out.shape[0] == 0 or not jnp.issubdtype(out.dtype, jnp.floating):
        raise ValueError(f"residuals: must return a non-empty real vector, got shape {out.shape} dtype {out.dtype}")
    forward = jac == "forward" or (jac == "auto" and u0.shape[0] <= out.shape[0])

    t0 = time.perf_counter()
    key = key_or_none(
        "levenberg_marquardt",
        callable_key(residuals),
        reparam,
        jax.tree_util.tree_structure(x0),
        [(leaf.shape, str(leaf.dtype)) for leaf in jax.tree_util.tree_leaves(x0)],
        forward,
        max_steps,
        damping,
        gtol,
        xtol,
        ftol,
    )
    run = _COMPILED.get_or_build(
        key,
        lambda: jax.jit(_solver(flat_residuals, forward, max_steps, damping, gtol, xtol, ftol)).lower(u0).compile(),
    )
    compile_s = time.perf_counter() - t0
    t1 = time.perf_counter()
    state = jax.block_until_ready(run(u0))
    wall_s = time.perf_counter() - t1

    status = int(state.status)
    steps = int(state.step)
    cost = np.asarray(state.cost_history[: steps + 1])
    evals = np.asarray(state.evals_history[: steps + 1])
    check_some_loss_finite(float(np.min(cost[np.isfinite(cost)], initial=np.inf)), "the start")
    sims = evals * jac_cost * sims_per_eval
    history = History(
        best_loss=np.minimum.accumulate(cost),
        sims=sims,
        wall_s=wall_s * np.arange(1, steps + 2) / (steps + 1),
        loss=cost,
    )
    u = state.u
    return TuneResult(
        params=apply(reparam, unravel(u)),
        loss=float(state.cost),
        history=history,
        n_sims=int(round(float(sims[-1]))),
        wall_s=wall_s,
        compile_s=compile_s,
        converged=status in _CONVERGED,
        message=f"{STATUS[status]} after {steps} step(s); ‖Jᵀr‖∞ = {float(jnp.max(jnp.abs(state.J.T @ state.r))):.3g}",
        u=u,
        n_steps=steps,
        mode="lm-forward" if forward else "lm-reverse",
        n_evals=int(state.n_evals),
        grad_cost=jac_cost,
    )
