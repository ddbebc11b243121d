"""Hybrid tuner: a short global phase (particle swarm or CMA-ES), then gradient polishing.

:func:`hybrid` runs :func:`optim.pso` or :func:`optim.cmaes.cmaes` on a small budget to find the
right basin, then :func:`optim.tune` (L-BFGS by default) from the best point found, and returns
one :class:`~optim.results.TuneResult` whose history is the global phase's followed by the
polishing phase's (simulations and seconds continue from where the global phase stopped; the
best-so-far loss never rises).  The polishing start is the global best moved ``1e-6`` of the box
inside it, because the space's reparametrisation (``Interval``: a sigmoid) cannot start on a bound.
"""

from __future__ import annotations

from typing import Any, Callable, Literal

import jax
import numpy as np
import optax

from jaxsim.problem import Problem
from jaxsim.problem.reparam import Interval
from optim.lbfgs import lbfgs
from optim.results import History, TuneResult, as_box

GlobalPhase = Literal["pso", "cmaes"]
INSIDE = 1e-6  # fraction of the box a polishing start keeps from the bounds


def default_polisher() -> optax.GradientTransformation:
    """:func:`optim.lbfgs.lbfgs` with at most 20 step cuts per search, as the PID study uses it."""
    return lbfgs(max_backtracking_steps=20)


def _inside(z: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    return lo + np.clip((z - lo) / (hi - lo), INSIDE, 1 - INSIDE) * (hi - lo)


def join_histories(first: History, second: History) -> History:
    """``first`` then ``second``: sims and seconds of ``second`` offset by ``first``'s last values,
    best-so-far losses as the running minimum over both (per-start fields are dropped)."""
    best = np.concatenate([first.best_loss, np.minimum(second.best_loss, first.best_loss[-1])])
    both_loss = first.loss is not None and second.loss is not None
    return History(
        best_loss=np.minimum.accumulate(best),
        sims=np.concatenate([first.sims, second.sims + first.sims[-1]]),
        wall_s=np.concatenate([first.wall_s, second.wall_s + first.wall_s[-1]]),
        loss=np.concatenate([first.loss, second.loss]) if both_loss else None,
    )


def hybrid(
    loss: Problem | Callable[[jax.Array], jax.Array],
    lo: Any = None,
    hi: Any = None,
    *,
    method: GlobalPhase = "pso",
    popsize: int = 16,
    iters: int = 20,
    key: jax.Array | None = None,
    optimizer: optax.GradientTransformation | None = None,
    steps: int = 100,
    global_options: dict[str, Any] | None = None,
    tune_options: dict[str, Any] | None = None,
) -> TuneResult:
    """Minimise a :class:`~jaxsim.problem.Problem` (or ``loss(x)`` over ``lo ≤ x ≤ hi``) by a global
    phase of ``iters`` iterations of ``popsize`` candidates (``method``: ``"pso"`` or ``"cmaes"``,
    more settings in ``global_options``), then at most ``steps`` gradient steps of :func:`optim.tune`
    with ``optimizer`` (default :func:`default_polisher`, more settings in ``tune_options``) from
    the global phase's best point.

    A Problem is polished in its space's reparametrisation; a plain loss in ``Interval(lo, hi)``, so
    both phases stay in the box.  ``key`` (default ``PRNGKey(0)``) seeds the global phase; the
    polishing phase gets ``fold_in(key, 1)`` (used only for its extra starts).

    Returns the better of the two phases' points (the polishing phase keeps its start, so it is
    normally that one): ``params``, ``loss`` (for a Problem with constraints, the swarm's loss is
    penalised and the polisher's is not), ``history`` (:func:`join_histories`), ``n_sims``,
    ``wall_s`` and ``compile_s`` summed, ``converged`` and ``message`` of the polishing phase (with
    the global phase's message), ``mode`` e.g. ``"pso+reverse"``.
    """
    from optim.cmaes import cmaes
    from optim.pso import pso
    from optim.tune import tune

    if method not in ("pso", "cmaes"):
        raise ValueError(f"method: must be 'pso' or 'cmaes', got {method!r}")
    problem = loss if isinstance(loss, Problem) else None
    if problem is None:
        if lo is None or hi is None:
            raise ValueError("lo/hi: required for a plain loss function (a Problem brings space.box)")
        lo, hi = as_box(lo, hi)
    elif lo is not None or hi is not None:
        raise ValueError("lo/hi: a Problem brings its own box (problem.space.box)")
    key = jax.random.PRNGKey(0) if key is None else key
    box = () if problem is not None else (lo, hi)
    g_opts = dict(global_options or {})
    if method == "pso":
        first = pso(loss, *box, n_particles=popsize, n_iters=iters, key=key, **g_opts)
    else:
        first = cmaes(loss, *box, popsize=popsize, iters=iters, key=key, **g_opts)

    b_lo, b_hi = (np.asarray(v) for v in (problem.space.box if problem is not None else (lo, hi)))
    z = _inside(np.asarray(first.u, float), b_lo, b_hi)
    t_opts = dict(tune_options or {})
    t_opts.setdefault("key", jax.random.fold_in(key, 1))
    optimizer = default_polisher() if optimizer is None else optimizer
    if problem is not None:
        second = tune(problem, problem.space.from_search(z), optimizer=optimizer, steps=steps, **t_opts)
    else:
        second = tune(loss, z, optimizer=optimizer, steps=steps, reparam=Interval(lo, hi), **t_opts)

    polished = second.loss <= first.loss
    best = second if polished else first
    return TuneResult(
        params=best.params,
        loss=float(min(first.loss, second.loss)),
        history=join_histories(first.history, second.history),
        n_sims=int(first.n_sims + second.n_sims),
        wall_s=float(first.wall_s + second.wall_s),
        compile_s=float(first.compile_s + second.compile_s),
        converged=bool(second.converged),
        message=f"{method}: {first.message}; then gradient ({second.mode}): {second.message}",
        start_index=int(second.start_index) if polished else 0,
        u=second.u if polished else first.u,
        constraint_violation=float(second.constraint_violation) if polished else 0.0,
        multipliers=second.multipliers if polished else None,
        n_steps=int(first.n_steps + second.n_steps),
        mode=f"{method}+{second.mode}",
    )
