"""Study ``auv_formation``: leader–follower AUV formation from camera measurements (seed 002).

The follower (fully actuated 6-DOF Fossen AUV, :mod:`jaxsim.plants.auv`, true parameters = nominal
+ the paper's deviations) keeps the target point ``X_L* = [−1.5, −6]`` m beside the leader, which
flies the paper's straight-then-curved trajectory (:mod:`jaxsim.plants.formation`).  It sees the
leader only through a 10 Hz camera; a sliding-window quartic fit over 51 frames plus a Kalman filter
predicting every 1 ms (:mod:`jaxsim.estimation.leader_predictor`) gives the target point's position,
velocity and acceleration between frames, and a computed-torque + variable-structure controller
(:mod:`jaxsim.control.auv_tracking`, ``K_s = 100·I``, ``Λ = diag(0.2, 0.2, 0.2, 0.2, 0.4, 0.4)``)
drives the follower.  All rollouts are one ``lax.scan``/``fold`` of :mod:`jaxsim.core.rollout`.

Parts:

1. **Reproduction** (study 1 of the paper: exact leader pose, exact ``sign`` switching, RK4 at
   1 ms): initial error 7.8 m at t = 4 s, the time it falls below 0.2 m (paper: by 28 s), the
   steady-state error bands (paper: x ≤ 0.02, y ≤ 0.002, z ≤ 0.01 m), the relative velocity swing
   (paper: +1.2 → −1.1 m/s), the start-up transient while the window fills and the transient at
   t = 32 s; the same scenario without prediction between frames and with the Taylor polynomial
   alone, for comparison.
2. **Monte Carlo** (:mod:`jaxsim.montecarlo`): deviations uniform within ``±(M_Δ, d_Δ1, d_Δ2)``
   around the nominal plant and camera pose noise; distribution of the steady-state error and of the
   time to 0.2 m, with the paper's prediction between frames and without it (common random numbers).
3. **Tuning** (:func:`optim.tune.tune`): ``Λ``, ``K_s`` and the Kalman noise levels by gradient on a
   CVaR of the tracking loss over sampled deviations and camera noise (smooth ``tanh`` switching for
   the gradient), compared with the paper's values on held-out draws and, with the exact sign at
   1 ms, on the paper's plant.

Error definitions: ``e = R_z(ψ_F)ᵀ (X*_true − p_F)``, the true target point relative to the follower
in its level frame FR (what Fig. 4 shows).  ``t_to_0p2m_s``: first time after the start at which
``‖e‖ ≤ 0.2 m``.  Steady-state errors: ``max |e_x|, |e_y|, |e_z|`` over ``ss_window``.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np
import optax

import jaxsim.montecarlo as mc
from experiments.study import Study, StudyResult, assumption
from jaxsim.control.auv_tracking import PAPER_KS, PAPER_LAMBDA, auv_tracking
from jaxsim.core.rollout import ClosedLoop, Timing, fold, simulate
from jaxsim.core.system import add_input_disturbance
from jaxsim.estimation.leader_predictor import leader_predictor
from jaxsim.plants import auv, formation, marine
from optim.reparam import Interval
from optim.robust import cvar, robust_loss
from optim.tune import tune

THRESHOLD_M = 0.2


@dataclass(frozen=True)
class Config:
    quick: bool = False
    dt: float = 1e-3  # s: plant step = control period = prediction period h_Δ (paper line 1007)
    t_final: float = 100.0  # s (not given; long enough for both transients to decay)
    t_follower_start: float = 4.0  # s, paper line 1112
    estimator_start: float = 0.0  # s: the camera sees the leader from t = 0 (paper line 1031)
    camera_period: float = 0.1  # s, paper line 1006
    window: int = 51  # M + 1 samples, M = 50 (paper line 1009)
    degree: int = 4  # N (paper line 1009)
    lam: tuple = PAPER_LAMBDA
    k_s: tuple = PAPER_KS
    switch: str = "sign"
    width: float = 0.01  # m/s, boundary layer of the smooth variant (unused by sign)
    deviation_sign: float = 1.0  # true = nominal + sign·Δ
    accel_psd: float = 1e-3  # m²/s³, Kalman process noise (assumed)
    meas_std: float = 0.01  # m, camera noise assumed by the Kalman R (assumed)
    p0: tuple = (1.0, 1.0)  # initial variances of [v, X] per axis (assumed)
    ss_window: tuple = (60.0, 100.0)  # s, steady-state window
    t32_window: tuple = (32.0, 45.0)  # s, window of the manoeuvre transient
    cam_pos_std: float = 0.01  # m, Monte-Carlo camera noise on the leader's relative position
    cam_yaw_std_deg: float = 0.2  # deg, Monte-Carlo camera noise on the leader's relative yaw
    mc_runs: int = 64  # per prediction mode (quick: 4); ≈ 2 s per vmapped 100 s rollout on the CPU
    tune_dt: float = 2e-3  # s, step of the tuning rollouts
    tune_t_final: float = 46.0  # s
    tune_loss_start: float = 20.0  # s, the loss integrates from here (manoeuvre + steady state)
    tune_width: float = 0.05  # m/s, tanh temperature while tuning
    tune_samples: int = 4  # deviation/noise draws in the CVaR (quick: 2)
    tune_holdout: int = 8  # held-out draws for the comparison (quick: 2)
    tune_steps: int = 12  # Adam steps (quick: 2)
    tune_lr: float = 0.1  # Adam step in the reparametrised space
    cvar_alpha: float = 0.75
    effort_weight: float = 1e-3  # ρ on mean (τ/100 N)² in the tuning loss
    seed: int = 0


ASSUMPTIONS = {
    "frames": assumption("NED (z down), zyx Euler angles, Fossen's C(ν) from M",
                         "the paper cites Fossen [25] without writing the matrices out"),
    "deviation_sign": assumption("true = nominal + Δ (M_Δ added to the added-mass block)",
                                 "the paper says the parameters 'differ by' Δ without a sign"),
    "weight": assumption("W = B = 170 kg · 9.81 m/s², CG 0.01 m below CB",
                         "'zero buoyancy' and the 0.01 m offset are printed; which mass gives W is not"),
    "estimator_start": assumption(0.0, "the camera sees the leader from t = 0; starting the zero-filled "
                                  "window with the follower (t = 4 s) makes the quartic fit report "
                                  "~20 m/s and the follower swing at ±11 m/s, unlike the paper's "
                                  "+1.2 → −1.1 m/s (see table startup_variants)"),
    "window_fill": assumption("zeros in FR (the target at the follower's own position)",
                              "paper: 'the array Ω is filled with zeros' before the start"),
    "attitude_reference": assumption("roll 0, pitch and yaw along the target point's velocity, weighted "
                                     "by a smoothstep of its horizontal speed (0 below 0.2, 1 above 0.5 m/s)",
                                     "the paper's rule 'near the target point' lost its symbol; pointing at "
                                     "the target point is singular there, and the course of a slow target "
                                     "point (while the window fills, under camera noise) is ill-defined"),
    "switch": assumption("exact sign for the reproduction; tanh(s/0.05) while tuning",
                         "the paper says 'variable structure' and 'sliding mode' without a formula"),
    "kalman_noise": assumption({"accel_psd_m2_s3": 1e-3, "meas_std_m": 0.01, "p0": (1.0, 1.0)},
                               "the paper gives no P_p(0), Q_p, R_p; R is the fit's covariance for "
                               "white camera noise meas_std, Q a white-acceleration model"),
    "camera_noise": assumption({"pos_std_m": 0.01, "yaw_std_deg": 0.2},
                               "pose noise (no intrinsics or beacon layout in the paper); ~1 cm and "
                               "0.2° are typical of LM-PnP at 5–10 m; the reproduction uses the exact "
                               "pose like the paper's study 1"),
    "t_final": assumption(100.0, "the figure's time axis is not readable; 100 s covers both transients"),
    "ss_window": assumption((60.0, 100.0), "after the t = 32 s transient has decayed below the bands "
                            "(Λ = 0.2 gives a 5 s time constant); earlier windows in table error_bands"),
    "t_to_0p2m": assumption("first time ‖e‖ ≤ 0.2 m after the start",
                            "the paper: 'reduced to 0.2 m by t = 28 s'"),
    "tuning_loss": assumption("mean ‖e‖² + ρ·mean (τ/100 N)² over [20, 46] s, ρ = 1e-3, CVaR₀.₇₅",
                              "formation keeping through the manoeuvre with noise and deviations; "
                              "no criterion in the paper"),
}


# ---------------------------------------------------------------------------------------------
# building the loop


def timing(dt: float, t_final: float, save_every: int = 1) -> Timing:
    return Timing(t_final=t_final, dt=dt, controller_period=dt, save_every=save_every)


def initial_state() -> jax.Array:
    """Follower at (−1.5, −6, 1.2) m, at rest, aligned with the absolute frame (paper line 1106)."""
    return auv.initial_state([-1.5, -6.0, 1.2])


def build_loop(
    cfg: Config,
    plant: auv.AUVParams,
    *,
    dt: float | None = None,
    mode: str = "kalman",
    lam: Any = None,
    k_s: Any = None,
    switch: str | None = None,
    width: Any = None,
    accel_psd: Any = None,
    meas_std: Any = None,
    cam_pos_std: Any = 0.0,
    cam_yaw_std: Any = 0.0,
    estimator_start: Any = None,
) -> ClosedLoop:
    """The closed loop with ``cfg``'s values unless overridden (``None`` = from ``cfg``)."""
    dt = cfg.dt if dt is None else dt
    lead = formation.LeaderParams()
    sensor = formation.camera_sensor(lead, cam_pos_std, cam_yaw_std, cfg.camera_period, dt)
    est = leader_predictor(
        cfg.window, cfg.degree, cfg.camera_period,
        accel_psd=cfg.accel_psd if accel_psd is None else accel_psd,
        meas_std=cfg.meas_std if meas_std is None else meas_std, p0=cfg.p0,
        t_start=cfg.estimator_start if estimator_start is None else estimator_start, mode=mode)
    ctrl = auv_tracking(auv.nominal_params(), cfg.lam if lam is None else lam, cfg.k_s if k_s is None else k_s,
                        cfg.switch if switch is None else switch, cfg.width if width is None else width,
                        cfg.t_follower_start)
    return ClosedLoop(auv.auv_plant(plant), ctrl, sensor=sensor, estimator=est, actuate=add_input_disturbance)


def true_plant(cfg: Config) -> auv.AUVParams:
    return auv.true_params(cfg.deviation_sign)


# ---------------------------------------------------------------------------------------------
# per-tick quantities and folded metrics


def tick_errors(x: jax.Array, t: jax.Array) -> tuple[jax.Array, jax.Array]:
    """True target point relative to the follower in FR ``(3,)`` and its time derivative ``(3,)``."""
    lead = formation.LeaderParams()
    eta_dot = marine.kinematics_jacobian(x[:6]) @ x[6:]
    x_dot = jnp.concatenate([eta_dot, jnp.zeros(6)])
    return jax.jvp(lambda s, z: formation.level_frame_error(formation.target_point(lead, s), z),
                   (t, x), (jnp.ones_like(t), x_dot))


def _window(t: jax.Array, lo: float, hi: float) -> jax.Array:
    return (t >= lo - 1e-9) & (t < hi - 1e-9)


def metric_fold(cfg: Config, t_final: float, loss_start: float | None = None):
    """``(fn, acc0, finish)`` for :func:`jaxsim.core.rollout.fold` over the formation metrics."""
    ts = cfg.dt
    start = cfg.t_follower_start
    ss_lo, ss_hi = cfg.ss_window
    t32_lo, t32_hi = cfg.t32_window
    loss_start = start if loss_start is None else loss_start
    inf = jnp.inf

    acc0 = {
        "err0": jnp.zeros(()), "first_below": jnp.asarray(inf), "last_above": jnp.asarray(-inf),
        "ss_abs": jnp.zeros(3), "ss_norm": jnp.zeros(()), "ss_rel_vel": jnp.zeros(()),
        "t32_peak": jnp.zeros(()), "rel_vel_x_min": jnp.asarray(inf),
        "est_startup_max": jnp.zeros(()), "est_last_above": jnp.asarray(-inf),
        "t32_est_peak": jnp.zeros(()), "t32_est_last_above": jnp.asarray(t32_lo),
        "sq_err": jnp.zeros(()), "effort": jnp.zeros(()), "loss_time": jnp.zeros(()),
    }

    def fn(a: dict, tick: Any) -> dict:
        t = tick.t
        e, e_dot = tick_errors(tick.x, t)
        n = jnp.linalg.norm(e)
        est = jnp.linalg.norm(tick.x_hat.position - formation.target_point(formation.LeaderParams(), t))
        on = t >= start - 1e-9
        ss = _window(t, ss_lo, ss_hi)
        w32 = _window(t, t32_lo, t32_hi)
        before32 = t < t32_lo - 1e-9
        in_loss = t >= loss_start - 1e-9
        return {
            "err0": jnp.where(jnp.abs(t - start) < 0.5 * ts, n, a["err0"]),
            "first_below": jnp.where(on & (n <= THRESHOLD_M), jnp.minimum(a["first_below"], t), a["first_below"]),
            "last_above": jnp.where(on & (n > THRESHOLD_M), t, a["last_above"]),
            "ss_abs": jnp.where(ss, jnp.maximum(a["ss_abs"], jnp.abs(e)), a["ss_abs"]),
            "ss_norm": jnp.where(ss, jnp.maximum(a["ss_norm"], n), a["ss_norm"]),
            "ss_rel_vel": jnp.where(ss, jnp.maximum(a["ss_rel_vel"], jnp.abs(e_dot[0])), a["ss_rel_vel"]),
            "t32_peak": jnp.where(w32, jnp.maximum(a["t32_peak"], n), a["t32_peak"]),
            "rel_vel_x_min": jnp.where(on & before32, jnp.minimum(a["rel_vel_x_min"], e_dot[0]), a["rel_vel_x_min"]),
            "est_startup_max": jnp.where(on & before32, jnp.maximum(a["est_startup_max"], est), a["est_startup_max"]),
            "est_last_above": jnp.where(before32 & (est > 0.02), t, a["est_last_above"]),
            "t32_est_peak": jnp.where(w32, jnp.maximum(a["t32_est_peak"], est), a["t32_est_peak"]),
            "t32_est_last_above": jnp.where(w32 & (est > 0.02), t, a["t32_est_last_above"]),
            "sq_err": a["sq_err"] + jnp.where(in_loss, n**2, 0.0),
            "effort": a["effort"] + jnp.where(in_loss, jnp.sum((tick.u / 100.0) ** 2), 0.0),
            "loss_time": a["loss_time"] + jnp.where(in_loss, 1.0, 0.0),
        }

    def finish(a: dict) -> dict:
        steps = jnp.maximum(a["loss_time"], 1.0)
        return {
            "err0_m": a["err0"],
            "t_to_0p2m_s": a["first_below"],
            "t_last_above_0p2m_s": a["last_above"] + ts,
            "ss_err_x_m": a["ss_abs"][0], "ss_err_y_m": a["ss_abs"][1], "ss_err_z_m": a["ss_abs"][2],
            "ss_err_m": a["ss_norm"],
            "ss_rel_vel_x_mps": a["ss_rel_vel"],
            "t32_peak_err_m": a["t32_peak"],
            "rel_vel_x_min_mps": a["rel_vel_x_min"],
            "startup_est_err_max_m": a["est_startup_max"],
            "startup_est_settled_s": a["est_last_above"] + ts - start,
            "t32_est_err_peak_m": a["t32_est_peak"],
            "t32_est_recovery_s": a["t32_est_last_above"] + ts - t32_lo,
            "mean_sq_err_m2": a["sq_err"] / steps,
            "mean_effort": a["effort"] / steps,
        }

    return fn, acc0, finish


def run_metrics(cfg: Config, loop: ClosedLoop, key: jax.Array, *, dt: float | None = None,
                t_final: float | None = None, loss_start: float | None = None) -> dict:
    """The formation metrics of one rollout (pure: jit/vmap/grad it from outside)."""
    dt = cfg.dt if dt is None else dt
    t_final = cfg.t_final if t_final is None else t_final
    fn, acc0, finish = metric_fold(dataclasses.replace(cfg, dt=dt), t_final, loss_start)
    acc, _ = fold(loop, initial_state(), timing(dt, t_final), fn, acc0, key=key)
    return finish(acc)


# ---------------------------------------------------------------------------------------------
# Monte Carlo


def deviation_space(cfg: Config) -> dict:
    """Deviations uniform within ±Δ (the paper's bounds (3)) around the nominal plant."""
    dev = auv.PAPER_DEVIATION
    return {"dm": mc.deviation(np.zeros(6), np.asarray(dev.mass)),
            "dd1": mc.deviation(np.zeros(6), np.asarray(dev.d1)),
            "dd2": mc.deviation(np.zeros(6), np.asarray(dev.d2))}


def plant_of(draw: dict) -> auv.AUVParams:
    return auv.perturb(auv.nominal_params(), auv.AUVDeviation(draw["dm"], draw["dd1"], draw["dd2"]))


def mc_metric(cfg: Config, mode: str) -> Callable[[jax.Array, dict], dict]:
    yaw_std = math.radians(cfg.cam_yaw_std_deg)

    def metric(key: jax.Array, draw: dict) -> dict:
        loop = build_loop(cfg, plant_of(draw), mode=mode, cam_pos_std=cfg.cam_pos_std, cam_yaw_std=yaw_std)
        m = run_metrics(cfg, loop, key)
        keep = ("t_to_0p2m_s", "ss_err_m", "ss_err_x_m", "ss_err_y_m", "ss_err_z_m", "t32_peak_err_m",
                "rel_vel_x_min_mps")
        out = {k: m[k] for k in keep}
        out["reached_0p2m"] = jnp.isfinite(m["t_to_0p2m_s"])
        return out

    return metric


# ---------------------------------------------------------------------------------------------
# tuning


def tuning_reparam() -> dict:
    return {"lam": Interval(0.05, 1.5), "k_s": Interval(10.0, 300.0),
            "log10_accel_psd": Interval(-6.0, 1.0), "log10_meas_std": Interval(-4.0, -0.5)}


def paper_tuning_params(cfg: Config) -> dict:
    return {"lam": jnp.asarray(cfg.lam, dtype=float), "k_s": jnp.asarray(cfg.k_s, dtype=float),
            "log10_accel_psd": jnp.asarray(math.log10(cfg.accel_psd)),
            "log10_meas_std": jnp.asarray(math.log10(cfg.meas_std))}


def tuning_loss_fn(cfg: Config) -> Callable[[dict, dict], jax.Array]:
    """``loss(theta, sample)``: mean ‖e‖² + ρ mean (τ/100)² on one deviation/noise draw."""
    yaw_std = math.radians(cfg.cam_yaw_std_deg)

    def loss(theta: dict, sample: dict) -> jax.Array:
        loop = build_loop(cfg, plant_of(sample), dt=cfg.tune_dt, lam=theta["lam"], k_s=theta["k_s"],
                          switch="tanh", width=cfg.tune_width, accel_psd=10.0 ** theta["log10_accel_psd"],
                          meas_std=10.0 ** theta["log10_meas_std"], cam_pos_std=cfg.cam_pos_std,
                          cam_yaw_std=yaw_std)
        m = run_metrics(cfg, loop, sample["key"], dt=cfg.tune_dt, t_final=cfg.tune_t_final,
                        loss_start=cfg.tune_loss_start)
        return m["mean_sq_err_m2"] + cfg.effort_weight * m["mean_effort"]

    return loss


def draw_samples(cfg: Config, n: int, seed: int) -> dict:
    """``n`` deviation draws (uniform within ±Δ) with their camera-noise keys."""
    space = deviation_space(cfg)
    keys = jax.random.split(jax.random.PRNGKey(seed), n)
    draws = jax.vmap(lambda k: mc.draw(space, jax.random.fold_in(k, 0)))(keys)
    return {**draws, "key": jax.vmap(lambda k: jax.random.fold_in(k, 1))(keys)}


# ---------------------------------------------------------------------------------------------
# figures


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


def _fig_mc(results: dict) -> Any:
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8))
    q = np.linspace(0.01, 0.99, 99)
    for label, res in results.items():
        for ax, name in zip(axes, ("ss_err_m", "t_to_0p2m_s")):
            ax.plot(np.asarray(res[name].quantile(q)), q, label=label)
            ax.set(xlabel=name, ylabel="cumulative probability")
    axes[0].set_xscale("log")
    axes[0].legend()
    fig.suptitle("Monte Carlo over deviations (uniform ±Δ) and camera noise")
    fig.tight_layout()
    return fig


def _fig_tuning(history: Any) -> Any:
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5, 3.4))
    ax.plot(np.asarray(history.loss), label="current")
    ax.plot(np.asarray(history.best_loss), label="best")
    ax.set(xlabel="Adam step", ylabel="CVaR loss", yscale="log", title="gradient tuning of Λ, K_s, Q, R")
    ax.legend()
    fig.tight_layout()
    return fig


# ---------------------------------------------------------------------------------------------
# the study


def _floats(d: dict) -> dict:
    return {k: float(v) for k, v in d.items()}


def reproduction(cfg: Config, progress: Callable[..., Any]) -> tuple[dict, list, list, Any]:
    """Part 1: the paper's study 1 (exact pose) with and without prediction, and start-up variants."""
    plant = true_plant(cfg)
    key = jax.random.PRNGKey(cfg.seed)
    metrics_of = jax.jit(lambda loop: run_metrics(cfg, loop, key))
    rows = []
    bar = progress(total=4, desc="reproduction", unit="run")
    by_mode = {}
    for mode in ("kalman", "polynomial", "hold"):
        m = _floats(metrics_of(build_loop(cfg, plant, mode=mode)))
        by_mode[mode] = m
        rows.append({"prediction": mode, **m})
        bar.update(1)
    late = _floats(metrics_of(build_loop(cfg, plant, estimator_start=cfg.t_follower_start)))
    bar.update(1)
    bar.close()
    startup = [{"estimator_start_s": cfg.estimator_start, **{k: by_mode["kalman"][k] for k in late}},
               {"estimator_start_s": cfg.t_follower_start, **late}]
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
            rows.append({"t_from_s": lo, "t_to_s": hi, "max_abs_x_m": mx[0], "max_abs_y_m": mx[1],
                         "max_abs_z_m": mx[2], "within_paper_bands": bool(mx[0] <= 0.02 and mx[1] <= 0.002
                                                                           and mx[2] <= 0.01)})
    return rows


def monte_carlo_part(cfg: Config, progress: Callable[..., Any]) -> dict:
    runs = 4 if cfg.quick else cfg.mc_runs
    space = deviation_space(cfg)
    out = {}
    for label, mode in (("with_prediction", "kalman"), ("without_prediction", "hold")):
        out[label] = mc.monte_carlo(mc_metric(cfg, mode), space, runs, cfg.seed, block_size=min(runs, 32),
                                    progress=progress)
    return out


def tuning_part(cfg: Config, progress: Callable[..., Any]) -> tuple[dict, list, Any]:
    n_train = 2 if cfg.quick else cfg.tune_samples
    n_hold = 2 if cfg.quick else cfg.tune_holdout
    steps = 2 if cfg.quick else cfg.tune_steps
    loss_fn = tuning_loss_fn(cfg)
    reducer = lambda losses: cvar(losses, cfg.cvar_alpha)  # noqa: E731
    train = robust_loss(loss_fn, draw_samples(cfg, n_train, cfg.seed + 1), reducer)
    held = jax.jit(robust_loss(loss_fn, draw_samples(cfg, n_hold, cfg.seed + 2), reducer))
    theta0 = paper_tuning_params(cfg)
    bar = progress(total=steps, desc="tuning", unit="step")
    res = tune(train, theta0, optimizer=optax.adam(cfg.tune_lr), steps=steps, reparam=tuning_reparam(),
               callback=lambda *_: bar.update(1) and None, sims_per_eval=n_train,
               mode="reverse")  # 14 parameters over a 23k-step scan: one backward pass is cheaper
    bar.close()
    tuned = res.params
    exact = {}
    key = jax.random.PRNGKey(cfg.seed)
    metrics_of = jax.jit(lambda loop: run_metrics(cfg, loop, key))
    for label, th in (("paper", theta0), ("tuned", tuned)):
        loop = build_loop(cfg, true_plant(cfg), lam=th["lam"], k_s=th["k_s"],
                          accel_psd=10.0 ** th["log10_accel_psd"], meas_std=10.0 ** th["log10_meas_std"])
        exact[label] = {"train_cvar": float(train(th)) if label == "paper" else float(res.loss),
                        "holdout_cvar": float(held(th)), **_floats(metrics_of(loop))}
    rows = []
    for label, th in (("paper", theta0), ("tuned", tuned)):
        row = {"gains": label, **{f"lam_{i}": float(v) for i, v in enumerate(np.asarray(th["lam"]))},
               **{f"k_s_{i}": float(v) for i, v in enumerate(np.asarray(th["k_s"]))},
               "accel_psd": float(10.0 ** th["log10_accel_psd"]), "meas_std": float(10.0 ** th["log10_meas_std"]),
               **exact[label]}
        rows.append(row)
    info = {"steps": int(res.n_steps), "sims": int(res.n_sims), "wall_s": float(res.wall_s),
            "compile_s": float(res.compile_s), "message": res.message}
    return exact, rows, (res.history, info)


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    if cfg.ss_window[1] > cfg.t_final + 1e-9:
        raise ValueError(f"ss_window: must end by t_final={cfg.t_final}, got {cfg.ss_window}")
    nominal, rows, startup, tr = reproduction(cfg, progress)
    bands = error_bands(tr, cfg)
    mc_res = monte_carlo_part(cfg, progress)
    exact, tune_rows, (history, info) = tuning_part(cfg, progress)

    k = nominal["kalman"]
    wp, wo = mc_res["with_prediction"], mc_res["without_prediction"]
    metrics = {
        "err0_m": k["err0_m"], "t_to_0p2m_s": k["t_to_0p2m_s"],
        "ss_err_x_m": k["ss_err_x_m"], "ss_err_y_m": k["ss_err_y_m"], "ss_err_z_m": k["ss_err_z_m"],
        "mc_t_to_0p2m_p95_s": float(wp["t_to_0p2m_s"].quantile(0.95)),
        "mc_ss_err_p95_m_with_prediction": float(wp["ss_err_m"].quantile(0.95)),
        "mc_ss_err_p95_m_without_prediction": float(wo["ss_err_m"].quantile(0.95)),
        "t_last_above_0p2m_s": k["t_last_above_0p2m_s"], "t32_peak_err_m": k["t32_peak_err_m"],
        "rel_vel_x_min_mps": k["rel_vel_x_min_mps"], "ss_rel_vel_x_mps": k["ss_rel_vel_x_mps"],
        "startup_est_err_max_m": k["startup_est_err_max_m"], "startup_est_settled_s": k["startup_est_settled_s"],
        "t32_est_err_peak_m": k["t32_est_err_peak_m"], "t32_est_recovery_s": k["t32_est_recovery_s"],
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
        "tuned_t_to_0p2m_s": exact["tuned"]["t_to_0p2m_s"], "tuned_ss_err_m": exact["tuned"]["ss_err_m"],
        "tuned_t32_peak_err_m": exact["tuned"]["t32_peak_err_m"],
        "tune_steps": info["steps"], "tune_wall_s": info["wall_s"],
    }
    mc_rows = [{"prediction": label, **res.row()} for label, res in mc_res.items()]
    figures = {"reproduction": _fig_reproduction(tr, cfg), "monte_carlo": _fig_mc(mc_res),
               "tuning": _fig_tuning(history)}
    notes = [
        f"reproduction: RK4 at dt = {cfg.dt} s over {cfg.t_final} s, exact leader pose, exact sign; "
        f"paper: 7.8 m → 0.2 m by 28 s, ss bands x 0.02 / y 0.002 / z 0.01 m, relative velocity +1.2 → −1.1 m/s",
        f"Monte Carlo: {int(wp.runs)} runs per mode, deviations uniform ±Δ, camera pose noise "
        f"{cfg.cam_pos_std} m / {cfg.cam_yaw_std_deg}°; same draws for both modes (common random numbers)",
        f"tuning: {info['message']}; {info['sims']} simulations in {info['wall_s']:.1f} s "
        f"(+{info['compile_s']:.1f} s compile), dt = {cfg.tune_dt} s, tanh width {cfg.tune_width} m/s; "
        "the 'paper'/'tuned' rows of table tuning re-run both with the exact sign at dt = 1 ms",
    ]
    return StudyResult(
        metrics=metrics,
        tables={"reproduction": rows, "startup_variants": startup, "error_bands": bands,
                "monte_carlo": mc_rows, "tuning": tune_rows},
        assumptions=ASSUMPTIONS, figures=figures, notes=notes,
    )


STUDY = Study(
    name="auv_formation",
    description="Leader–follower AUV formation from a 10 Hz camera: LS + Kalman leader prediction, "
                "computed torque + sliding mode; reproduction, Monte Carlo, CVaR gradient tuning (seed 002)",
    config_cls=Config,
    run=run,
)
