"""Shared figures of the studies: axes labelled with units, a legend on every multi-line plot.

* :func:`best_so_far` — tuners' best loss vs simulations and vs seconds (equal-budget comparison);
* :func:`responses` — the closed-loop response of several designs of one Problem;
* :func:`mc_bands` — Monte-Carlo percentile bands of a response over the problem's uncertainty.
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


def best_so_far(comparison: Comparison, *, reference: float | None = None, title: str | None = None,
                loss_label: str = "loss"):
    """Best loss vs simulations and vs wall time per tuner (``reference``: plot the gap to it, log
    scale); ``loss_label`` names the loss and its unit."""
    _plt()
    return plot_comparison(comparison, reference=reference, title=title, loss_label=loss_label)


def responses(problem: Any, designs: dict[str, Any], *, channel: int = 0, y_label: str = "y",
              time_unit: str = "s", title: str | None = None, draw: dict[str, Any] | None = None,
              losses: dict[str, float] | None = None):
    """Output ``channel`` of ``problem.simulate(params, draw)`` for every design, with the reference."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7, 4))
    tr = None
    for name, params in designs.items():
        tr = problem.jitted.simulate(params, draw)
        label = name if losses is None or name not in losses else f"{name} (J = {losses[name]:.5g})"
        ax.plot(np.asarray(tr.t), np.asarray(tr.y[:, channel]), label=label)
    if tr is not None:
        ax.plot(np.asarray(tr.t), np.asarray(tr.r[:, min(channel, tr.r.shape[1] - 1)]), "k--", lw=0.8,
                label="reference")
    ax.set_xlabel(f"t, {time_unit}")
    ax.set_ylabel(y_label)
    ax.set_title(title or f"{problem.name}: responses of the tuned designs")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def trajectory_bands(problem: Any, params: Any, draws: dict[str, Any], *, channel: int = 0,
                     quantiles: tuple[float, ...] = (0.05, 0.5, 0.95)) -> tuple[np.ndarray, np.ndarray]:
    """``(t (N,), q (len(quantiles), N))``: percentiles over ``draws`` (a batched dict) of output
    ``channel`` of ``problem.simulate(params, draw)`` (noise from the problem's fixed key)."""
    tr = problem.jitted.simulate_batch(params, draws)  # compiled once per problem, for any params
    ys = tr.y[:, :, channel]
    return np.asarray(tr.t[0]), np.asarray(jnp.quantile(ys, jnp.asarray(quantiles), axis=0))


def mc_bands(bands: dict[str, tuple[np.ndarray, np.ndarray]], *, y_label: str = "y", time_unit: str = "s",
             title: str | None = None, quantiles: tuple[float, float, float] = (0.05, 0.5, 0.95)):
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
