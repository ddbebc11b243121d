"""Shared stages of the studies, each returning tables, metrics and figures ready to merge.

* :func:`tune_and_compare` — several tuners on one :class:`~jaxsim.problem.Problem`, equal budgets
  of simulations: the comparison table, flat metrics, the best-so-far figure, the tuned designs;
* :func:`responses` — step-response metrics (``step_info``) and the response figure of designs;
* :func:`robustness` — Monte Carlo of designs over the problem's uncertainty: the percentile table
  straight from the Monte-Carlo result, flat metrics, a percentile-band figure;
* :func:`pyswarms_search` — pyswarms' GlobalBestPSO on a problem's box (the reference swarm
  library as one more tuner of :func:`tune_and_compare`);
* :func:`gradient_tuning` — :func:`optim.tune` on one problem: the result, the per-step history
  table (loss, best loss, the evaluated parameters by coordinate name) and the loss-vs-step figure;
* :func:`median_over_seeds` — a stochastic tuner repeated over seeds, represented by its median run,
  every run in a per-seed table (with its best loss within a reference number of simulations);
* :func:`merge` — stages (and extra metrics/notes) into one :class:`~experiments.study.StudyResult`.
* :func:`event_rows` — Monte-Carlo event probabilities over a grid with Wilson intervals, as table rows;
* :func:`series_rows` — time series as table rows; :func:`band_claims` — claims on values read off a figure.

Metric names: ``loss_<tuner>``, ``sims_<tuner>``, ``wall_s_<tuner>``, ``loss_at_common_sims_<tuner>``,
``loss_at_common_seconds_<tuner>``, ``converged_<tuner>`` (1/0), ``gap_to_<ref>_<tuner>``;
``<term>_mean_<design>``, ``<term>_p05_<design>``, ``<term>_p50_<design>``, ``<term>_p95_<design>``.
"""

from __future__ import annotations

import contextlib
import logging
import tempfile
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

import jax.numpy as jnp
import numpy as np

import jaxsim.montecarlo as mc
from experiments import figures
from experiments.runner import Claim
from experiments.study import StudyResult
from jaxsim.core.metrics import step_info
from optim.compare import Comparison, Curve, best_within, compare, comparison_metrics
from optim.results import History, TuneResult
from optim.tune import tune


@dataclass
class Stage:
    """Pieces of a :class:`StudyResult`; ``data`` keeps the stage's own objects (comparison,
    Monte-Carlo results) for anything further."""

    metrics: dict[str, float] = field(default_factory=dict)
    tables: dict[str, list[dict[str, Any]]] = field(default_factory=dict)
    figures: dict[str, Any] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    data: Any = None


@dataclass
class ComparisonStage(Stage):
    """:func:`tune_and_compare`'s stage; ``designs``: tuner → its best params."""

    comparison: Comparison | None = None
    designs: dict[str, Any] = field(default_factory=dict)

    def with_baseline(self, name: str, params: dict[str, Any]) -> dict[str, dict[str, Any]]:
        """``{name: params, tuner: best params, …}`` with every value a float64 scalar: the designs to
        re-score side by side (the hand design first)."""
        as_scalars = lambda d: {k: jnp.float64(v) for k, v in d.items()}  # noqa: E731
        return {name: as_scalars(params), **{k: as_scalars(d) for k, d in self.designs.items()}}


def tune_and_compare(
    problem: Any,
    budget: int,
    tuners: Sequence[str] | dict[str, Any] = ("gradient", "pso", "random"),
    *,
    reference: str | float | None = None,
    progress: Callable[..., Any] | None = None,
    loss_label: str = "loss",
    table: str = "comparison",
    figure: str = "loss_vs_budget",
    title: str | None = None,
    **options: Any,
) -> ComparisonStage:
    """Every tuner on ``problem`` with ``budget`` simulations (:func:`optim.compare.compare`).

    ``tuners``: standard names (``gradient``, ``pso``, ``random``, ``grid``) or a dict name → ``None``
    (standard) or ``callable(problem, budget) -> TuneResult`` (a study's own tuner), in table order.
    ``reference``: a tuner whose loss is the reference (its gap ``gap_to_<ref>_<tuner>`` per tuner, the
    figure shows the gap), or a known optimum value.  ``options`` go to
    :func:`optim.compare.standard_tuners` (``key``, ``learning_rate``, ``n_starts``, ``n_particles``,
    ``batch_size``, ...).  Table rows carry the tuned parameters by coordinate name.
    """
    spec = dict(tuners) if isinstance(tuners, dict) else dict.fromkeys(tuners)
    bar = progress(total=len(spec), desc=f"{problem.name}: tuners", unit="tuner") if progress else None
    comp = compare(problem, tuners=spec, budget=budget, on_done=(lambda _: bar.update(1)) if bar else None, **options)
    if bar is not None:
        bar.close()
    metrics = comparison_metrics(comp)
    ref_loss, ref_name = None, None
    if isinstance(reference, str):
        if reference not in comp.results:
            raise ValueError(f"reference: {reference!r} is not one of the tuners {list(comp.results)}")
        ref_name, ref_loss = reference, float(comp.results[reference].loss)
    elif reference is not None:
        ref_name, ref_loss = "reference", float(reference)
    rows = []
    for row in comp.rows:
        row = dict(row)
        params = row.pop("params")
        if isinstance(params, dict):
            row.update(params)
        else:
            row["params"] = params
        name = row["tuner"]
        metrics[f"converged_{name}"] = float(row["converged"])
        if ref_loss is not None:
            row[f"gap_to_{ref_name}"] = row["best_loss"] - ref_loss
            metrics[f"gap_to_{ref_name}_{name}"] = float(comp.results[name].loss - ref_loss)
        rows.append(row)
    fig = figures.best_so_far(
        comp,
        reference=ref_loss,
        loss_label=loss_label,
        title=title or f"{problem.name}: tuners on equal budgets ({budget} simulations each)",
    )
    designs = {name: res.params for name, res in comp.results.items()}
    return ComparisonStage(
        metrics=metrics,
        tables={table: rows},
        figures={figure: fig},
        notes=[
            f"budget {budget} simulations per tuner ({problem.sims_per_eval} per loss "
            "evaluation); wall times exclude compilation (compile_s in the table)"
        ],
        data=comp,
        comparison=comp,
        designs=designs,
    )


def median_over_seeds(
    run: Callable[[int], TuneResult], seeds: Sequence[int], name: str, rows: list[dict[str, Any]]
) -> TuneResult:
    """``run(seed)`` for every seed; returns the median run by loss (the lower one for an even count)
    and appends one row per seed to ``rows``: ``tuner, seed, best_loss, sims, wall_s`` and the run's
    history (for :func:`seed_rows_within`)."""
    runs = sorted(((s, run(s)) for s in seeds), key=lambda sr: float(sr[1].loss))
    rows += [
        {
            "tuner": name,
            "seed": s,
            "best_loss": float(r.loss),
            "sims": int(r.n_sims),
            "wall_s": float(r.wall_s),
            "_r": r,
        }
        for s, r in sorted(runs, key=lambda sr: sr[0])
    ]
    return runs[(len(runs) - 1) // 2][1]


def seed_rows_within(
    rows: list[dict[str, Any]], sims: float, column: str = "best_loss_within_ref_sims"
) -> list[dict[str, Any]]:
    """:func:`median_over_seeds`'s rows with ``column`` — the best loss each run had found after
    ``sims`` simulations — in place of the run itself."""

    def within(r: TuneResult) -> float:
        h = r.history
        curve = Curve(*(np.asarray(v, float) for v in (h.sims, h.wall_s, h.best_loss)))
        return best_within(curve, sims=sims)

    return [{**{k: v for k, v in row.items() if k != "_r"}, column: within(row["_r"])} for row in rows]


def responses(
    problem: Any,
    designs: dict[str, Any],
    *,
    channel: int = 0,
    y_final: float | None = None,
    y_label: str = "y",
    losses: dict[str, float] | None = None,
    table: str = "step_response",
    figure: str = "step_responses",
    title: str | None = None,
) -> Stage:
    """Step-response metrics of output ``channel`` for each design (overshoot %, settling and rise time
    in s; ``y_final`` default: the reference's last value) and the response figure."""
    rows = []
    for name, params in designs.items():
        tr = problem.jitted.simulate(params)
        yf = float(tr.r[-1, min(channel, tr.r.shape[1] - 1)]) if y_final is None else y_final
        info = step_info(tr.t, tr.y[:, channel], y_final=yf)
        flat = problem.space.flat(params) if isinstance(params, dict) else {}
        rows.append(
            {
                "design": name,
                **flat,
                "overshoot_percent": float(info.overshoot),
                "settling_time_s": float(info.settling_time),
                "rise_time_s": float(info.rise_time),
            }
        )
    fig = figures.responses(problem, designs, channel=channel, y_label=y_label, title=title, losses=losses)
    return Stage(tables={table: rows}, figures={figure: fig})


def robustness(
    problem: Any,
    designs: dict[str, Any],
    n: int,
    key: Any,
    *,
    band_runs: int = 64,
    channel: int = 0,
    y_label: str = "y",
    quantiles: tuple[float, ...] = (0.05, 0.5, 0.95),
    progress: Callable[..., Any] | None = None,
    table: str = "robustness",
    figure: str = "mc_bands",
    block_size: int = 1000,
) -> Stage:
    """Monte Carlo of every design over ``problem.uncertainty`` (``n`` runs, fresh noise each; the
    same ``key`` for every design: common random numbers) and the percentile bands of output
    ``channel`` over ``band_runs`` draws."""
    if not problem.uncertainty:
        raise ValueError(f"problem {problem.name!r} declares no uncertainty to run a Monte Carlo over")
    rows, metrics, results = [], {}, {}
    for name, params in designs.items():
        res = mc.monte_carlo(problem, params, n, key, block_size=min(block_size, n), progress=progress)
        results[name] = res
        rows.append({"design": name, **res.row(quantiles)})
        for term, stats in res.by_name.items():
            metrics[f"{term}_mean_{name}"] = float(stats.mean)
            for q in quantiles:
                metrics[f"{term}_p{round(100 * q):02d}_{name}"] = float(stats.quantile(q))
    draws = problem.sample(key, band_runs)
    bands = {
        name: figures.trajectory_bands(
            problem, params, draws, channel=channel, quantiles=(quantiles[0], 0.5, quantiles[-1])
        )
        for name, params in designs.items()
    }
    unc = ", ".join(problem.uncertainty)
    fig = figures.mc_bands(
        bands,
        y_label=y_label,
        quantiles=(quantiles[0], 0.5, quantiles[-1]),
        title=f"{problem.name}: {band_runs} draws of {unc}",
    )
    return Stage(
        metrics=metrics,
        tables={table: rows},
        figures={figure: fig},
        notes=[
            f"Monte Carlo: {n} runs per design over {unc}, common random numbers across designs; "
            "quantiles from the streaming sketch (relative error ≤ 1e-3)"
        ],
        data=results,
    )


def pyswarms_search(
    problem: Any, n_particles: int, n_iters: int, *, seed: int, inertia: float = 0.7, c1: float = 1.5, c2: float = 1.5
) -> TuneResult:
    """pyswarms' ``GlobalBestPSO`` (global best, constant ``inertia``, ``c1``, ``c2``) on the problem's
    box in search coordinates, evaluating the problem's jitted batched :meth:`search_loss` (non-finite
    losses count as ``+inf``); ``n_particles·n_iters`` simulations per scenario; ``params`` of the
    result is the params dict.  ``seed`` seeds NumPy's global generator, which pyswarms draws from."""
    lo, hi = problem.space.box
    batched = problem.jitted.search_losses
    np.random.seed(seed)
    # pyswarms' reporters open ./report.log (at import and per optimiser): keep it out of the cwd
    with tempfile.TemporaryDirectory() as tmp, contextlib.chdir(tmp):
        import pyswarms as ps

        logging.getLogger("pyswarms").setLevel(logging.WARNING)
        opt = ps.single.GlobalBestPSO(
            n_particles=n_particles, dimensions=lo.size, options={"c1": c1, "c2": c2, "w": inertia}, bounds=(lo, hi)
        )
    stamps = []

    def objective(x):
        out = np.asarray(batched(jnp.asarray(x)))
        stamps.append(time.perf_counter())
        return np.where(np.isfinite(out), out, np.inf)

    batched(jnp.asarray(np.tile((lo + hi) / 2, (n_particles, 1)))).block_until_ready()  # compile
    start = time.perf_counter()
    best, pos = opt.optimize(objective, iters=n_iters, verbose=False)
    wall = time.perf_counter() - start
    hist = np.minimum.accumulate(np.asarray(opt.cost_history, float))
    sims = n_particles * problem.sims_per_eval * np.arange(1, hist.size + 1)
    history = History(hist, sims, np.asarray(stamps[: hist.size]) - start)
    return TuneResult(
        problem.space.from_search(jnp.asarray(pos)),
        float(best),
        history,
        int(sims[-1]),
        wall,
        message="pyswarms GlobalBestPSO",
    )


@dataclass
class TuningStage(Stage):
    """:func:`gradient_tuning`'s stage; ``result``: the :class:`optim.results.TuneResult`."""

    result: Any = None


def gradient_tuning(
    problem: Any,
    *,
    steps: int,
    optimizer: Any,
    progress: Callable[..., Any] | None = None,
    loss_label: str = "loss",
    title: str | None = None,
    table: str = "tuning_history",
    figure: str = "tuning",
    **options: Any,
) -> TuningStage:
    """:func:`optim.tune` of ``problem`` for ``steps`` steps of ``optimizer`` (``options`` go to
    ``tune``: ``mode``, ``n_starts``, ...).  Table rows: ``step``, ``loss`` (the loss evaluated at
    that step, of the start with the lowest one), ``best_loss`` and the evaluated parameters by
    coordinate name (:meth:`ParamSpace.flat`); figure: :func:`figures.tuning_curve`."""
    rows: list[dict[str, Any]] = []

    def record(step: int, params: Any, loss: float) -> None:
        rows.append({"step": step, "loss": loss, **problem.space.flat(params)})

    res = tune(problem, optimizer=optimizer, steps=steps, callback=record, progress=progress or False, **options)
    for row, best in zip(rows, res.history.best_loss):
        row["best_loss"] = float(best)
    fig = figures.tuning_curve(
        res.history, loss_label=loss_label, title=title or f"{problem.name}: gradient tuning ({res.n_steps} steps)"
    )
    return TuningStage(
        tables={table: rows},
        figures={figure: fig},
        data=res,
        result=res,
        notes=[
            f"tuning {problem.name}: {res.message}; {res.n_sims} simulations in "
            f"{res.wall_s:.1f} s (+{res.compile_s:.1f} s compile)"
        ],
    )


def merge(
    *stages: Stage,
    metrics: dict[str, float] | None = None,
    notes: Sequence[str] = (),
    assumptions: dict[str, Any] | None = None,
) -> StudyResult:
    """One :class:`StudyResult` from the stages (later stages win on a name clash) plus extras."""
    out = StudyResult(assumptions=dict(assumptions or {}))
    for st in stages:
        out.metrics.update(st.metrics)
        out.tables.update(st.tables)
        out.figures.update(st.figures)
        out.notes.extend(st.notes)
    out.metrics.update(metrics or {})
    out.notes.extend(notes)
    return out


def event_rows(
    result: Any,
    events: dict[str, str],
    x: Sequence[float],
    *,
    x_name: str,
    label: str = "event",
    p_name: str = "p",
    level: float = 0.95,
) -> list[dict[str, Any]]:
    """Probabilities of Monte-Carlo events over a grid, with their Wilson intervals: one row per
    ``events[name]`` (an event of ``result`` with one probability per grid point ``x``) and grid point,
    ``{label: name, x_name: x, p_name: p, "wilson_low", "wilson_high", "runs"}``."""
    rows = []
    for name, event in events.items():
        stats = result[event]
        lo, hi = stats.interval(level)
        rows += [
            {
                label: name,
                x_name: xi,
                p_name: float(stats.probability[i]),
                "wilson_low": float(lo[i]),
                "wilson_high": float(hi[i]),
                "runs": result.runs,
            }
            for i, xi in enumerate(x)
        ]
    return rows


def series_rows(t: Any, columns: dict[str, Any], t_name: str = "t_s") -> list[dict[str, float]]:
    """A table of time series: one row per sample of ``t`` with ``t_name`` and every ``columns[name][i]``."""
    return [{t_name: float(ti), **{k: float(v[i]) for k, v in columns.items()}} for i, ti in enumerate(t)]


def band_claims(targets: dict[str, Any], rel: float, source: str) -> list[Claim]:
    """Claims on values read off a figure: ``targets[metric]`` is a value or a ``(lo, hi)`` range,
    reproduced within ``[(1 − rel)·lo, (1 + rel)·hi]``; the claim's ``paper`` is ``lo``, a range is noted."""
    claims = []
    for metric, target in targets.items():
        lo, hi = (target, target) if np.isscalar(target) else target
        note = "" if lo == hi else f"paper: {lo:g}–{hi:g}"
        claims.append(Claim(metric, paper=lo, band=((1 - rel) * lo, (1 + rel) * hi), source=source, note=note))
    return claims
