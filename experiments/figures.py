"""Shared figures of the studies: axes labelled with units, a legend on every multi-line plot.

* :func:`best_so_far` — tuners' best loss vs simulations and vs seconds (equal-budget comparison);
* :func:`responses` — the closed-loop response of several designs of one Problem;
* :func:`mc_bands` — Monte-Carlo percentile bands of a response over the problem's uncertainty;
* :func:`tuning_curve` — a gradient tuner's loss per step (current and best so far);
* :func:`probability_curves` — event probabilities with their confidence intervals vs a parameter;
* :func:`mc_cdfs` — empirical CDFs (from the quantile sketches) of Monte-Carlo metrics, one line per result;
* :func:`line_panels` — side-by-side panels of labelled curves (characteristics, transients), declared as data;
* :func:`box_by_group` — box plots of one quantity per group (Monte-Carlo cases), with a reference line;
* :func:`panel` — one panel of :func:`line_panels`; :func:`parity` — computed vs reference values around y = x.
"""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp
import numpy as np

from optim.compare import Comparison, plot_comparison


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def best_so_far(
    comparison: Comparison, *, reference: float | None = None, title: str | None = None, loss_label: str = "loss"
):
    """Best loss vs simulations and vs wall time per tuner (``reference``: plot the gap to it, log
    scale); ``loss_label`` names the loss and its unit."""
    _plt()
    return plot_comparison(comparison, reference=reference, title=title, loss_label=loss_label)


def responses(
    problem: Any,
    designs: dict[str, Any],
    *,
    channel: int = 0,
    y_label: str = "y",
    time_unit: str = "s",
    title: str | None = None,
    draw: dict[str, Any] | None = None,
    losses: dict[str, float] | None = None,
):
    """Output ``channel`` of ``problem.simulate(params, draw)`` for every design, with the reference."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7, 4))
    tr = None
    for name, params in designs.items():
        tr = problem.jitted.simulate(params, draw)
        label = name if losses is None or name not in losses else f"{name} (J = {losses[name]:.5g})"
        ax.plot(np.asarray(tr.t), np.asarray(tr.y[:, channel]), label=label)
    if tr is not None:
        ax.plot(
            np.asarray(tr.t), np.asarray(tr.r[:, min(channel, tr.r.shape[1] - 1)]), "k--", lw=0.8, label="reference"
        )
    ax.set_xlabel(f"t, {time_unit}")
    ax.set_ylabel(y_label)
    ax.set_title(title or f"{problem.name}: responses of the tuned designs")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def trajectory_bands(
    problem: Any,
    params: Any,
    draws: dict[str, Any],
    *,
    channel: int = 0,
    quantiles: tuple[float, ...] = (0.05, 0.5, 0.95),
) -> tuple[np.ndarray, np.ndarray]:
    """``(t (N,), q (len(quantiles), N))``: percentiles over ``draws`` (a batched dict) of output
    ``channel`` of ``problem.simulate(params, draw)`` (noise from the problem's fixed key)."""
    tr = problem.jitted.simulate_batch(params, draws)  # compiled once per problem, for any params
    ys = tr.y[:, :, channel]
    return np.asarray(tr.t[0]), np.asarray(jnp.quantile(ys, jnp.asarray(quantiles), axis=0))


def mc_bands(
    bands: dict[str, tuple[np.ndarray, np.ndarray]],
    *,
    y_label: str = "y",
    time_unit: str = "s",
    title: str | None = None,
    quantiles: tuple[float, float, float] = (0.05, 0.5, 0.95),
):
    """Median line and the ``quantiles[0]``–``quantiles[2]`` band per design (``bands[name] = (t, q)`` of
    :func:`trajectory_bands`)."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7, 4))
    lo, mid, hi = (f"{100 * q:g} %" for q in quantiles)
    for i, (name, (t, q)) in enumerate(bands.items()):
        color = f"C{i}"
        ax.fill_between(t, q[0], q[2], color=color, alpha=0.2, label=f"{name}: {lo}–{hi}")
        ax.plot(t, q[1], color=color, label=f"{name}: median")
    ax.set_xlabel(f"t, {time_unit}")
    ax.set_ylabel(y_label)
    ax.set_title(title or "Monte-Carlo percentile bands over the uncertainty")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def tuning_curve(history: Any, *, loss_label: str = "loss", title: str | None = None, log: bool = True):
    """The loss evaluated at each step and the best so far, of an :class:`optim.results.History`."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(np.asarray(history.loss), "o-", ms=3, label="evaluated")
    ax.plot(np.asarray(history.best_loss), "k--", lw=1.0, label="best so far")
    ax.set_xlabel("step")
    ax.set_ylabel(loss_label)
    if log:
        ax.set_yscale("log")
    ax.set_title(title or "gradient tuning")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def box_by_group(
    groups: dict[str, Any],
    *,
    y_label: str,
    title: str | None = None,
    log: bool = False,
    reference: float | None = None,
    reference_label: str = "reference",
):
    """One box per group (``groups[name]`` = the samples), optionally a horizontal reference line."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(8, 4))
    ax.boxplot([np.asarray(v, float) for v in groups.values()])
    ax.set_xticks(range(1, len(groups) + 1), list(groups), rotation=15)
    if log:
        ax.set_yscale("log")
    if reference is not None:
        ax.axhline(reference, color="r", ls="--", label=reference_label)
        ax.legend(fontsize=8)
    ax.set_ylabel(y_label)
    if title:
        ax.set_title(title)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def probability_curves(
    x: Any,
    curves: dict[str, tuple[Any, Any, Any]],
    *,
    x_label: str,
    y_label: str,
    title: str | None = None,
    log: bool = False,
    mark: float | None = None,
):
    """``curves[name] = (p, lo, hi)`` over ``x``: probabilities with error bars to their interval
    (e.g. Wilson, :meth:`jaxsim.montecarlo.result.EventStats.interval`); ``mark``: a vertical line."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7, 4.5))
    x = np.asarray(x, float)
    for name, (p, lo, hi) in curves.items():
        p, lo, hi = (np.asarray(v, float) for v in (p, lo, hi))
        ax.errorbar(x, p, yerr=[p - lo, hi - p], marker="o", ms=3, capsize=2, label=name)
    if mark is not None:
        ax.axvline(mark, color="0.5", ls=":", lw=0.8)
    if log:
        ax.set_yscale("log")
    ax.set_xlabel(x_label)
    ax.set_ylabel(y_label)
    if title:
        ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def mc_cdfs(results: dict[str, Any], metrics: dict[str, tuple[str, bool]], *, title: str | None = None):
    """One panel per ``metrics[name] = (x label with unit, log x)``: the CDF of that metric of each
    :class:`jaxsim.montecarlo.MonteCarloResult` in ``results`` (label → result), from its quantiles."""
    plt = _plt()
    fig, axes = plt.subplots(1, len(metrics), figsize=(5 * len(metrics), 3.8), squeeze=False)
    q = np.linspace(0.01, 0.99, 99)
    for ax, (name, (x_label, log)) in zip(axes[0], metrics.items()):
        for label, res in results.items():
            ax.plot(np.asarray(res[name].quantile(q)), q, label=label)
        ax.set(xlabel=x_label, ylabel="cumulative probability", xscale="log" if log else "linear")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig


def line_panels(panels: list[dict[str, Any]], *, title: str | None = None, size: tuple[float, float] = (6.0, 4.5)):
    """One axis per panel; a panel is a dict with ``lines`` (label → ``(x, y)`` or ``(x, y, style)``),
    ``x_label``, ``y_label`` (with units) and optionally ``title``, ``xlim``, ``ylim``, ``log_y``,
    ``hline`` (a reference level drawn in black)."""
    plt = _plt()
    fig, axes = plt.subplots(1, len(panels), figsize=(size[0] * len(panels), size[1]), squeeze=False)
    for ax, panel in zip(axes[0], panels):
        for label, line in panel["lines"].items():
            x, y, *style = line
            ax.plot(np.asarray(x), np.asarray(y), *style, label=label)
        if panel.get("hline") is not None:
            ax.axhline(panel["hline"], color="k", lw=0.6)
        ax.set(xlabel=panel["x_label"], ylabel=panel["y_label"], title=panel.get("title", ""))
        if panel.get("log_y"):
            ax.set_yscale("log")
        for lim in ("xlim", "ylim"):
            if panel.get(lim) is not None:
                getattr(ax, f"set_{lim}")(*panel[lim])
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig


def panel(lines: dict[str, tuple], x_label: str, y_label: str, **options: Any) -> dict[str, Any]:
    """One panel of :func:`line_panels`: ``lines`` (label → ``(x, y)`` or ``(x, y, style)``), the axis
    labels with units and the optional keys (``title``, ``xlim``, ``ylim``, ``log_y``, ``hline``)."""
    return {"lines": lines, "x_label": x_label, "y_label": y_label, **options}


def parity(
    points: dict[str, tuple[Any, Any]], *, x_label: str, y_label: str, title: str | None = None, size=(6.5, 5.0)
):
    """Computed against reference values: ``points[label] = (x, y)`` as hollow markers, one marker
    shape per label, and the identity line ``y = x`` over ±1.1·max|x|."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=size)
    for k, (label, (x, y)) in enumerate(points.items()):
        ax.scatter(x, y, marker="os^Dv<>p"[k % 8], facecolors="none", edgecolors=f"C{k}", label=label)
    lim = 1.1 * max((float(np.max(np.abs(x))) for x, _ in points.values() if len(x)), default=1.0)
    ax.plot([-lim, lim], [-lim, lim], "k-", lw=0.6)
    ax.set(xlabel=x_label, ylabel=y_label, title=title or "")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig
