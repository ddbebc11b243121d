"""Study ``pid_tuning_comparison``: one PID tuning problem, six tuners, equal simulation budgets.

The reference study of the runner (:mod:`experiments.runner`): a :class:`~jaxsim.problem.Problem`,
the shared stage :func:`experiments.stages.tune_and_compare`, claims, presets.

Problem: the PID of the fuzzy-PID paper's static plant ``2/((0.1s+1)(0.5s+1))`` (seed 000, paper 1,
lines 468–470) for a unit step, the loop of :class:`optim.problems.PIDTuning` (sampled PID at ``ts``,
P and I on the error, filtered derivative on the measurement, ``substeps`` RK4 steps per period),
``J = ∫ e² + ρ u² dt`` over ``t_final`` as running costs ``ise + ρ·control_energy``, the gains in a
box.  Tuners, each given ``budget`` simulations: ``gradient`` (Adam over the box's sigmoid
reparametrisation, ``n_starts`` starts), ``gradient_lbfgs`` (:func:`optim.lbfgs`: L-BFGS with a
backtracking line search, each trial one evaluation; stopped at gradient norm 1e-9), ``pso``,
``random``, ``grid`` (``⌊budget^{1/3}⌋`` points per gain), and ``ipopt``
(:func:`optim.casadi_pid.ipopt_tune`, the same loss rebuilt in CasADi with its own RK4; it stops at
its tolerance).  The IPOPT optimum is the reference every tuner's gap is measured
to; the JAX and CasADi losses and gradients are compared at the start point.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np

from experiments import stages
from experiments.runner import Study, StudyResult, paper_facts
from jaxsim.core import costs
from jaxsim.problem import Param, ParamSpace, Problem, Scenario
from optim.casadi_pid import casadi_value_and_grad, ipopt_tune
from optim.lbfgs import lbfgs as trial_lbfgs
from optim.problems import GAIN_NAMES, PIDTuning
from optim.tune import tune


@dataclass(frozen=True)
class Config:
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
    budget: int = 3200  # simulations per tuner
    n_starts: int = 4  # gradient tuner starts
    learning_rate: float = 0.05  # Adam, in the reparametrised (sigmoid) space
    n_particles: int = 32
    seed: int = 0


CLAIMS, ASSUMPTIONS = paper_facts("pid_tuning_comparison")


def tuning_of(cfg: Config) -> PIDTuning:
    """The loop settings (shared with the CasADi rebuild)."""
    return PIDTuning(
        K=cfg.K,
        T1=cfg.T1,
        T2=cfg.T2,
        tf=cfg.derivative_filter,
        ts=cfg.controller_period,
        substeps=cfg.substeps,
        t_final=cfg.t_final,
        rho=cfg.rho,
        lo=(0.0, 0.0, 0.0),
        hi=(cfg.kp_max, cfg.ki_max, cfg.kd_max),
    )


def problem_of(cfg: Config) -> Problem:
    """The gains ``(kp, ki, kd)`` as one vector parameter starting at the box centre; ``J`` as running costs."""
    tuning = tuning_of(cfg)
    lo, hi = tuning.box
    space = ParamSpace(gains=Param(lo=lo, hi=hi, init=(lo + hi) / 2, labels=GAIN_NAMES))
    objective = costs.combine(ise=costs.ise(), energy=(cfg.rho, costs.control_energy()))
    return Problem(
        "pid_static_plant",
        space,
        objective,
        lambda p, d: Scenario(tuning.closed_loop(p["gains"]), jnp.zeros(2), tuning.timing),
    )


def own_tuners(cfg: Config, tuning: PIDTuning) -> dict[str, Any]:
    """The two tuners beyond the standard ones (L-BFGS, IPOPT), in table order with the standard ones."""
    lbfgs = trial_lbfgs(max_backtracking_steps=20)

    def ipopt(problem: Problem, budget: int):
        res = ipopt_tune(tuning, np.asarray(problem.space.init["gains"]), max_iter=budget, tol=1e-10)
        return res._replace(params={"gains": jnp.asarray(res.params)})

    return {
        "gradient": None,
        "gradient_lbfgs": lambda problem, budget: tune(problem, optimizer=lbfgs, steps=budget, gtol=1e-9, patience=20),
        "pso": None,
        "random": None,
        "grid": None,
        "ipopt": ipopt,
    }


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    tuning, problem = tuning_of(cfg), problem_of(cfg)
    cmp = stages.tune_and_compare(
        problem,
        cfg.budget,
        own_tuners(cfg, tuning),
        reference="ipopt",
        progress=progress,
        loss_label="J = ∫ e² + ρu² dt (s)",
        key=jax.random.PRNGKey(cfg.seed),
        learning_rate=cfg.learning_rate,
        n_starts=cfg.n_starts,
        n_particles=cfg.n_particles,
        init_spread=1.0,
        batch_size=128,
        title=f"PID tuning, static plant: gap to the IPOPT optimum (budget {cfg.budget} simulations)",
    )
    ref = np.asarray(cmp.designs["ipopt"]["gains"])
    grad = np.asarray(cmp.designs["gradient"]["gains"])
    metrics = {f"optimum_{g}": float(v) for g, v in zip(GAIN_NAMES, ref)}
    metrics["gradient_vs_ipopt_gain_rel_diff"] = float(np.max(np.abs(grad - ref) / np.abs(ref)))
    start = problem.space.init
    v_jax, g_jax = problem.jitted.value_and_grad(start)
    v_ca, g_ca = casadi_value_and_grad(tuning, np.asarray(start["gains"]))
    metrics["jax_vs_casadi_loss_rel_diff"] = float(abs(float(v_jax) - v_ca) / abs(v_ca))
    g_jax = np.asarray(g_jax["gains"])
    metrics["jax_vs_casadi_grad_rel_diff"] = float(np.max(np.abs(g_jax - g_ca)) / np.max(np.abs(g_ca)))
    metrics["budget"] = cfg.budget
    losses = {r["tuner"]: r["best_loss"] for r in cmp.tables["comparison"]}
    steps = stages.responses(
        problem, cmp.designs, y_final=1.0, losses=losses, title="step responses with the tuned PID gains"
    )
    return stages.merge(
        cmp,
        steps,
        metrics=metrics,
        notes=[
            "one gradient evaluation counts one simulation (its extra cost shows in the wall time); IPOPT's "
            "count is its f + gradient evaluations",
            "the machine may be shared: wall times are indicative",
        ],
    )


STUDY = Study(
    name="pid_tuning_comparison",
    description="PID of the fuzzy-PID paper's static plant tuned by gradient / PSO / random / grid / IPOPT "
    "on equal budgets",
    config=Config,
    presets={"quick": dict(budget=640)},
    claims=CLAIMS,
    assumptions=ASSUMPTIONS,
    run=run,
)
