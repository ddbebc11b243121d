"""Study ``noisy_pid_mc``: Monte-Carlo robustness of a PI loop with a noisy sensor (demo of the MC engine).

Plant: the fuzzy-PID paper's static plant ``K/((T1 s+1)(T2 s+1))`` (seed 000, paper 1; K = 2,
T1 = 0.1, T2 = 0.5), with the paper-style uncertainty "nominal ± Δ" on ``K`` (±20 %) and on the time
constants (±10 %), and white Gaussian sensor noise.  Controller: PI designed for maximum stability
degree on the nominal plant (``jaxsim.control.stability_degree``: kp = 0.7, ki = 1.6, triple root at −4).

The loop is a :class:`~jaxsim.problem.Problem` (gains as params, plant and noise level as draws)
whose objective is the running costs ``itae`` (∫ t|r − y| dt on the true output) and ``overshoot``
(peak above the unit set-point, %).  Per run (``PerRun.metric``, also used by ``python -m
experiments sweep noisy_pid_mc``): those terms and the event ``overshoot_exceeded`` (overshoot >
``overshoot_limit`` %).  The study runs a Monte Carlo at the nominal gains and a sweep over ``kp``
(ki fixed), and checks the engine against a direct simulation: with the uncertainty and noise
switched off every run must give the deterministic ITAE of ``simulate`` + ``metrics.itae``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np

import jaxsim.montecarlo as mc
from experiments.runner import PerRun, Study, StudyResult, paper_facts
from jaxsim.control.pid import pid
from jaxsim.control.stability_degree import max_stability_degree
from jaxsim.core import costs
from jaxsim.core import metrics as core_metrics
from jaxsim.core.rollout import ClosedLoop, Timing
from jaxsim.core.signals import Step
from jaxsim.core.system import gaussian_sensor
from jaxsim.montecarlo.plots import plot_distribution, plot_sweep
from jaxsim.plants.second_order import StaticParams, static_plant, static_transfer_function
from jaxsim.problem import Param, ParamSpace, Problem, Scenario


@dataclass(frozen=True)
class Config:
    K: float = 2.0  # paper lines 468–470
    T1: float = 0.1
    T2: float = 0.5
    K_delta: float = 0.2  # ±20 % (relative), assumed
    T_delta: float = 0.1  # ±10 % on T1 and T2 (relative), assumed
    noise_std: float = 0.02  # sensor noise, output units, assumed
    overshoot_limit: float = 5.0  # %, event threshold
    t_final: float = 5.0  # s
    dt: float = 1e-3  # s, plant step = controller period
    runs: int = 20_000  # Monte-Carlo runs per point
    kp_sweep: tuple = (0.3, 1.5, 7)  # lo, hi, points
    seed: int = 0


CLAIMS, ASSUMPTIONS = paper_facts("noisy_pid_mc")


def nominal_gains(cfg: Config) -> dict[str, float]:
    """Maximum-stability-degree PI for the nominal static plant."""
    num, den = (np.asarray(v) for v in static_transfer_function(StaticParams(cfg.K, cfg.T1, cfg.T2)))
    return max_stability_degree(num, den, "PI").gains


def peak_overshoot(y_final: float = 1.0) -> costs.RunningCost:
    """``100·max(0, max_t y − y_final)/|y_final|`` of output 0 (%), a running max (not additive)."""
    return costs.RunningCost(
        init=lambda: jnp.asarray(-jnp.inf),
        update=lambda a, tick, ts: jnp.maximum(a, tick.y[0]),
        finish=lambda a: 100.0 * jnp.maximum(a - y_final, 0.0) / abs(y_final),
    )


def problem_of(cfg: Config) -> Problem:
    """Gains ``kp``, ``ki`` as params; ``K``, ``T1``, ``T2``, ``noise_std`` as draws (nominal ± Δ)."""
    gains = nominal_gains(cfg)
    space = ParamSpace(
        kp=Param(lo=1e-3, hi=100.0, init=gains["kp"], log=True), ki=Param(lo=1e-3, hi=100.0, init=gains["ki"], log=True)
    )
    timing = Timing(t_final=cfg.t_final, dt=cfg.dt, controller_period=cfg.dt)

    def build(p: dict[str, Any], d: dict[str, Any]) -> Scenario:
        loop = ClosedLoop(
            static_plant(StaticParams(K=d["K"], T1=d["T1"], T2=d["T2"])),
            pid(kp=p["kp"], ki=p["ki"], anti_windup="none"),
            reference=Step(1.0),
            sensor=gaussian_sensor(d["noise_std"]),
        )
        return Scenario(loop, jnp.zeros(2), timing)

    uncertainty = {}
    if cfg.K_delta > 0:
        uncertainty["K"] = mc.deviation(cfg.K, cfg.K_delta, relative=True)
    if cfg.T_delta > 0:
        uncertainty["T1"] = mc.deviation(cfg.T1, cfg.T_delta, relative=True)
        uncertainty["T2"] = mc.deviation(cfg.T2, cfg.T_delta, relative=True)
    return Problem(
        "noisy_pi",
        space,
        costs.combine(itae=costs.itae(), overshoot=peak_overshoot()),
        build,
        nominal={"K": cfg.K, "T1": cfg.T1, "T2": cfg.T2, "noise_std": cfg.noise_std},
        uncertainty=uncertainty,
    )


def per_run(cfg: Config) -> PerRun:
    """One run's terms of the problem (gains and plant both in the Monte-Carlo space) plus the event."""
    problem = problem_of(cfg)
    gains = problem.space.keys

    def metric(key: jax.Array, p: dict[str, Any]) -> dict[str, jax.Array]:
        terms = problem.evaluate({g: p[g] for g in gains}, {d: p[d] for d in problem.nominal}, key).terms
        return {**terms, "overshoot_exceeded": terms["overshoot"] > cfg.overshoot_limit}

    nominal = {g: float(v) for g, v in problem.space.init.items()}
    return PerRun(metric, {**nominal, **problem.nominal}, problem.uncertainty)


def deterministic_itae(cfg: Config, p: dict[str, float]) -> float:
    """ITAE of one noise-free rollout at the gains ``p`` via ``simulate`` + ``metrics.itae`` (independent
    of ``fold`` and of the Monte-Carlo engine)."""
    tr = problem_of(cfg).simulate({"kp": p["kp"], "ki": p["ki"]}, {"noise_std": 0.0})
    return float(core_metrics.itae(tr.t, tr.r[:, 0] - tr.y[:, 0]))


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    spec = per_run(cfg)
    space = {**spec.nominal, **spec.uncertain}
    lo, hi, n_kp = cfg.kp_sweep
    nominal_mc = mc.monte_carlo(spec.metric, space, cfg.runs, cfg.seed, progress=progress)
    swept = mc.sweep(spec.metric, space, mc.grid({"kp": (lo, hi, int(n_kp))}), cfg.runs, cfg.seed, progress=progress)
    exact = mc.monte_carlo(spec.metric, {**spec.nominal, "noise_std": 0.0}, 1000, cfg.seed)
    reference = deterministic_itae(cfg, spec.nominal)

    itae, over, event = nominal_mc["itae"], nominal_mc["overshoot"], nominal_mc["overshoot_exceeded"]
    w_lo, w_hi = event.interval(0.95)
    sweep_rows = swept.table()
    metrics = {
        "kp_nominal": spec.nominal["kp"],
        "ki_nominal": spec.nominal["ki"],
        "runs": cfg.runs,
        "itae_mean": float(itae.mean),
        "itae_std": float(itae.std),
        "itae_p50": float(itae.quantile(0.5)),
        "itae_p95": float(itae.quantile(0.95)),
        "overshoot_mean": float(over.mean),
        "overshoot_p95": float(over.quantile(0.95)),
        "p_overshoot_exceeded": float(event.probability),
        "p_overshoot_exceeded_wilson_low": float(w_lo),
        "p_overshoot_exceeded_wilson_high": float(w_hi),
        "best_kp_by_mean_itae": min(sweep_rows, key=lambda r: r["itae:mean"])["kp"],
        "deterministic_itae": reference,
        "engine_vs_simulate_itae_rel_diff": abs(float(exact["itae"].mean) - reference) / reference,
        "engine_noise_free_itae_std": float(exact["itae"].std),
        "runs_per_s": cfg.runs / max(nominal_mc.wall_s, 1e-9),
    }
    return StudyResult(
        metrics=metrics,
        tables={"nominal": [nominal_mc.row()], "kp_sweep": sweep_rows},
        figures={"distribution_nominal": plot_distribution(nominal_mc), **plot_sweep(swept)},
        notes=[
            f"{cfg.runs} runs per point, RK4 at dt = controller period = {cfg.dt} s over {cfg.t_final} s; "
            "same PRNG key at every sweep point (common random numbers)",
            "quantiles from the log-bucket sketch: relative error ≤ 1e-3",
        ],
    )


STUDY = Study(
    name="noisy_pid_mc",
    description="Monte Carlo of a PI loop (fuzzy-PID paper's static plant, ±20 % gain, noisy sensor): ITAE, overshoot",
    config=Config,
    presets={"quick": dict(dt=5e-3, runs=2_000, kp_sweep=(0.3, 1.5, 3))},
    claims=CLAIMS,
    assumptions=ASSUMPTIONS,
    run=run,
    per_run=per_run,
)
