"""Study ``dc_motor_pi``: PI position control of a DC motor — the README's worked example.

Plant :mod:`jaxsim.plants.dc_motor`, ``θ/V = K/(s(Ts+1))``; a PI at 100 Hz follows a 1 rad step
(through a first-order set-point prefilter: with a raw step the ITAE-optimal PI of this type-2 loop
overshoots by 70 %) and rejects a load step (an equivalent voltage) at ``t_load``.  Loss
``J = ITAE + ρ·∫u² dt``.  Gradient
tuning and a particle swarm get the same budget of simulations; both designs then go through a
Monte Carlo over ±20 % in ``K`` and ``T``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp

import jaxsim.montecarlo as mc
from experiments import stages
from experiments.runner import Claim, Study, StudyResult, assumption
from jaxsim.control.pid import pid
from jaxsim.core import ClosedLoop, FilteredStep, Step, Timing
from jaxsim.core.costs import combine, control_energy, itae
from jaxsim.plants.dc_motor import dc_motor
from jaxsim.problem import Param, ParamSpace, Problem, Scenario


@dataclass(frozen=True)
class Config:
    K: float = 10.0  # rad/(V·s)
    T: float = 0.1  # s
    prefilter: float = 0.1  # s, time constant of the set-point prefilter
    load: float = 0.5  # V, load torque as an equivalent input voltage
    t_load: float = 1.0  # s
    t_final: float = 2.0  # s
    ts: float = 0.01  # s, controller period
    substeps: int = 2  # RK4 steps per period
    rho: float = 1e-2  # weight of the control energy, rad·s² per V²·s
    uncertainty: float = 0.2  # ± relative, on K and T
    budget: int = 1024  # simulations per tuner
    n_particles: int = 16
    n_starts: int = 4
    learning_rate: float = 0.1
    mc_runs: int = 2000
    seed: int = 0


def problem_of(cfg: Config) -> Problem:
    space = ParamSpace(
        kp=Param(lo=0.05, hi=20.0, init=1.0, log=True),  # V/rad
        ki=Param(lo=0.01, hi=20.0, init=0.5, log=True),
    )  # V/(rad·s)

    def build(p: dict[str, Any], d: dict[str, Any]) -> Scenario:
        pi = pid(kp=p["kp"], ki=p["ki"], anti_windup="none")
        loop = ClosedLoop(
            dc_motor(K=d["K"], T=d["T"]),
            pi,
            reference=FilteredStep(1.0, cfg.prefilter),
            disturbance=Step(cfg.load, cfg.t_load),
        )
        return Scenario(loop, jnp.zeros(2), Timing(cfg.t_final, cfg.ts / cfg.substeps, cfg.ts))

    return Problem(
        "dc_motor_pi",
        space,
        combine(itae=itae(), energy=(cfg.rho, control_energy())),
        build,
        nominal={"K": cfg.K, "T": cfg.T},
        uncertainty={
            "K": mc.deviation(cfg.K, cfg.uncertainty, relative=True),
            "T": mc.deviation(cfg.T, cfg.uncertainty, relative=True),
        },
    )


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    problem = problem_of(cfg)
    key = jax.random.PRNGKey(cfg.seed)
    tuned = stages.tune_and_compare(
        problem,
        cfg.budget,
        ("gradient", "pso"),
        key=key,
        learning_rate=cfg.learning_rate,
        n_starts=cfg.n_starts,
        n_particles=cfg.n_particles,
        progress=progress,
        loss_label="J = ITAE + ρ·energy (rad·s²)",
    )
    designs = tuned.designs
    steps = stages.responses(problem, designs, y_label="θ, rad", title="prefiltered step, load step at 1 s")
    robust = stages.robustness(problem, designs, cfg.mc_runs, cfg.seed, y_label="θ, rad", progress=progress)
    ratio = tuned.metrics["loss_gradient"] / tuned.metrics["loss_pso"]
    return stages.merge(tuned, steps, robust, metrics={"loss_ratio_gradient_to_pso": ratio})


STUDY = Study(
    name="dc_motor_pi",
    description="PI position control of a DC motor K/(s(Ts+1)): gradient vs PSO on equal budgets, "
    "Monte Carlo over ±20 % in K and T",
    config=Config,
    presets={"quick": dict(budget=256, mc_runs=500)},
    claims=[
        Claim(
            "loss_ratio_gradient_to_pso",
            paper=1.0,
            rel_tol=0.01,
            source="both tuners should find the same optimum of this two-gain problem",
        )
    ],
    assumptions={
        "motor": assumption("K = 10 rad/(V·s), T = 0.1 s", "a small PM motor; illustrative, no paper"),
        "loss": assumption("ITAE + 1e-2·∫u² dt", "ITAE for the transient, some energy for finite gains"),
    },
    run=run,
)
