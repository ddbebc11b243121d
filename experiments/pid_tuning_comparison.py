"""Study ``pid_tuning_comparison``: one PID tuning problem, six tuners, equal simulation budgets.

The template every study that tunes follows: a loss, several tuners given the same budget of
simulations, :func:`optim.compare.compare` for the table and the best-so-far curves (loss vs
simulations and vs seconds), and an independent check of the optimum.

Problem (:class:`optim.problems.PIDTuning`): the PID of the fuzzy-PID paper's static plant
``2/((0.1s+1)(0.5s+1))`` (seed 000, paper 1, lines 468–470) for a unit step reference, sampled
PID (P and I on the error, filtered derivative on the measurement) at ``ts`` with ``substeps`` RK4
steps per period, ``J = ∫ e² + ρ u² dt`` over ``t_final``, gains in a box.  Tuners:

* ``gradient`` — :func:`optim.tune.tune`, Adam in the unconstrained space of an ``Interval``
  reparametrisation of the box, ``n_starts`` vmapped starts from the box centre;
* ``gradient_lbfgs`` — the same tuner with ``optax.lbfgs`` (backtracking line search), one start
  from the box centre, stopped when the gradient norm falls below ``1e-9`` (a quasi-Newton method,
  like IPOPT's limited-memory mode);
* ``pso`` — :func:`optim.pso.pso` (global best, the toolkit's defaults);
* ``random`` — :func:`optim.search.random_search`; ``grid`` — :func:`optim.search.grid_search`
  (``⌊budget^{1/3}⌋`` points per gain);
* ``ipopt`` — :func:`optim.casadi_pid.ipopt_tune`: the same loss rebuilt in CasADi (own RK4
  integrator) and solved by IPOPT from the box centre; it stops at its own tolerance, well inside
  the budget.

The IPOPT optimum is the reference: every tuner's gap to it is reported, the JAX and CasADi losses
and gradients are compared at the start point, and the tuned step responses are plotted.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np
import optax

from experiments.study import Study, StudyResult, assumption
from jaxsim.core.metrics import step_info
from jaxsim.core.rollout import simulate
from optim.casadi_pid import casadi_value_and_grad, ipopt_tune
from optim.compare import compare, comparison_metrics, plot_comparison
from optim.problems import GAIN_NAMES, PIDTuning
from optim.pso import pso
from optim.reparam import Interval
from optim.search import grid_search, random_search
from optim.tune import tune


@dataclass(frozen=True)
class Config:
    quick: bool = False
    K: float = 2.0  # paper lines 468–470
    T1: float = 0.1
    T2: float = 0.5
    derivative_filter: float = 0.05  # s, assumed
    controller_period: float = 0.01  # s, assumed
    substeps: int = 2
    t_final: float = 3.0  # s, assumed
    rho: float = 0.01  # weight of u² in the loss, assumed
    kp_max: float = 20.0
    ki_max: float = 20.0
    kd_max: float = 2.0
    budget: int = 3200  # simulations per tuner (quick: 640)
    n_starts: int = 4  # gradient tuner starts
    learning_rate: float = 0.05  # Adam, in the reparametrised (sigmoid) space
    n_particles: int = 32
    seed: int = 0


ASSUMPTIONS = {
    "loss": assumption("∫ e² + ρ u² dt, ρ = 0.01, unit step, 3 s",
                       "the paper gives no tuning criterion for its linear PID; a smooth ISE with a "
                       "control-effort term has a finite interior optimum, so IPOPT is well posed"),
    "controller_period": assumption(
        0.01, "a 100 Hz digital PID; the paper simulates at 1e-3 without a stated controller rate"),
    "derivative_filter": assumption(0.05, "the paper's PD has no stated filter (as in linear_pid_accuracy)"),
    "gain_box": assumption("kp, ki ∈ [0, 20], kd ∈ [0, 2]", "wide enough to hold the optimum well inside"),
    "budget": assumption(3200, "simulations per tuner; equal for all but IPOPT, which stops at its tolerance"),
}


def problem_of(cfg: Config) -> PIDTuning:
    return PIDTuning(K=cfg.K, T1=cfg.T1, T2=cfg.T2, tf=cfg.derivative_filter, ts=cfg.controller_period,
                     substeps=cfg.substeps, t_final=cfg.t_final, rho=cfg.rho,
                     lo=(0.0, 0.0, 0.0), hi=(cfg.kp_max, cfg.ki_max, cfg.kd_max))


def tuners(cfg: Config, problem: PIDTuning, budget: int) -> dict[str, Callable[[], Any]]:
    """The tuners, each given ``budget`` simulations (L-BFGS and IPOPT stop at their tolerance)."""
    lo, hi = problem.box
    centre = (lo + hi) / 2
    key = jax.random.PRNGKey(cfg.seed)
    grid_points = int(np.floor(budget ** (1 / 3) + 1e-9))
    return {
        "gradient": lambda: tune(
            problem.loss, jnp.asarray(centre), optimizer=optax.adam(cfg.learning_rate),
            steps=budget // cfg.n_starts, reparam=Interval(jnp.asarray(lo), jnp.asarray(hi)),
            n_starts=cfg.n_starts, key=key, init_spread=1.0),
        "gradient_lbfgs": lambda: tune(
            problem.loss, jnp.asarray(centre),
            optimizer=optax.lbfgs(linesearch=optax.scale_by_backtracking_linesearch(20)),
            steps=budget, reparam=Interval(jnp.asarray(lo), jnp.asarray(hi)), gtol=1e-9, patience=20),
        "pso": lambda: pso(problem.loss, lo, hi, n_particles=cfg.n_particles,
                           n_iters=budget // cfg.n_particles, key=key),
        "random": lambda: random_search(problem.loss, lo, hi, n=budget, key=key, batch_size=128),
        "grid": lambda: grid_search(problem.loss, lo, hi, points_per_dim=grid_points, batch_size=128),
        "ipopt": lambda: ipopt_tune(problem, centre, max_iter=budget, tol=1e-10),
    }


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    budget = 640 if cfg.quick else cfg.budget
    problem = problem_of(cfg)
    runs = tuners(cfg, problem, budget)
    bar = progress(total=len(runs), desc="pid_tuning_comparison", unit="tuner")

    comp = compare(runs, on_done=lambda _: bar.update(1))
    bar.close()

    ref = comp.results["ipopt"]
    metrics = comparison_metrics(comp)
    for row in comp.rows:
        row.update(dict(zip(GAIN_NAMES, row.pop("params"))))
        row["gap_to_ipopt"] = row["best_loss"] - ref.loss
    for name, res in comp.results.items():
        metrics[f"gap_to_ipopt_{name}"] = float(res.loss - ref.loss)
    for gname, v in zip(GAIN_NAMES, np.asarray(ref.x)):
        metrics[f"optimum_{gname}"] = float(v)
    grad_params = np.asarray(comp.results["gradient"].params)
    metrics["gradient_vs_ipopt_gain_rel_diff"] = float(np.max(np.abs(grad_params - ref.x) / np.abs(ref.x)))

    # the cross-check at the start point: JAX vs CasADi loss and gradient
    lo, hi = problem.box
    start = (lo + hi) / 2
    v_jax, g_jax = jax.jit(jax.value_and_grad(problem.loss))(jnp.asarray(start))
    v_ca, g_ca = casadi_value_and_grad(problem, start)
    metrics["jax_vs_casadi_loss_rel_diff"] = float(abs(float(v_jax) - v_ca) / abs(v_ca))
    metrics["jax_vs_casadi_grad_rel_diff"] = float(np.max(np.abs(np.asarray(g_jax) - g_ca)) / np.max(np.abs(g_ca)))
    metrics["budget"] = budget

    responses, steps_rows = _responses(problem, comp)
    figures = {
        "loss_vs_budget": plot_comparison(
            comp, reference=ref.loss,
            title=f"PID tuning, static plant: gap to the IPOPT optimum (budget {budget} simulations)"),
        "step_responses": responses,
    }
    return StudyResult(
        metrics=metrics,
        tables={"comparison": comp.rows, "step_response": steps_rows},
        assumptions=ASSUMPTIONS,
        figures=figures,
        notes=[
            f"budget {budget} simulations per tuner; one gradient evaluation counts one simulation "
            "(its extra cost shows in the wall time); IPOPT's count is its f + gradient evaluations",
            "wall times exclude compilation (compile_s in the table); the machine may be shared",
        ],
    )


def _responses(problem: PIDTuning, comp) -> tuple[Any, list[dict[str, Any]]]:
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4))
    rows = []
    for row in comp.rows:
        gains = jnp.asarray([row[g] for g in GAIN_NAMES])
        tr = simulate(problem.closed_loop(gains), jnp.zeros(2), problem.timing)
        info = step_info(tr.t, tr.y[:, 0], y_final=problem.reference)
        rows.append({"tuner": row["tuner"], **{g: row[g] for g in GAIN_NAMES},
                     "overshoot_percent": float(info.overshoot), "settling_time_s": float(info.settling_time),
                     "rise_time_s": float(info.rise_time)})
        ax.plot(np.asarray(tr.t), np.asarray(tr.y[:, 0]), label=f"{row['tuner']} (J = {row['best_loss']:.5f})")
    ax.axhline(problem.reference, color="k", lw=0.7, ls="--")
    ax.set_xlabel("t, s")
    ax.set_ylabel("y")
    ax.set_title("step responses with the tuned PID gains")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig, rows


STUDY = Study(
    name="pid_tuning_comparison",
    description="PID of the fuzzy-PID paper's static plant tuned by gradient / PSO / random / grid / IPOPT "
                "on equal budgets",
    config_cls=Config,
    run=run,
)
