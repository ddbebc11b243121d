"""The leader–follower AUV formation problem of the ``auv_formation`` study (seed 002): loop, metrics,
deviation space and the tuning problem.

The follower (fully actuated 6-DOF Fossen AUV, :mod:`jaxsim.plants.auv`, true parameters = nominal
+ the paper's deviations) keeps the target point ``X_L* = [−1.5, −6]`` m beside the leader, which
flies the paper's straight-then-curved trajectory (:mod:`jaxsim.plants.formation`).  It sees the
leader only through a 10 Hz camera; a sliding-window quartic fit over 51 frames plus a Kalman filter
predicting every 1 ms (:mod:`jaxsim.estimation.leader_predictor`) gives the target point between
frames, and a computed-torque + variable-structure controller (:mod:`jaxsim.control.auv_tracking`)
drives the follower.  All rollouts are one ``fold`` of :mod:`jaxsim.core.rollout`.

Error definitions: ``e = R_z(ψ_F)ᵀ (X*_true − p_F)``, the true target point relative to the follower
in its level frame FR.  ``t_to_0p2m_s``: first time after the start at which ``‖e‖ ≤ 0.2 m``.
Steady-state errors: ``max |e_x|, |e_y|, |e_z|`` over ``ss_window``.  Units: m, s, N.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.control.auv_tracking import PAPER_KS, PAPER_LAMBDA, auv_tracking
from jaxsim.core.rollout import ClosedLoop, Timing, fold
from jaxsim.core.system import add_input_disturbance
from jaxsim.estimation.leader_predictor import leader_predictor
from jaxsim.montecarlo.distributions import deviation, draw
from jaxsim.plants import auv, formation, marine
from jaxsim.problem.problem import Problem
from jaxsim.problem.reducers import cvar
from jaxsim.problem.space import Param, ParamSpace

THRESHOLD_M = 0.2


@dataclass(frozen=True)
class FormationSetup:
    """The paper's scenario and loop (study 1), the metric windows, camera noise and the tuning loss."""

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
    tune_dt: float = 2e-3  # s, step of the tuning rollouts
    tune_t_final: float = 46.0  # s
    tune_loss_start: float = 20.0  # s, the loss integrates from here (manoeuvre + steady state)
    tune_width: float = 0.05  # m/s, tanh temperature while tuning
    cvar_alpha: float = 0.75
    effort_weight: float = 1e-3  # ρ on mean (τ/100 N)² in the tuning loss


def timing(dt: float, t_final: float, save_every: int = 1) -> Timing:
    return Timing(t_final=t_final, dt=dt, controller_period=dt, save_every=save_every)


def initial_state() -> jax.Array:
    """Follower at (−1.5, −6, 1.2) m, at rest, aligned with the absolute frame (paper line 1106)."""
    return auv.initial_state([-1.5, -6.0, 1.2])


def build_loop(
    cfg: FormationSetup,
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
        cfg.window,
        cfg.degree,
        cfg.camera_period,
        accel_psd=cfg.accel_psd if accel_psd is None else accel_psd,
        meas_std=cfg.meas_std if meas_std is None else meas_std,
        p0=cfg.p0,
        t_start=cfg.estimator_start if estimator_start is None else estimator_start,
        mode=mode,
    )
    ctrl = auv_tracking(
        auv.nominal_params(),
        cfg.lam if lam is None else lam,
        cfg.k_s if k_s is None else k_s,
        cfg.switch if switch is None else switch,
        cfg.width if width is None else width,
        cfg.t_follower_start,
    )
    return ClosedLoop(auv.auv_plant(plant), ctrl, sensor=sensor, estimator=est, actuate=add_input_disturbance)


def true_plant(cfg: FormationSetup) -> auv.AUVParams:
    return auv.true_params(cfg.deviation_sign)


# ---------------------------------------------------------------------------------------------
# per-tick quantities and folded metrics


def tick_errors(x: jax.Array, t: jax.Array) -> tuple[jax.Array, jax.Array]:
    """True target point relative to the follower in FR ``(3,)`` and its time derivative ``(3,)``."""
    lead = formation.LeaderParams()
    eta_dot = marine.kinematics_jacobian(x[:6]) @ x[6:]
    x_dot = jnp.concatenate([eta_dot, jnp.zeros(6)])
    return jax.jvp(
        lambda s, z: formation.level_frame_error(formation.target_point(lead, s), z), (t, x), (jnp.ones_like(t), x_dot)
    )


def _window(t: jax.Array, lo: float, hi: float) -> jax.Array:
    return (t >= lo - 1e-9) & (t < hi - 1e-9)


def metric_fold(cfg: FormationSetup, t_final: float, loss_start: float | None = None):
    """``(fn, acc0, finish)`` for :func:`jaxsim.core.rollout.fold` over the formation metrics."""
    ts = cfg.dt
    start = cfg.t_follower_start
    ss_lo, ss_hi = cfg.ss_window
    t32_lo, t32_hi = cfg.t32_window
    loss_start = start if loss_start is None else loss_start
    inf = jnp.inf

    acc0 = {
        "err0": jnp.zeros(()),
        "first_below": jnp.asarray(inf),
        "last_above": jnp.asarray(-inf),
        "ss_abs": jnp.zeros(3),
        "ss_norm": jnp.zeros(()),
        "ss_rel_vel": jnp.zeros(()),
        "t32_peak": jnp.zeros(()),
        "rel_vel_x_min": jnp.asarray(inf),
        "est_startup_max": jnp.zeros(()),
        "est_last_above": jnp.asarray(-inf),
        "t32_est_peak": jnp.zeros(()),
        "t32_est_last_above": jnp.asarray(t32_lo),
        "sq_err": jnp.zeros(()),
        "effort": jnp.zeros(()),
        "loss_time": jnp.zeros(()),
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
            "ss_err_x_m": a["ss_abs"][0],
            "ss_err_y_m": a["ss_abs"][1],
            "ss_err_z_m": a["ss_abs"][2],
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


def run_metrics(
    cfg: FormationSetup,
    loop: ClosedLoop,
    key: jax.Array,
    *,
    dt: float | None = None,
    t_final: float | None = None,
    loss_start: float | None = None,
) -> dict:
    """The formation metrics of one rollout (pure: jit/vmap/grad it from outside)."""
    dt = cfg.dt if dt is None else dt
    t_final = cfg.t_final if t_final is None else t_final
    fn, acc0, finish = metric_fold(dataclasses.replace(cfg, dt=dt), t_final, loss_start)
    acc, _ = fold(loop, initial_state(), timing(dt, t_final), fn, acc0, key=key)
    return finish(acc)


# ---------------------------------------------------------------------------------------------
# Monte Carlo


def deviation_space(cfg: FormationSetup) -> dict:
    """Deviations uniform within ±Δ (the paper's bounds (3)) around the nominal plant."""
    dev = auv.PAPER_DEVIATION
    return {
        "dm": deviation(np.zeros(6), np.asarray(dev.mass)),
        "dd1": deviation(np.zeros(6), np.asarray(dev.d1)),
        "dd2": deviation(np.zeros(6), np.asarray(dev.d2)),
    }


def plant_of(draw: dict) -> auv.AUVParams:
    return auv.perturb(auv.nominal_params(), auv.AUVDeviation(draw["dm"], draw["dd1"], draw["dd2"]))


def mc_metric(cfg: FormationSetup, mode: str) -> Callable[[jax.Array, dict], dict]:
    yaw_std = math.radians(cfg.cam_yaw_std_deg)

    def metric(key: jax.Array, draw: dict) -> dict:
        loop = build_loop(cfg, plant_of(draw), mode=mode, cam_pos_std=cfg.cam_pos_std, cam_yaw_std=yaw_std)
        m = run_metrics(cfg, loop, key)
        keep = (
            "t_to_0p2m_s",
            "ss_err_m",
            "ss_err_x_m",
            "ss_err_y_m",
            "ss_err_z_m",
            "t32_peak_err_m",
            "rel_vel_x_min_mps",
        )
        out = {k: m[k] for k in keep}
        out["reached_0p2m"] = jnp.isfinite(m["t_to_0p2m_s"])
        return out

    return metric


def tuning_space(cfg: FormationSetup) -> ParamSpace:
    """``Λ`` (6,) in [0.05, 1.5], ``K_s`` (6,) in [10, 300], log10 of the Kalman ``accel_psd`` in [−6, 1]
    and of ``meas_std`` in [−4, −0.5]; from the configured (paper) values."""
    return ParamSpace(
        lam=Param(lo=0.05, hi=1.5, init=cfg.lam),
        k_s=Param(lo=10.0, hi=300.0, init=cfg.k_s),
        log10_accel_psd=Param(lo=-6.0, hi=1.0, init=math.log10(cfg.accel_psd)),
        log10_meas_std=Param(lo=-4.0, hi=-0.5, init=math.log10(cfg.meas_std)),
    )


def tuning_loss(cfg: FormationSetup, theta: dict, sample: dict, key: jax.Array) -> jax.Array:
    """Mean ‖e‖² + ρ mean (τ/100)² over ``[tune_loss_start, tune_t_final]`` on one deviation draw
    ``sample`` with camera noise ``key`` (smooth ``tanh`` switching, step ``tune_dt``)."""
    loop = build_loop(
        cfg,
        plant_of(sample),
        dt=cfg.tune_dt,
        lam=theta["lam"],
        k_s=theta["k_s"],
        switch="tanh",
        width=cfg.tune_width,
        accel_psd=10.0 ** theta["log10_accel_psd"],
        meas_std=10.0 ** theta["log10_meas_std"],
        cam_pos_std=cfg.cam_pos_std,
        cam_yaw_std=math.radians(cfg.cam_yaw_std_deg),
    )
    m = run_metrics(cfg, loop, key, dt=cfg.tune_dt, t_final=cfg.tune_t_final, loss_start=cfg.tune_loss_start)
    return m["mean_sq_err_m2"] + cfg.effort_weight * m["mean_effort"]


def draw_samples(cfg: FormationSetup, n: int, seed: int) -> dict:
    """``n`` deviation draws (uniform within ±Δ) with their camera-noise keys (``"key"``)."""
    space = deviation_space(cfg)
    keys = jax.random.split(jax.random.PRNGKey(seed), n)
    draws = jax.vmap(lambda k: draw(space, jax.random.fold_in(k, 0)))(keys)
    return {**draws, "key": jax.vmap(lambda k: jax.random.fold_in(k, 1))(keys)}


def tuning_problem(cfg: FormationSetup, n: int, seed: int) -> Problem:
    """CVaR at ``cvar_alpha`` of :func:`tuning_loss` over ``n`` fixed draws (:func:`draw_samples`)."""
    return Problem.from_loss(
        "auv_formation",
        tuning_space(cfg),
        lambda p, d, k: tuning_loss(cfg, p, d, k),
        scenarios=draw_samples(cfg, n, seed),
        reduce=lambda v: cvar(v, cfg.cvar_alpha),
    )
