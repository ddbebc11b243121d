"""Study ``noisy_pid_mc``: Monte-Carlo robustness of a PI loop with a noisy sensor (demo of the MC engine).

Plant: the fuzzy-PID paper's static plant ``K/((T1 s+1)(T2 s+1))`` (seed 000, paper 1; K = 2,
T1 = 0.1, T2 = 0.5), with the paper-style uncertainty "nominal ± Δ" on ``K`` (±20 %) and on the time
constants (±10 %), and white Gaussian sensor noise.  Controller: PI designed for maximum stability
degree on the nominal plant (``jaxsim.control.stability_degree``: kp = 0.7, ki = 1.6, triple root at −4).

Per run (``PerRun.metric``, also used by ``python -m experiments sweep noisy_pid_mc``): unit-step
response over ``t_final``; metrics ``itae`` (∫ t|r − y| dt on the true output), ``overshoot`` in %
of the set-point, and the event ``overshoot_exceeded`` (overshoot > ``overshoot_limit`` %).

The study itself runs a Monte Carlo at the nominal gains and a sweep over ``kp`` (ki fixed), and
checks the engine against a direct simulation: with the uncertainty and noise switched off every
run must give the deterministic ITAE of ``simulate`` + ``metrics.itae``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np

import jaxsim.montecarlo as mc
from experiments.study import PerRun, Study, StudyResult, assumption
from jaxsim.control.pid import pid
from jaxsim.control.stability_degree import max_stability_degree
from jaxsim.core import metrics as core_metrics
from jaxsim.core.rollout import ClosedLoop, Timing, fold, simulate
from jaxsim.core.signals import Step
from jaxsim.core.system import gaussian_sensor
from jaxsim.montecarlo.plots import plot_distribution, plot_sweep
from jaxsim.plants.second_order import StaticParams, static_plant, static_transfer_function


@dataclass(frozen=True)
class Config:
    quick: bool = False
    K: float = 2.0  # paper lines 468–470
    T1: float = 0.1
    T2: float = 0.5
    K_delta: float = 0.2  # ±20 % (relative), assumed
    T_delta: float = 0.1  # ±10 % on T1 and T2 (relative), assumed
    noise_std: float = 0.02  # sensor noise, output units, assumed
    overshoot_limit: float = 5.0  # %, event threshold
    t_final: float = 5.0  # s
    dt: float = 1e-3  # s, plant step = controller period (quick: 5e-3)
    runs: int = 20_000  # quick: 2,000
    kp_sweep: tuple = (0.3, 1.5, 7)  # lo, hi, points (quick: 3 points)
    seed: int = 0


ASSUMPTIONS = {
    "K_delta": assumption(0.2, "the papers quote ±20 % parameter spreads for robustness checks; applied to K"),
    "T_delta": assumption(0.1, "time constants are better known than the gain; ±10 % chosen"),
    "noise_std": assumption(0.02, "1 % of the unit set-point's steady state; not from the paper"),
    "overshoot_limit": assumption(5.0, "a common specification, not from the paper"),
}


def nominal_gains(cfg: Config) -> dict[str, float]:
    """Maximum-stability-degree PI for the nominal static plant."""
    num, den = (np.asarray(v) for v in static_transfer_function(StaticParams(cfg.K, cfg.T1, cfg.T2)))
    return max_stability_degree(num, den, "PI").gains


def _timing(cfg: Config) -> Timing:
    dt = 5e-3 if cfg.quick else cfg.dt
    return Timing(t_final=cfg.t_final, dt=dt, controller_period=dt)


def _loop(p: dict[str, Any]) -> ClosedLoop:
    plant = static_plant(StaticParams(K=p["K"], T1=p["T1"], T2=p["T2"]))
    return ClosedLoop(plant, pid(kp=p["kp"], ki=p["ki"], anti_windup="none"),
                      reference=Step(1.0), sensor=gaussian_sensor(p["noise_std"]))


def make_metric(cfg: Config) -> Callable[[jax.Array, dict[str, Any]], dict[str, jax.Array]]:
    timing = _timing(cfg)
    ts = timing.ts

    def metric(key: jax.Array, p: dict[str, Any]) -> dict[str, jax.Array]:
        def acc(a, tick):
            itae, peak = a
            return itae + core_metrics.itae_integrand(tick.t, tick.r[0] - tick.y[0]) * ts, jnp.maximum(peak, tick.y[0])

        (itae, peak), _ = fold(_loop(p), jnp.zeros(2), timing, acc, (jnp.zeros(()), jnp.asarray(-jnp.inf)), key=key)
        overshoot = 100.0 * jnp.maximum(peak - 1.0, 0.0)
        return {"itae": itae, "overshoot": overshoot, "overshoot_exceeded": overshoot > cfg.overshoot_limit}

    return metric


def per_run(cfg: Config) -> PerRun:
    gains = nominal_gains(cfg)
    nominal = {"kp": gains["kp"], "ki": gains["ki"], "K": cfg.K, "T1": cfg.T1, "T2": cfg.T2,
               "noise_std": cfg.noise_std}
    uncertain = {}
    if cfg.K_delta > 0:
        uncertain["K"] = mc.deviation(cfg.K, cfg.K_delta, relative=True)
    if cfg.T_delta > 0:
        uncertain["T1"] = mc.deviation(cfg.T1, cfg.T_delta, relative=True)
        uncertain["T2"] = mc.deviation(cfg.T2, cfg.T_delta, relative=True)
    return PerRun(make_metric(cfg), nominal, uncertain)


def deterministic_itae(cfg: Config, p: dict[str, float]) -> float:
    """ITAE of one noise-free rollout via ``simulate`` + ``metrics.itae`` (independent of ``fold``)."""
    tr = simulate(_loop({**p, "noise_std": 0.0}), jnp.zeros(2), _timing(cfg))
    return float(core_metrics.itae(tr.t, tr.r[:, 0] - tr.y[:, 0]))


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    runs = 2_000 if cfg.quick else cfg.runs
    lo, hi, n_kp = cfg.kp_sweep
    n_kp = 3 if cfg.quick else int(n_kp)
    spec = per_run(cfg)
    space = {**spec.nominal, **spec.uncertain}
    nominal_mc = mc.monte_carlo(spec.metric, space, runs, cfg.seed, progress=progress)
    swept = mc.sweep(spec.metric, space, mc.grid({"kp": (lo, hi, n_kp)}), runs, cfg.seed, progress=progress)

    exact = mc.monte_carlo(spec.metric, {**spec.nominal, "noise_std": 0.0}, 1000, cfg.seed)
    reference = deterministic_itae(cfg, spec.nominal)
    itae, over, event = nominal_mc["itae"], nominal_mc["overshoot"], nominal_mc["overshoot_exceeded"]
    w_lo, w_hi = event.interval(0.95)
    sweep_rows = swept.table()
    best = min(sweep_rows, key=lambda r: r["itae:mean"])
    metrics = {
        "kp_nominal": spec.nominal["kp"], "ki_nominal": spec.nominal["ki"], "runs": runs,
        "itae_mean": float(itae.mean), "itae_std": float(itae.std),
        "itae_p50": float(itae.quantile(0.5)), "itae_p95": float(itae.quantile(0.95)),
        "overshoot_mean": float(over.mean), "overshoot_p95": float(over.quantile(0.95)),
        "p_overshoot_exceeded": float(event.probability),
        "p_overshoot_exceeded_wilson_low": float(w_lo), "p_overshoot_exceeded_wilson_high": float(w_hi),
        "best_kp_by_mean_itae": best["kp"],
        "deterministic_itae": reference,
        "engine_vs_simulate_itae_rel_diff": abs(float(exact["itae"].mean) - reference) / reference,
        "engine_noise_free_itae_std": float(exact["itae"].std),
        "runs_per_s": runs / max(nominal_mc.wall_s, 1e-9),
    }
    figures = {"distribution_nominal": plot_distribution(nominal_mc), **plot_sweep(swept)}
    return StudyResult(
        metrics=metrics,
        tables={"nominal": [nominal_mc.row()], "kp_sweep": sweep_rows},
        assumptions=ASSUMPTIONS,
        figures=figures,
        notes=[f"{runs} runs per point, RK4 at dt = controller period = {_timing(cfg).dt} s over "
               f"{cfg.t_final} s; same PRNG key at every sweep point (common random numbers)",
               "quantiles from the log-bucket sketch: relative error ≤ 1e-3"],
    )


STUDY = Study(
    name="noisy_pid_mc",
    description="Monte Carlo of a PI loop (fuzzy-PID paper's static plant, ±20 % gain, noisy sensor): ITAE, overshoot",
    config_cls=Config,
    run=run,
    per_run=per_run,
)
