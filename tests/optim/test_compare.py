"""Comparison harness: rows, equal-budget losses read off the curves, and the plot."""

import jax
import jax.numpy as jnp
import numpy as np
import optax
import pytest

from optim.compare import best_within, compare, comparison_metrics, plot_comparison
from optim.pso import pso
from optim.search import random_search
from optim.tune import tune


def test_compare_records_budgets_and_equal_budget_losses():
    loss = lambda x: jnp.sum((x - 0.3) ** 2)  # noqa: E731
    lo, hi = -np.ones(2), np.ones(2)
    finished = []
    comp = compare(
        {
            # grad_cost=1: a gradient evaluation counted as one simulation (fixed numbers for the harness)
            "gradient": lambda: tune(loss, jnp.zeros(2), optimizer=optax.adam(0.05), steps=100, grad_cost=1.0),
            "pso": lambda: pso(loss, lo, hi, n_particles=10, n_iters=30, key=jax.random.PRNGKey(1)),
            "random": lambda: random_search(loss, lo, hi, n=500, batch_size=100),
        },
        on_done=finished.append,
    )
    assert finished == ["gradient", "pso", "random"]
    rows = {r["tuner"]: r for r in comp.rows}
    assert [rows[k]["sims"] for k in ("gradient", "pso", "random")] == [100, 300, 500]
    assert all(r["common_sims"] == 100 for r in comp.rows)
    for name, row in rows.items():
        c = comp.curves[name]
        # by hand: the last best-so-far value recorded at ≤ 100 simulations
        manual = c.best_loss[c.sims <= 100].min() if np.any(c.sims <= 100) else np.inf
        assert row["loss_at_common_sims"] == manual
        assert row["best_loss"] == pytest.approx(float(comp.results[name].loss))
        assert row["loss_at_common_seconds"] >= row["best_loss"]
    assert rows["random"]["loss_at_common_sims"] == comp.curves["random"].best_loss[0]
    m = comparison_metrics(comp)
    assert m["sims_pso"] == 300 and m["loss_gradient"] == rows["gradient"]["best_loss"]
    assert best_within(comp.curves["pso"], sims=5) == np.inf  # nothing finished within 5 sims
    fig = plot_comparison(comp, reference=0.0)
    assert len(fig.axes) == 2 and len(fig.axes[0].lines) == 3
    assert fig.axes[0].get_xlabel() == "simulations"
    with pytest.raises(ValueError, match="runs"):
        compare({})
