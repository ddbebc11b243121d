"""Levenberg–Marquardt for least-squares-shaped losses ``loss(θ) = Σᵢ rᵢ(θ)²``.

Tracking-error losses (``Σ_k (e_k² + ρ u_k²)·ts``) are sums of squares: written as a residual vector
``r = (e_k √ts, √ρ u_k √ts)_k`` they let Gauss–Newton use the Jacobian ``J = ∂r/∂u`` instead of the
gradient alone, and converge in a handful of steps where Adam needs hundreds::

    problem.least_squares                 # True: ISE + control energy, averaged over scenarios
    result = levenberg_marquardt(problem) # or levenberg_marquardt(residual_fn, params0, reparam=...)
    result.params, result.loss            # loss = Σ r² at the best point

The algorithm (Marquardt scaling, Nielsen's damping rule, the stopping tests) is the pure kernel
:func:`jaxsim.core.least_squares.levenberg_marquardt_solve`.  The whole run is one
``lax.while_loop`` on the device (one host sync), compiled once per residual function,
reparametrisation, settings and shapes and cached (:mod:`optim.compile_cache`): a second call
compiles nothing.  Bounds and positivity come from ``reparam`` as in :func:`optim.tune`: the solver
works on the unconstrained ``u`` with ``θ = apply(reparam, u)``.

``TuneResult.message`` says why it stopped.

Accounting as in :func:`optim.tune`: one evaluation of the residuals with their Jacobian counts
``jac_cost`` loss evaluations (1 by default) × ``sims_per_eval``; a rejected trial costs the same
(its Jacobian is computed with its value).  The Jacobian is forward mode when the parameters are
no more than the residuals (``jac="auto"``), else reverse mode.
"""

from __future__ import annotations

import functools
import time
from typing import Any, Callable, Literal

import jax
import jax.numpy as jnp
import numpy as np
from jax.flatten_util import ravel_pytree

from jaxsim.core.least_squares import CONVERGED, STATUS, levenberg_marquardt_solve
from jaxsim.problem import Problem
from jaxsim.problem.reparam import apply, check_domain, invert
from optim.compile_cache import LRUCache, callable_key, key_or_none
from optim.results import History, TuneResult, check_int, check_number, check_some_loss_finite

JacobianMode = Literal["auto", "forward", "reverse"]

_COMPILED = LRUCache()


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
    damping = check_number("damping", damping)
    gtol, xtol, ftol = (
        check_number(n, v, allow_zero=True) for n, v in (("gtol", gtol), ("xtol", xtol), ("ftol", ftol))
    )
    jac_cost = check_number("jac_cost", jac_cost)
    if jac not in ("auto", "forward", "reverse"):
        raise ValueError(f"jac: must be 'auto', 'forward' or 'reverse', got {jac!r}")
    # NumPy: a weakly typed JAX scalar converted on the device is one more eager compilation
    x0 = jax.tree_util.tree_map(lambda a: np.asarray(a, dtype=jnp.result_type(a, float)), params0)
    if not jax.tree_util.tree_leaves(x0):
        raise ValueError("params0: must contain at least one array")
    check_domain(reparam, x0, "params0")
    t0 = time.perf_counter()
    leaves = [(leaf.shape, str(leaf.dtype)) for leaf in jax.tree_util.tree_leaves(x0)]
    key = key_or_none(
        "levenberg_marquardt",
        callable_key(residuals),
        reparam,
        jax.tree_util.tree_structure(x0),
        leaves,
        jac,
        max_steps,
        damping,
        gtol,
        xtol,
        ftol,
    )
    # everything that traces the residuals (the shape probe, the solver) or transforms the start runs
    # once per residual function and shapes; a warm call only runs the compiled programs
    built = _COMPILED.get_or_build(
        key, lambda: _build(residuals, reparam, x0, jac, max_steps, damping, gtol, xtol, ftol)
    )
    u0 = built["to_u"](x0)
    run, forward = built["run"], built["forward"]
    compile_s = time.perf_counter() - t0
    t1 = time.perf_counter()
    final = run(u0)
    state = jax.device_get(final)  # one transfer; the host reads NumPy (no eager device ops)
    wall_s = time.perf_counter() - t1

    status = int(state.status)
    steps = int(state.step)
    cost = state.cost_history[: steps + 1]
    evals = state.evals_history[: steps + 1]
    check_some_loss_finite(float(np.min(cost[np.isfinite(cost)], initial=np.inf)), "the start")
    sims = evals * jac_cost * sims_per_eval
    history = History(
        best_loss=np.minimum.accumulate(cost),
        sims=sims,
        wall_s=wall_s * np.arange(1, steps + 2) / (steps + 1),
        loss=cost,
    )
    u = final.u
    grad_inf = float(np.max(np.abs(state.J.T @ state.r)))
    return TuneResult(
        params=built["to_x"](u),
        loss=float(state.cost),
        history=history,
        n_sims=int(round(float(sims[-1]))),
        wall_s=wall_s,
        compile_s=compile_s,
        converged=status in CONVERGED,
        message=f"{STATUS[status]} after {steps} step(s); ‖Jᵀr‖∞ = {grad_inf:.3g}",
        u=u,
        n_steps=steps,
        mode="lm-forward" if forward else "lm-reverse",
        n_evals=int(state.n_evals),
        grad_cost=jac_cost,
    )


def _build(residuals: Callable, reparam: Any, x0: Any, jac: str, max_steps: int, *tols: float) -> dict[str, Any]:
    """The checked, compiled solver for one residual function and parameter shapes, with jitted
    transforms to and from the unconstrained vector ``u``."""
    damping, gtol, xtol, ftol = tols
    unravels = []

    def flat_start(x: Any) -> jax.Array:
        flat, unravel = ravel_pytree(invert(reparam, x))
        unravels.append(unravel)  # static: shapes, dtypes and the tree
        return flat

    # traced, not run: an eager ``invert`` compiled one small program per operation (≈ 0.1 s cold)
    u0 = jax.eval_shape(flat_start, x0)
    unravel = unravels[0]

    def flat_residuals(u: jax.Array) -> jax.Array:
        return jnp.ravel(residuals(apply(reparam, unravel(u))))

    out = jax.eval_shape(lambda u: jnp.asarray(residuals(apply(reparam, unravel(u)))), u0)
    if out.ndim != 1 or out.shape[0] == 0 or not jnp.issubdtype(out.dtype, jnp.floating):
        raise ValueError(f"residuals: must return a non-empty real vector, got shape {out.shape} dtype {out.dtype}")
    forward = jac == "forward" or (jac == "auto" and u0.shape[0] <= out.shape[0])
    solve = functools.partial(
        levenberg_marquardt_solve,
        flat_residuals,
        max_steps=max_steps,
        damping=damping,
        gtol=gtol,
        xtol=xtol,
        ftol=ftol,
        forward=forward,
    )
    return {
        "run": jax.jit(solve).lower(u0).compile(),
        "forward": forward,
        "to_u": jax.jit(flat_start),
        "to_x": jax.jit(lambda u: apply(reparam, unravel(u))),
    }
