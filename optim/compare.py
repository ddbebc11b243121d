"""Comparison harness: several tuners on one loss, their best-so-far curves, a table and a plot.

``compare(problem, tuners=("gradient", "pso", "random"), budget=640)`` gives each standard tuner
(:func:`standard_tuners`) the same budget of simulations on a :class:`~jaxsim.problem.Problem`;
``compare({"gradient": lambda: tune(...), "pso": lambda: pso(...), ...})`` runs any zero-argument
callables.  Each tuner runs once and its history is read (every tuner returns
:class:`optim.results.TuneResult`, with ``best_loss``, ``sims`` and ``wall_s`` per step).  The
harness reports what each used — simulations; with ``grad_cost="measure"`` in loss-evaluation
equivalents, so a gradient evaluation counts what it costs (:func:`optim.tune.grad_cost`, several
loss evaluations), not one — and, for the equal-budget view, the best loss each tuner had
reached by the smallest budget any of them used — of simulations (``loss_at_common_sims``) and of
seconds (``loss_at_common_seconds``).

A study that tunes puts ``Comparison.rows`` in its tables, :func:`comparison_metrics` in its metrics
and :func:`plot_comparison` in its figures (see ``experiments/pid_tuning_comparison.py``).
"""

from __future__ import annotations

import time
from typing import Any, Callable, NamedTuple, Sequence

import jax
import numpy as np
import optax

from jaxsim.problem import Problem

STANDARD_TUNERS = ("gradient", "pso", "random", "grid", "cmaes", "hybrid")


class Curve(NamedTuple):
    """Best loss so far of one tuner, ``(T,)`` arrays, against simulations and seconds."""

    sims: np.ndarray
    seconds: np.ndarray
    best_loss: np.ndarray


class Comparison(NamedTuple):
    """``rows``: one dict per tuner (table rows); ``curves``: name → :class:`Curve`;
    ``results``: name → the tuner's own result object."""

    rows: list[dict[str, Any]]
    curves: dict[str, Curve]
    results: dict[str, Any]


def best_within(curve: Curve, *, sims: float | None = None, seconds: float | None = None) -> float:
    """Best loss the tuner had reached within a budget of ``sims`` simulations and/or ``seconds``
    (``inf`` if it had not finished its first step by then)."""
    ok = np.ones(curve.best_loss.shape, bool)
    if sims is not None:
        ok &= curve.sims <= sims * (1 + 1e-12)
    if seconds is not None:
        ok &= curve.seconds <= seconds * (1 + 1e-12)
    return float(np.min(curve.best_loss[ok])) if np.any(ok) else float("inf")


def _params_of(result: Any, problem: Problem | None = None) -> Any:
    x = result.params
    if problem is not None and isinstance(x, dict):
        try:
            return problem.space.flat(x)
        except (KeyError, TypeError, ValueError):
            pass
    try:
        return np.concatenate([np.ravel(np.asarray(v, float)) for v in jax.tree_util.tree_leaves(x)]).tolist()
    except (TypeError, ValueError):
        return str(x)


def standard_tuners(
    problem: Problem,
    budget: int,
    names: Sequence[str] = ("gradient", "pso", "random"),
    *,
    key: Any = None,
    learning_rate: float = 0.05,
    n_starts: int = 4,
    init_spread: float = 1.0,
    n_particles: int = 32,
    batch_size: int = 256,
    grad_cost: float | str | None = None,
    progress: Any = False,
) -> dict[str, Callable[[], Any]]:
    """Zero-argument runs of the standard tuners on ``problem``, each given ``budget`` simulations.

    * ``gradient``: :func:`optim.tune`, Adam(``learning_rate``) in the space's reparametrisation,
      ``n_starts`` starts (start 0 at ``space.init``, the others spread by ``init_spread``),
      ``⌊budget / (n_starts·S·c)⌋`` steps (at least 1; ``S`` = scenarios per loss evaluation,
      ``c`` = what one gradient evaluation costs in loss evaluations: ``grad_cost`` — 1 by default
      (reproducible), ``"measure"`` (:func:`optim.tune.grad_cost`, wall-clock, once per problem) or
      a number): its ``n_sims`` counts the same loss-evaluation equivalents;
    * ``pso``: :func:`optim.pso`, ``n_particles`` particles, ``budget // (n_particles·S)`` iterations;
    * ``random``: :func:`optim.random_search`, ``budget // S`` points (batches of ``batch_size``);
    * ``grid``: :func:`optim.grid_search`, ``⌊(budget/S)^{1/d}⌋`` points per dimension;
    * ``cmaes``: :func:`optim.cmaes.cmaes` (the ``cmaes`` extra), ``n_particles`` candidates,
      ``budget // (n_particles·S)`` generations;
    * ``hybrid``: :func:`optim.hybrid.hybrid`, a swarm of ``n_particles`` for a quarter of the
      budget, then at most the rest as L-BFGS steps (stopping at a gradient norm ≤ 1e-9 or after 20
      steps without improvement); its line search may spend more simulations than steps, and the
      row reports them all.

    ``key``: PRNG key of the gradient starts, the swarm and the random points (default ``PRNGKey(0)``).
    """
    from optim.least_squares import levenberg_marquardt
    from optim.pso import pso
    from optim.search import grid_search, random_search
    from optim.tune import grad_cost as measure_grad_cost
    from optim.tune import tune

    def _cmaes(*args: Any, **kw: Any) -> Any:  # evosax (the cmaes extra) only when asked for
        from optim.cmaes import cmaes

        return cmaes(*args, **kw)

    def _hybrid(*args: Any, **kw: Any) -> Any:
        from optim.hybrid import hybrid

        return hybrid(*args, **kw)

    if isinstance(budget, bool) or not isinstance(budget, (int, np.integer)) or budget < 1:
        raise ValueError(f"budget: must be a positive integer number of simulations, got {budget!r}")
    key = jax.random.PRNGKey(0) if key is None else key
    evals = int(budget) // problem.sims_per_eval

    def gradient(c: float) -> Any:
        steps = max(1, int(evals // (n_starts * c)))
        return tune(
            problem,
            optimizer=optax.adam(learning_rate),
            steps=steps,
            n_starts=n_starts,
            key=key,
            init_spread=init_spread,
            grad_cost=c,
            progress=progress,
        )

    def least_squares(c: float) -> Any:
        return levenberg_marquardt(problem, max_steps=max(0, int(evals // c) - 1), jac_cost=c)  # + the start

    def cost() -> float:
        if grad_cost == "measure":
            return measure_grad_cost(problem, n_starts=n_starts)
        return 1.0 if grad_cost is None else float(grad_cost)

    d = problem.space.dim
    makers = {
        "gradient": lambda: gradient(cost()),
        "pso": lambda: pso(problem, n_particles=n_particles, n_iters=evals // n_particles, key=key, progress=progress),
        "random": lambda: random_search(problem, n=evals, key=key, batch_size=batch_size),
        "grid": lambda: grid_search(
            problem, points_per_dim=int(np.floor(evals ** (1 / d) + 1e-9)), batch_size=batch_size
        ),
        "cmaes": lambda: _cmaes(problem, popsize=n_particles, iters=evals // n_particles, key=key, progress=progress),
        "hybrid": lambda: _hybrid(
            problem,
            popsize=n_particles,
            iters=max(1, evals // (4 * n_particles)),
            key=key,
            steps=hybrid_steps,
            tune_options=dict(gtol=1e-9, patience=20),
        ),
        "lm": lambda: least_squares(cost()),
    }
    unknown = [n for n in names if n not in makers]
    if unknown:
        raise ValueError(f"tuners: unknown standard tuner(s) {unknown}; known: {', '.join(makers)}")
    hybrid_steps = evals - max(1, evals // (4 * n_particles)) * n_particles
    too_small = {
        "gradient": evals < n_starts,
        "pso": evals < n_particles,
        "random": evals < 1,
        "grid": evals < 1,
        "cmaes": evals < n_particles,
        "hybrid": hybrid_steps < 1,
        "lm": evals < 1,
    }
    small = [n for n in names if too_small[n]]
    if small:
        raise ValueError(
            f"budget: {budget} simulations ({evals} loss evaluations of {problem.sims_per_eval} "
            f"scenario(s)) is too small for {', '.join(small)}"
        )
    return {n: makers[n] for n in names}


def compare(
    runs: dict[str, Callable[[], Any]] | Problem,
    on_done: Callable[[str], Any] | None = None,
    *,
    tuners: Sequence[str] | dict[str, Any] | None = None,
    budget: int | None = None,
    **options: Any,
) -> Comparison:
    """Run each tuner once and collect its best-so-far curve.

    ``runs``: name → zero-argument callable returning a :class:`~optim.results.TuneResult`; or a
    :class:`~jaxsim.problem.Problem`, with ``tuners`` (standard names, see :func:`standard_tuners`,
    or a dict name → ``None`` for a standard tuner or a callable ``(problem, budget) -> TuneResult``)
    each given ``budget`` simulations; ``options`` go to :func:`standard_tuners`.
    ``on_done(name)`` is called after each tuner finishes (e.g. a progress bar's update).
    """
    problem = runs if isinstance(runs, Problem) else None
    if problem is not None:
        if budget is None:
            raise ValueError("budget: required when comparing tuners on a Problem (simulations per tuner)")
        spec = (
            dict.fromkeys(("gradient", "pso", "random"))
            if tuners is None
            else (dict(tuners) if isinstance(tuners, dict) else dict.fromkeys(tuners))
        )
        standard = standard_tuners(problem, budget, [n for n, v in spec.items() if v is None], **options)
        runs = {n: standard[n] if v is None else (lambda v=v: v(problem, budget)) for n, v in spec.items()}
    elif tuners is not None or budget is not None or options:
        raise ValueError("tuners/budget: only for a Problem; with a dict of runs each run sets its own budget")
    if not runs:
        raise ValueError("runs: need at least one tuner")
    curves, results, rows = {}, {}, []
    for name, run in runs.items():
        if not callable(run):
            raise ValueError(f"runs[{name!r}]: must be a zero-argument callable, got {type(run).__name__}")
        t0 = time.perf_counter()
        res = run()
        total = time.perf_counter() - t0
        if on_done is not None:
            on_done(name)
        h = res.history
        curves[name] = Curve(np.asarray(h.sims, float), np.asarray(h.wall_s, float), np.asarray(h.best_loss, float))
        results[name] = res
        rows.append(
            {
                "tuner": name,
                "best_loss": float(res.loss),
                "sims": int(res.n_sims),
                "wall_s": float(res.wall_s),
                "compile_s": float(getattr(res, "compile_s", 0.0)),
                "total_s": total,
                "params": _params_of(res, problem),
                "converged": bool(getattr(res, "converged", False)),
                "message": getattr(res, "message", ""),
            }
        )
    common_sims = min(float(c.sims[-1]) for c in curves.values())
    common_s = min(float(c.seconds[-1]) for c in curves.values())
    for row in rows:
        c = curves[row["tuner"]]
        row["common_sims"] = common_sims
        row["loss_at_common_sims"] = best_within(c, sims=common_sims)
        row["common_seconds"] = common_s
        row["loss_at_common_seconds"] = best_within(c, seconds=common_s)
    return Comparison(rows, curves, results)


def comparison_metrics(comparison: Comparison) -> dict[str, float]:
    """Flat metrics: ``loss_<tuner>``, ``sims_<tuner>``, ``wall_s_<tuner>`` and the equal-budget losses."""
    out: dict[str, float] = {}
    for row in comparison.rows:
        name = row["tuner"]
        out[f"loss_{name}"] = row["best_loss"]
        out[f"sims_{name}"] = row["sims"]
        out[f"wall_s_{name}"] = row["wall_s"]
        out[f"loss_at_common_sims_{name}"] = row["loss_at_common_sims"]
        out[f"loss_at_common_seconds_{name}"] = row["loss_at_common_seconds"]
    return out


def plot_comparison(
    comparison: Comparison, *, reference: float | None = None, title: str | None = None, loss_label: str = "loss"
):
    """Figure with best loss vs simulations and vs seconds, one line per tuner.

    With ``reference`` (e.g. a known optimum) the curves show ``best − reference`` on a log scale
    (gaps below ``1e-15·|reference|`` are drawn at that floor).  ``loss_label`` names the loss and
    its unit on the y axis (e.g. ``"J = ITAE + ρ·energy, s²"``).
    """
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    floor = 1e-15 * max(abs(reference), 1e-300) if reference is not None else None
    for name, c in comparison.curves.items():
        y = c.best_loss if reference is None else np.maximum(c.best_loss - reference, floor)
        axes[0].step(c.sims, y, where="post", label=name)
        axes[1].step(np.maximum(c.seconds, 1e-6), y, where="post", label=name)
    positive = all(np.all(c.best_loss[np.isfinite(c.best_loss)] > 0) for c in comparison.curves.values())
    for ax in axes:
        if reference is not None or positive:
            ax.set_yscale("log")
        ax.grid(alpha=0.3, which="both")
    axes[0].set_xlabel("simulations")
    axes[1].set_xlabel("wall time, s (compile excluded)")
    axes[1].set_xscale("log")
    ylabel = f"best {loss_label} − reference" if reference is not None else f"best {loss_label}"
    axes[0].set_ylabel(ylabel)
    axes[0].legend()
    fig.suptitle(title or "tuners on equal simulation budgets")
    fig.tight_layout()
    return fig
