"""Matplotlib figures of Monte-Carlo results (scalar metrics only; arrays are in the tables)."""

from __future__ import annotations

from typing import Any

import numpy as np

from jaxsim.montecarlo.result import EventStats, MetricStats, MonteCarloResult


def _scalar_names(result: MonteCarloResult) -> list[str]:
    return [k for k, s in result.by_name.items() if np.ndim(s.count) == 0]


def plot_sweep(result: Any, band: tuple[float, float] = (0.05, 0.95), confidence: float = 0.95) -> dict[str, Any]:
    """One figure per scalar metric of a :class:`~jaxsim.montecarlo.engine.SweepResult`.

    One panel per swept parameter: the mean (numeric metric, band = sketch quantiles ``band``) or the
    probability (event, band = Wilson interval) at every point against that parameter.
    """
    import matplotlib.pyplot as plt

    design, pts = result.design, result.points
    figures = {}
    for name in _scalar_names(pts[0]):
        d = max(1, len(design.names))
        fig, axes = plt.subplots(1, d, figsize=(4.2 * d, 3.4), squeeze=False)
        stats = [r.by_name[name] for r in pts]
        if isinstance(stats[0], EventStats):
            y = np.array([float(s.probability) for s in stats])
            lo, hi = np.array([[float(v) for v in s.interval(confidence)] for s in stats]).T
            label = f"P({name}), {100 * confidence:g} % Wilson interval"
        else:
            y = np.array([float(s.mean) for s in stats])
            if stats[0].bucket_counts is not None:
                lo = np.array([float(s.quantile(band[0])) for s in stats])
                hi = np.array([float(s.quantile(band[1])) for s in stats])
            else:
                sd = np.array([float(s.std) for s in stats])
                lo, hi = y - sd, y + sd
            label = f"mean {name}, band p{100 * band[0]:g}–p{100 * band[1]:g}"
        for j, ax in enumerate(axes[0]):
            x = design.values[:, j] if design.names else np.zeros(len(pts))
            order = np.argsort(x, kind="stable")
            ax.vlines(x[order], lo[order], hi[order], color="C0", alpha=0.5, lw=3)
            ax.plot(x[order], y[order], "o-" if len(design.names) == 1 else "o", color="C0", ms=4, lw=1)
            ax.set_xlabel(design.names[j] if design.names else "point")
            ax.grid(alpha=0.3)
        axes[0, 0].set_ylabel(name)
        fig.suptitle(f"{label} ({pts[0].runs} runs per point, {design.kind} design)", fontsize=10)
        fig.tight_layout()
        figures[f"sweep_{name.replace('/', '_')}"] = fig
    return figures


def plot_distribution(result: MonteCarloResult, levels: int = 199) -> Any:
    """Empirical quantile function (from the sketch) of every scalar numeric metric of one point."""
    import matplotlib.pyplot as plt

    names = [
        k
        for k in _scalar_names(result)
        if isinstance(result.by_name[k], MetricStats) and result.by_name[k].bucket_counts is not None
    ]
    fig, axes = plt.subplots(1, max(1, len(names)), figsize=(4.2 * max(1, len(names)), 3.4), squeeze=False)
    q = np.linspace(0.0, 1.0, levels + 2)[1:-1]
    for ax, name in zip(axes[0], names):
        s = result.by_name[name]
        ax.plot(s.quantile(q), q, lw=1.5)
        ax.axvline(float(s.mean), color="k", ls="--", lw=0.8, label="mean")
        ax.set_xlabel(name)
        ax.set_ylabel("fraction of runs ≤ x")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(f"distribution over {result.runs} runs", fontsize=10)
    fig.tight_layout()
    return fig
