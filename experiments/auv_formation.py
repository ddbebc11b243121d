"""Study ``auv_formation``: leader–follower AUV formation from camera measurements (seed 002).

The problem (loop, predictor, controller, metrics, tuning loss) is :mod:`jaxsim.problem.auv_formation`.

1. **Reproduction** (study 1 of the paper: exact leader pose, exact ``sign`` switching, RK4 at
   1 ms): initial error 7.8 m at t = 4 s, the time it falls below 0.2 m (paper: by 28 s), the
   steady-state error bands (paper: x ≤ 0.02, y ≤ 0.002, z ≤ 0.01 m), the relative velocity swing
   (paper: +1.2 → −1.1 m/s), the start-up transient while the window fills and the transient at
   t = 32 s; the same scenario without prediction between frames and with the Taylor polynomial
   alone, for comparison.
2. **Monte Carlo** (:mod:`jaxsim.montecarlo`): deviations uniform within ``±(M_Δ, d_Δ1, d_Δ2)``
   around the nominal plant and camera pose noise; distribution of the steady-state error and of the
   time to 0.2 m, with the paper's prediction between frames and without it (common random numbers).
3. **Tuning** (a :class:`~jaxsim.problem.Problem`): ``Λ``, ``K_s`` and the Kalman noise levels by
   gradient on a CVaR of the tracking loss over sampled deviations and camera noise (smooth ``tanh``
   switching), compared with the paper's values on held-out draws and, with the exact sign at 1 ms,
   on the paper's plant.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import jax
import numpy as np
import optax

import jaxsim.montecarlo as mc
from experiments import figures, stages
from experiments.runner import Claim, Study, StudyResult, paper_facts
from jaxsim.core.rollout import simulate
from jaxsim.plants import formation
from jaxsim.problem.auv_formation import (
    THRESHOLD_M,
    FormationSetup,
    build_loop,
    deviation_space,
    initial_state,
    mc_metric,
    run_metrics,
    tick_errors,
    timing,
    true_plant,
    tuning_problem,
)


@dataclass(frozen=True)
class Config(FormationSetup):  # + the scenario, loop, windows and tuning loss of FormationSetup
    mc_runs: int = 64  # per prediction mode; ≈ 2 s per vmapped 100 s rollout on the CPU
    tune_samples: int = 4  # deviation/noise draws in the CVaR
    tune_holdout: int = 8  # held-out draws for the comparison
    tune_steps: int = 12  # Adam steps
    tune_lr: float = 0.1  # Adam step in the reparametrised space
    seed: int = 0


PRESETS = {
    "quick": dict(mc_runs=4, tune_samples=2, tune_holdout=2, tune_steps=2),
    "tiny": dict(  # a 12 s run: every stage once (the test's preset)
        t_final=12.0,
        ss_window=(8.0, 12.0),
        t32_window=(10.0, 12.0),
        mc_runs=2,
        tune_samples=2,
        tune_holdout=2,
        tune_steps=1,
        tune_t_final=7.0,
        tune_loss_start=4.0,
        tune_dt=0.004,
    ),
}
SOURCE = "seed 002, study 1, Fig. 4 (spec 002.4, exact leader pose)"
CLAIMS = [
    Claim("err0_m", paper=7.8, rel_tol=1e-9, source=SOURCE + ": 7.8 m at t = 4 s (3 + 1.2·4)"),
    Claim(
        "t_to_0p2m_s",
        paper=28.0,
        band=(0.0, 28.0),
        source=SOURCE + ": x_FR error 0.2 m by t = 28 s",
        note="ours ≈ 29 s (read from the paper's figure)",
    ),
    *(
        Claim(f"ss_err_{ax}_m", paper=v, band=(0.0, v), source=SOURCE + ": steady-state deviation")
        for ax, v in (("x", 0.02), ("y", 0.002), ("z", 0.01))
    ),
    Claim(
        "rel_vel_x_min_mps",
        paper=-1.1,
        rel_tol=0.2,
        source=SOURCE + ": relative velocity +1.2 → −1.1 m/s",
        note="read from a figure",
    ),
]

_, ASSUMPTIONS = paper_facts("auv_formation")


def _fig_reproduction(tr: Any, cfg: Config) -> Any:
    import matplotlib.pyplot as plt

    t = np.asarray(tr.t)
    e, e_dot = jax.vmap(tick_errors)(tr.x, tr.t)
    e, e_dot = np.asarray(e), np.asarray(e_dot)
    lead = formation.LeaderParams()
    truth = np.asarray(jax.vmap(lambda s: formation.target_point(lead, s))(tr.t))
    est_err = np.linalg.norm(np.asarray(tr.x_hat.position) - truth, axis=1)
    fig, axes = plt.subplots(2, 2, figsize=(11, 6.5))
    for i, lab in enumerate("xyz"):
        axes[0, 0].plot(t, e[:, i], label=f"{lab}_FR")
    axes[0, 0].axhline(THRESHOLD_M, color="k", lw=0.6, ls=":")
    axes[0, 0].set(title="target point relative to the follower (FR)", ylabel="m", xlabel="t, s")
    axes[0, 0].legend()
    for i, lab in enumerate("xyz"):
        axes[0, 1].semilogy(t, np.abs(e[:, i]) + 1e-12, label=f"|{lab}_FR|")
    for val, ls in ((0.02, "--"), (0.002, ":"), (0.01, "-.")):
        axes[0, 1].axhline(val, color="k", lw=0.6, ls=ls)
    axes[0, 1].axvspan(*cfg.ss_window, color="0.9")
    axes[0, 1].set(title="|error| and the paper's bands (0.02 / 0.002 / 0.01 m)", xlabel="t, s", ylim=(1e-6, 20))
    axes[0, 1].legend(fontsize=8)
    for i, lab in enumerate("xyz"):
        axes[1, 0].plot(t, e_dot[:, i], label=f"d{lab}_FR/dt")
    axes[1, 0].set(title="relative velocity of the target point (FR)", ylabel="m/s", xlabel="t, s")
    axes[1, 0].legend()
    axes[1, 1].semilogy(t, est_err + 1e-12)
    axes[1, 1].axvline(cfg.t_follower_start, color="k", lw=0.6)
    axes[1, 1].axvline(cfg.t32_window[0], color="k", lw=0.6)
    axes[1, 1].set(title="target-point estimate error ‖X̂ − X*‖ (window fill, t = 32 s)", ylabel="m", xlabel="t, s")
    fig.tight_layout()
    return fig


# one jitted metrics program for every stage: the Kalman-mode loop of the reproduction and the
# tuning part's paper/tuned loops share their structure, so the second stage compiles nothing
_metrics = jax.jit(run_metrics, static_argnums=0)


def _floats(d: dict) -> dict:
    return {k: float(v) for k, v in d.items()}


def reproduction(cfg: Config, progress: Callable[..., Any]) -> tuple[dict, list, list, Any]:
    """Part 1: the paper's study 1 (exact pose) with and without prediction, and start-up variants."""
    plant = true_plant(cfg)
    key = jax.random.PRNGKey(cfg.seed)
    rows = []
    bar = progress(total=4, desc="reproduction", unit="run")
    by_mode = {}
    for mode in ("kalman", "polynomial", "hold"):
        m = _floats(_metrics(cfg, build_loop(cfg, plant, mode=mode), key))
        by_mode[mode] = m
        rows.append({"prediction": mode, **m})
        bar.update(1)
    late = _floats(_metrics(cfg, build_loop(cfg, plant, estimator_start=cfg.t_follower_start), key))
    bar.update(1)
    bar.close()
    startup = [
        {"estimator_start_s": cfg.estimator_start, **{k: by_mode["kalman"][k] for k in late}},
        {"estimator_start_s": cfg.t_follower_start, **late},
    ]
    tr = jax.jit(lambda: simulate(build_loop(cfg, plant), initial_state(), timing(cfg.dt, cfg.t_final, 10)))()
    return by_mode, rows, startup, tr


def error_bands(tr: Any, cfg: Config) -> list[dict]:
    """Max |e| per axis over consecutive windows after the transients (where do the bands hold?)."""
    t = np.asarray(tr.t)
    e = np.asarray(jax.vmap(lambda x, s: tick_errors(x, s)[0])(tr.x, tr.t))
    rows = []
    edges = [32.0, 40.0, 45.0, 50.0, 60.0, 70.0, 80.0, 90.0, 100.0]
    for lo, hi in zip(edges[:-1], edges[1:]):
        sel = (t >= lo) & (t < hi)
        if sel.any():
            mx = np.abs(e[sel]).max(axis=0)
            rows.append(
                {
                    "t_from_s": lo,
                    "t_to_s": hi,
                    "max_abs_x_m": mx[0],
                    "max_abs_y_m": mx[1],
                    "max_abs_z_m": mx[2],
                    "within_paper_bands": bool(mx[0] <= 0.02 and mx[1] <= 0.002 and mx[2] <= 0.01),
                }
            )
    return rows


def monte_carlo_part(cfg: Config, progress: Callable[..., Any]) -> dict:
    runs = cfg.mc_runs
    space = deviation_space(cfg)
    out = {}
    for label, mode in (("with_prediction", "kalman"), ("without_prediction", "hold")):
        out[label] = mc.monte_carlo(
            mc_metric(cfg, mode), space, runs, cfg.seed, block_size=min(runs, 32), progress=progress
        )
    return out


def tuning_part(cfg: Config, progress: Callable[..., Any]) -> tuple[dict, list, stages.TuningStage]:
    """Tune on ``tune_samples`` draws; paper vs tuned on held-out draws and with the exact sign at 1 ms."""
    train = tuning_problem(cfg, cfg.tune_samples, cfg.seed + 1)
    held = tuning_problem(cfg, cfg.tune_holdout, cfg.seed + 2)
    stage = stages.gradient_tuning(  # reverse mode: 14 parameters over a 23k-step scan
        train,
        steps=cfg.tune_steps,
        optimizer=optax.adam(cfg.tune_lr),
        mode="reverse",
        progress=progress,
        loss_label="CVaR loss",
        title="gradient tuning of Λ, K_s, Q, R",
    )
    res = stage.result
    theta0 = train.space.init
    key = jax.random.PRNGKey(cfg.seed)
    exact, rows = {}, []
    for label, th in (("paper", theta0), ("tuned", res.params)):
        loop = build_loop(
            cfg,
            true_plant(cfg),
            lam=th["lam"],
            k_s=th["k_s"],
            accel_psd=10.0 ** th["log10_accel_psd"],
            meas_std=10.0 ** th["log10_meas_std"],
        )
        exact[label] = {
            # the paper's gains are the tuner's start: its step-0 loss (an eager evaluation costs ~15 s of tracing)
            "train_cvar": float(stage.tables["tuning_history"][0]["loss"]) if label == "paper" else float(res.loss),
            "holdout_cvar": float(held.jitted.loss(th)),
            **_floats(_metrics(cfg, loop, key)),
        }
        rows.append(
            {
                "gains": label,
                **train.space.flat(th),
                "accel_psd": float(10.0 ** th["log10_accel_psd"]),
                "meas_std": float(10.0 ** th["log10_meas_std"]),
                **exact[label],
            }
        )
    return exact, rows, stage


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    if cfg.ss_window[1] > cfg.t_final + 1e-9:
        raise ValueError(f"ss_window: must end by t_final={cfg.t_final}, got {cfg.ss_window}")
    nominal, rows, startup, tr = reproduction(cfg, progress)
    bands = error_bands(tr, cfg)
    mc_res = monte_carlo_part(cfg, progress)
    exact, tune_rows, tuning = tuning_part(cfg, progress)
    info = {"steps": tuning.result.n_steps, "wall_s": tuning.result.wall_s}

    k = nominal["kalman"]
    wp, wo = mc_res["with_prediction"], mc_res["without_prediction"]
    metrics = {
        "err0_m": k["err0_m"],
        "t_to_0p2m_s": k["t_to_0p2m_s"],
        "ss_err_x_m": k["ss_err_x_m"],
        "ss_err_y_m": k["ss_err_y_m"],
        "ss_err_z_m": k["ss_err_z_m"],
        "mc_t_to_0p2m_p95_s": float(wp["t_to_0p2m_s"].quantile(0.95)),
        "mc_ss_err_p95_m_with_prediction": float(wp["ss_err_m"].quantile(0.95)),
        "mc_ss_err_p95_m_without_prediction": float(wo["ss_err_m"].quantile(0.95)),
        "t_last_above_0p2m_s": k["t_last_above_0p2m_s"],
        "t32_peak_err_m": k["t32_peak_err_m"],
        "rel_vel_x_min_mps": k["rel_vel_x_min_mps"],
        "ss_rel_vel_x_mps": k["ss_rel_vel_x_mps"],
        "startup_est_err_max_m": k["startup_est_err_max_m"],
        "startup_est_settled_s": k["startup_est_settled_s"],
        "t32_est_err_peak_m": k["t32_est_err_peak_m"],
        "t32_est_recovery_s": k["t32_est_recovery_s"],
        "ss_err_m_without_prediction": nominal["hold"]["ss_err_m"],
        "ss_err_m_polynomial_only": nominal["polynomial"]["ss_err_m"],
        "mc_runs": int(wp.runs),
        "mc_t_to_0p2m_p50_s": float(wp["t_to_0p2m_s"].quantile(0.5)),
        "mc_t_to_0p2m_p95_s_without_prediction": float(wo["t_to_0p2m_s"].quantile(0.95)),
        "mc_ss_err_p50_m_with_prediction": float(wp["ss_err_m"].quantile(0.5)),
        "mc_ss_err_p50_m_without_prediction": float(wo["ss_err_m"].quantile(0.5)),
        "mc_p_reached_0p2m": float(wp["reached_0p2m"].probability),
        "tune_holdout_cvar_paper": exact["paper"]["holdout_cvar"],
        "tune_holdout_cvar_tuned": exact["tuned"]["holdout_cvar"],
        "tune_train_cvar_paper": exact["paper"]["train_cvar"],
        "tune_train_cvar_tuned": exact["tuned"]["train_cvar"],
        "tuned_t_to_0p2m_s": exact["tuned"]["t_to_0p2m_s"],
        "tuned_ss_err_m": exact["tuned"]["ss_err_m"],
        "tuned_t32_peak_err_m": exact["tuned"]["t32_peak_err_m"],
        "tune_steps": info["steps"],
        "tune_wall_s": info["wall_s"],
    }
    mc_rows = [{"prediction": label, **res.row()} for label, res in mc_res.items()]
    figs = {
        "reproduction": _fig_reproduction(tr, cfg),
        "monte_carlo": figures.mc_cdfs(
            mc_res,
            {"ss_err_m": ("steady-state error ‖e‖, m", True), "t_to_0p2m_s": ("time to 0.2 m, s", False)},
            title="Monte Carlo over deviations (uniform ±Δ) and camera noise",
        ),
    }
    notes = [
        f"reproduction: RK4 at dt = {cfg.dt} s over {cfg.t_final} s, exact leader pose, exact sign; "
        f"paper: 7.8 m → 0.2 m by 28 s, ss bands x 0.02 / y 0.002 / z 0.01 m, relative velocity +1.2 → −1.1 m/s",
        f"Monte Carlo: {int(wp.runs)} runs per mode, deviations uniform ±Δ, camera pose noise "
        f"{cfg.cam_pos_std} m / {cfg.cam_yaw_std_deg}°; same draws for both modes (common random numbers)",
        f"tuning: dt = {cfg.tune_dt} s, tanh width {cfg.tune_width} m/s; the 'paper'/'tuned' rows of table "
        "tuning re-run both with the exact sign at dt = 1 ms",
    ]
    own = stages.Stage(
        tables={
            "reproduction": rows,
            "startup_variants": startup,
            "error_bands": bands,
            "monte_carlo": mc_rows,
            "tuning": tune_rows,
        },
        figures=figs,
    )
    return stages.merge(own, tuning, metrics=metrics, notes=notes)


STUDY = Study(
    name="auv_formation",
    description="Leader–follower AUV formation from a 10 Hz camera: LS + Kalman leader prediction, "
    "computed torque + sliding mode; reproduction, Monte Carlo, CVaR gradient tuning (seed 002)",
    config=Config,
    presets=PRESETS,
    claims=CLAIMS,
    assumptions=ASSUMPTIONS,
    run=run,
)
