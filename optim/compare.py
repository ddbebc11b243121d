"""Comparison harness: several tuners on one loss, their best-so-far curves, a table and a plot.

``compare({"gradient": lambda: tune(...), "pso": lambda: pso(...), ...})`` runs each tuner once and
reads its history (:class:`optim.tune.TuneResult` and :class:`optim.results.SearchResult` both
carry ``best_loss``, ``sims`` and ``wall_s`` per step or iteration).  Equal budgets are the caller's
job (give every tuner the same number of simulations); the harness reports what each used and, for
the equal-budget view, the best loss each tuner had reached by the smallest budget any of them
used — of simulations (``loss_at_common_sims``) and of seconds (``loss_at_common_seconds``).

A study that tunes puts ``Comparison.rows`` in its tables, :func:`comparison_metrics` in its metrics
and :func:`plot_comparison` in its figures (see ``experiments/pid_tuning_comparison.py``).
"""

from __future__ import annotations

import time
from typing import Any, Callable, NamedTuple

import numpy as np


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


def _params_of(result: Any) -> Any:
    x = getattr(result, "params", None)
    if x is None:
        x = getattr(result, "x", None)
    try:
        return np.asarray(x, float).ravel().tolist()
    except (TypeError, ValueError):
        return str(x)


def compare(runs: dict[str, Callable[[], Any]],
            on_done: Callable[[str], Any] | None = None) -> Comparison:
    """Run each tuner (a zero-argument callable returning a TuneResult or SearchResult).

    ``on_done(name)`` is called after each tuner finishes (e.g. a progress bar's update).
    """
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
        curves[name] = Curve(np.asarray(h.sims, float), np.asarray(h.wall_s, float),
                             np.asarray(h.best_loss, float))
        results[name] = res
        rows.append({
            "tuner": name, "best_loss": float(res.loss), "sims": int(res.n_sims),
            "wall_s": float(res.wall_s), "compile_s": float(getattr(res, "compile_s", 0.0)),
            "total_s": total, "params": _params_of(res), "message": getattr(res, "message", ""),
        })
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


def plot_comparison(comparison: Comparison, *, reference: float | None = None, title: str | None = None):
    """Figure with best loss vs simulations and vs seconds, one line per tuner.

    With ``reference`` (e.g. a known optimum) the curves show ``best − reference`` on a log scale
    (gaps below ``1e-15·|reference|`` are drawn at that floor).
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
    ylabel = "best loss − reference" if reference is not None else "best loss"
    axes[0].set_ylabel(ylabel)
    axes[0].legend()
    fig.suptitle(title or "tuners on equal simulation budgets")
    fig.tight_layout()
    return fig
