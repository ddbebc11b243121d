"""Study ``orientation_system_accuracy``: accuracy of a MEMS attitude system (gyro, accelerometer and
magnetometer triads plus air data) before and after calibration and fusion (Luchkina, seed 004 part 3
§2.5, Tables 1 and 2).

Models (:mod:`jaxsim.inertial.ahrs`): the sensor errors of the paper's Table 1 (bias, scale factor,
temperature term, white noise, first-order Gauss–Markov gyro noise with τ = 300 s), an assumed flight
segment with a longitudinal (pitch up and back) and a lateral (coordinated turn) manoeuvre, and a
22-state multiplicative EKF (gyro bias and its coloured part, accelerometer and magnetometer biases and
scale factors, airspeed error)
with the air-data correction of the linear acceleration and correction limiting during manoeuvres.
The study:

1. checks the kernels against independent references: the Gauss–Markov generator's variance and
   autocorrelation against ``σ² e^{−|Δt|/τ}``, the quaternion attitude update on noise-free gyro
   data against the closed-form (autodiff) attitude of the flight profile, with its error order from a
   halved step;
2. "before" (Table 2, left): raw gyro integration (drift, °/h) and raw accelerometer tilt and
   magnetometer heading (σ over the flight), all with Table 1's errors;
3. "after" (Table 2, right): gyro temperature compensation and magnetometer calibration (stand-ins
   with assumed residuals for the paper's least squares and modified TAMCAL, which are not given),
   then the MEKF; per run the bias (mean error) and σ (std over the flight after a settling time),
   Monte-Carlo means with 95 % intervals, and the attitude NEES against χ² bounds.

The paper's numbers come from one simulation of an unknown trajectory with unknown gains: they are
compared within bands (σ within a factor, the paper's bias as a plausible draw of our per-run biases).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np
import optax

from experiments import figures, stages
from experiments.runner import Study, StudyResult, paper_facts
from jaxsim.core.rotations import quat_mul, quat_rotation_vector
from jaxsim.estimation.gating import chi2_bounds
from jaxsim.inertial import ahrs
from jaxsim.inertial.attitude import propagate
from jaxsim.problem import Param, ParamSpace, Problem

CLAIMS, ASSUMPTIONS = paper_facts("orientation_system_accuracy")
DEG = math.pi / 180.0
ANGLES = ("roll", "pitch", "heading")  # Euler order [φ, θ, ψ]


@dataclass(frozen=True)
class Config:
    duration: float = 600.0  # s, flight segment [assumed]
    dt: float = 0.02  # s, 50 Hz sensors and filter [assumed]
    speed: float = 50.0  # m/s [assumed]
    pitch_amp_deg: float = 10.0  # longitudinal manoeuvre [assumed]
    turn_angle_deg: float = 360.0  # lateral manoeuvre: coordinated turn [assumed]
    turn_duration: float = 0.2  # fraction of the flight (max bank ≈ 27° at the defaults)
    temp_drop: float = 10.0  # °C over the flight [assumed]
    settle: float = 60.0  # s excluded from the "after" statistics (filter convergence)
    drift_window: float = 120.0  # s: the raw gyro drift is the slope over the first drift_window s
    n_runs: int = 32
    mag_residual_bias: float = 0.2  # µT σ after the magnetometer calibration [assumed]
    mag_residual_scale: float = 0.005  # σ after the magnetometer calibration [assumed]
    temp_coeff_residual: float = 0.1  # relative σ of the LS temperature coefficient [assumed]
    accel_sigma: float = 0.05  # m/s², MEKF accelerometer σ [assumed]
    mag_sigma: float = 0.5  # µT, MEKF magnetometer σ [assumed]
    accel_gate: float = 0.5  # m/s², correction limiting [assumed]
    correction_rate: float = 25.0  # Hz, accelerometer/magnetometer corrections of the MEKF [assumed]
    attitude0_deg: float = 2.0  # initial attitude error σ [assumed]
    cf_crossover: float = 0.05  # rad/s, complementary filter, tilt and heading loops [assumed]
    cf_ki_ratio: float = 0.25  # bias integral k_i = ratio·ω_c² [assumed]
    tune_runs: int = 4  # flights in the tuning batch (independent of the Monte-Carlo flights)
    tune_steps: int = 15  # Adam steps on (log ω_c, log k_i ratio)
    tune_learning_rate: float = 0.2
    nees_every: int = 50  # NEES sampled every this many steps
    gm_sequences: int = 256  # Gauss–Markov identity check: sequences ...
    gm_length: int = 3000  # ... of this many 1-s samples
    seed: int = 0


PRESETS = {
    "quick": dict(duration=300.0, n_runs=12, settle=40.0, gm_sequences=128, tune_runs=3, tune_steps=10),
    "tiny": dict(
        duration=60.0,
        dt=0.05,
        n_runs=3,
        settle=15.0,
        turn_angle_deg=90.0,
        turn_duration=0.4,
        gm_sequences=128,
        nees_every=20,
        tune_runs=1,
        tune_steps=2,
    ),
}


def flight_of(cfg: Config) -> ahrs.Flight:
    return ahrs.Flight(
        speed=cfg.speed,
        pitch_amp=cfg.pitch_amp_deg * DEG,
        turn_angle=cfg.turn_angle_deg * DEG,
        turn_duration=cfg.turn_duration,
        temp_drop=cfg.temp_drop,
        duration=cfg.duration,
    )


def tuning_of(cfg: Config) -> ahrs.MekfTuning:
    e = ahrs.AhrsErrors()
    return ahrs.MekfTuning(
        gyro_white=e.gyro_white,
        gyro_bias=e.gyro_bias,
        gm_sigma=e.gyro_gm_sigma,
        gm_tau=e.gyro_gm_tau,
        accel_bias=e.accel_bias,
        mag_bias=cfg.mag_residual_bias,
        accel_scale=e.accel_scale,
        mag_scale=cfg.mag_residual_scale,
        accel_sigma=cfg.accel_sigma,
        mag_sigma=cfg.mag_sigma,
        attitude0=cfg.attitude0_deg * DEG,
        accel_gate=cfg.accel_gate,
    )


def truth(cfg: Config, dt: float) -> tuple[jax.Array, dict[str, jax.Array], dict[str, jax.Array]]:
    """Times ``(n+1,)``, the truth on the grid and at the step midpoints (the gyro's rate over a step)."""
    n = int(round(cfg.duration / dt))
    t = jnp.arange(n + 1) * dt
    fl = flight_of(cfg)
    return t, ahrs.flight_truth(fl, t), ahrs.flight_truth(fl, t[:-1] + 0.5 * dt)


def _slope(t: jax.Array, e: jax.Array, w: jax.Array | None = None) -> jax.Array:
    """Weighted least-squares slope of ``e (n, 3)`` against ``t (n,)`` (weights ``w (n,)``, default 1)."""
    w = jnp.ones_like(t) if w is None else w
    w = w / jnp.sum(w)
    tc = t - jnp.sum(w * t)
    ec = e - jnp.sum(w[:, None] * e, axis=0)
    return jnp.sum((w * tc)[:, None] * ec, axis=0) / jnp.sum(w * tc * tc)


def _unwrap(e: jax.Array) -> jax.Array:
    d = jnp.diff(e, axis=0)
    d = jnp.arctan2(jnp.sin(d), jnp.cos(d))
    return jnp.concatenate([e[:1], e[:1] + jnp.cumsum(d, axis=0)])


def cf_gains(cfg: Config, crossover: Any, ki_ratio: Any) -> ahrs.ComplementaryGains:
    return ahrs.ComplementaryGains(
        tilt_crossover=crossover, heading_crossover=crossover, ki_ratio=ki_ratio, accel_gate=cfg.accel_gate
    )


def cf_loss(cfg: Config, data: dict[str, jax.Array], crossover: Any, ki_ratio: Any) -> jax.Array:
    """Mean over runs and kept times of the squared Euler-angle errors (deg²) of the complementary
    filter on calibrated flight data ``data`` (a batch from :func:`flight_inputs`)."""

    def one(d):
        cf = ahrs.complementary_run(
            cf_gains(cfg, crossover, ki_ratio), d["q0"], d["gyro"], d["accel"], d["mag"], d["airspeed"], cfg.dt
        )
        e = ahrs.euler_error(jax.vmap(ahrs.euler_from_quat)(cf.q), d["euler"]) / DEG
        keep = d["t"] >= cfg.settle
        return jnp.sum(keep[:, None] * e**2) / jnp.sum(keep)

    return jnp.mean(jax.vmap(one)(data))


@functools.partial(jax.jit, static_argnums=0)
def flight_inputs(cfg: Config, key: jax.Array) -> dict[str, jax.Array]:
    """The calibrated signals of one flight (inputs of both filters) and its true attitude."""
    return _flight(cfg, key)["inputs"]


def _flight(cfg: Config, key: jax.Array) -> dict[str, Any]:
    dt = cfg.dt
    t, tr, mid = truth(cfg, dt)
    errors = ahrs.AhrsErrors()
    m_ned = ahrs.earth_field()
    k_c, k_s, k_0, k_cal = jax.random.split(key, 4)
    consts = ahrs.draw_constants(k_c, errors)
    grid = {k: v[1:] for k, v in tr.items()}  # samples at t_1 … t_n
    sensed = {**grid, "omega": mid["omega"], "temp": mid["temp"]}
    meas = ahrs.corrupt(k_s, errors, consts, sensed, m_ned, dt)
    e_true = tr["euler"][1:]
    q_true0 = ahrs.quat_from_euler(tr["euler"][0])
    tt = t[1:]

    # calibrations (assumed residuals)
    kb, ks, kk = jax.random.split(k_cal, 3)
    # the calibration's output: (m − b̂)/(1 + ŝ) = (1 + δs) m_b + δb + noise, with the assumed residuals
    # drawn directly (drawing b̂, ŝ around the 30 %-scale truth would divide by 1 + ŝ ≈ 0 in rare runs)
    d_b = cfg.mag_residual_bias * jax.random.normal(kb, (3,))
    d_s = cfg.mag_residual_scale * jax.random.normal(ks, (3,))
    mag_cal = (meas["mag"] - consts.mag_bias) / (1.0 + consts.mag_scale) * (1.0 + d_s) + d_b
    k_hat = consts.gyro_temp_coeff * (1.0 + cfg.temp_coeff_residual * jax.random.normal(kk, (3,)))
    tau_t = 30.0  # s, low-pass of the indicated temperature

    def lp(y, x):
        y = y + (dt / tau_t) * (x - y)
        return y, y

    temp_f = jax.lax.scan(lp, meas["temp"][0], meas["temp"])[1]
    gyro_cal = meas["gyro"] - k_hat * (temp_f - temp_f[0])[:, None]
    tun = tuning_of(cfg)
    q0 = quat_mul(q_true0, ahrs.quat_exp(tun.attitude0 * jax.random.normal(k_0, (3,))))
    inputs = {
        "q0": q0,
        "gyro": gyro_cal,
        "accel": meas["accel"],
        "mag": mag_cal,
        "airspeed": meas["airspeed"],
        "euler": e_true,
        "t": tt,
    }
    return {"inputs": inputs, "meas": meas, "consts": consts, "q_true0": q_true0}


@functools.partial(jax.jit, static_argnums=0)
def one_run(cfg: Config, key: jax.Array, cf_crossover: Any, cf_ki_ratio: Any) -> dict[str, jax.Array]:
    """One Monte-Carlo flight: before/after statistics per angle (rad) and the sampled attitude NEES."""
    dt = cfg.dt
    fl = _flight(cfg, key)
    meas, consts, q_true0, inp = fl["meas"], fl["consts"], fl["q_true0"], fl["inputs"]
    e_true, tt, q0, gyro_cal, mag_cal = inp["euler"], inp["t"], inp["q0"], inp["gyro"], inp["mag"]
    m_ned = ahrs.earth_field()
    tun = tuning_of(cfg)
    # before: raw gyro integration from the true initial attitude; raw accelerometer tilt and
    # magnetometer heading (no calibration, no acceleration correction)
    q_raw = propagate(q_true0, meas["gyro"] * dt)
    e_raw = _unwrap(ahrs.euler_error(jax.vmap(ahrs.euler_from_quat)(q_raw), e_true))
    tilt = ahrs.accel_tilt(meas["accel"])
    heading = ahrs.mag_heading(meas["mag"], tilt[:, 0], tilt[:, 1])
    e_pos = ahrs.euler_error(jnp.concatenate([tilt, heading[:, None]], axis=1), e_true)

    # after: the MEKF
    every = max(1, int(round(1.0 / (cfg.correction_rate * dt))))
    res = ahrs.mekf_run(tun, q0, gyro_cal, meas["accel"], mag_cal, meas["airspeed"], m_ned, dt, update_every=every)
    e_est = ahrs.euler_error(jax.vmap(ahrs.euler_from_quat)(res.q), e_true)
    keep = tt >= cfg.settle
    w = keep / jnp.sum(keep)
    mean = jnp.sum(w[:, None] * e_est, axis=0)
    std = jnp.sqrt(jnp.sum(w[:, None] * (e_est - mean) ** 2, axis=0))
    # the complementary filter on the same calibrated signals
    cf = ahrs.complementary_run(
        cf_gains(cfg, cf_crossover, cf_ki_ratio), q0, gyro_cal, meas["accel"], mag_cal, meas["airspeed"], dt
    )
    e_cf = ahrs.euler_error(jax.vmap(ahrs.euler_from_quat)(cf.q), e_true)
    mean_cf = jnp.sum(w[:, None] * e_cf, axis=0)
    std_cf = jnp.sqrt(jnp.sum(w[:, None] * (e_cf - mean_cf) ** 2, axis=0))
    q_true = jax.vmap(ahrs.quat_from_euler)(e_true)
    idx = jnp.arange(cfg.nees_every - 1, tt.shape[0], cfg.nees_every)
    dth = quat_rotation_vector(quat_mul(res.q[idx] * jnp.array([1.0, -1.0, -1.0, -1.0]), q_true[idx]))  # R = R̂ exp(δθ)
    nees = jnp.einsum("ni,nij,nj->n", dth, jnp.linalg.inv(res.P_att[idx]), dth)
    return {
        # while the raw errors are small (Euler-angle errors of tens of degrees mix the axes)
        "drift_before": _slope(tt, e_raw, (tt <= cfg.drift_window).astype(tt.dtype)),
        "sigma_before": jnp.std(e_pos, axis=0),
        "bias_after": mean,
        "sigma_after": std,
        "drift_after": _slope(tt, e_est, w),
        "bias_cf": mean_cf,
        "sigma_cf": std_cf,
        "nees": nees,
        "nees_t": tt[idx],
        "accel_accepted": res.accel_accepted,
        "e_after": e_est[:: cfg.nees_every],
        "e_before_pos": e_pos[:: cfg.nees_every],
        "e_before_gyro": e_raw[:: cfg.nees_every],
        "t_series": tt[:: cfg.nees_every],
        "gyro_bias_true": consts.gyro_bias,
    }


# --- kernel checks --------------------------------------------------------------------------------


def gm_identity(cfg: Config) -> tuple[dict[str, float], list[dict[str, Any]]]:
    """Sample variance and autocorrelation of the Gauss–Markov generator against the closed form."""
    e = ahrs.AhrsErrors()
    sigma, tau = float(e.gyro_gm_sigma), float(e.gyro_gm_tau)
    keys = jax.random.split(jax.random.PRNGKey(cfg.seed + 101), cfg.gm_sequences)
    x = np.asarray(jax.vmap(lambda k: ahrs.gauss_markov(k, sigma, tau, 1.0, cfg.gm_length, dim=1)[:, 0])(keys))
    rows = []
    metrics: dict[str, float] = {}
    for lag in (0, 60, 150, 300, 600):
        if lag >= cfg.gm_length:
            continue
        per_seq = np.mean(x[:, : cfg.gm_length - lag] * x[:, lag:], axis=1)  # one estimate per sequence
        est = float(np.mean(per_seq))
        half = 1.96 * float(np.std(per_seq, ddof=1)) / math.sqrt(len(per_seq))
        closed = float(ahrs.gauss_markov_autocovariance(lag, sigma, tau))
        rows.append(
            {
                "lag_s": lag,
                "autocov_sample": est,
                "ci_low": est - half,
                "ci_high": est + half,
                "autocov_closed_form": closed,
            }
        )
        if lag == 0:
            metrics |= {"gm_variance_ratio": est / closed, "gm_variance_ratio_ci_half": half / closed}
        if lag == 300:
            metrics |= {"gm_autocorr_at_tau_ratio": est / closed, "gm_autocorr_at_tau_ci_half": half / closed}
    return metrics, rows


@functools.partial(jax.jit, static_argnums=(0, 1))
def _attitude_update_error(cfg: Config, dt: float) -> jax.Array:
    """Largest Euler-angle error (rad) of noise-free gyro integration at step ``dt`` (jitted: run
    eagerly, its few hundred small operations were each compiled, ~20 s)."""
    t, tr, mid = truth(cfg, dt)
    q = propagate(ahrs.quat_from_euler(tr["euler"][0]), mid["omega"] * dt)
    err = ahrs.euler_error(jax.vmap(ahrs.euler_from_quat)(q), tr["euler"][1:])
    return jnp.max(jnp.abs(err))


def attitude_update_check(cfg: Config) -> dict[str, float]:
    """Noise-free gyro integration against the closed-form attitude, at ``dt`` and ``dt/2``."""
    out = {
        name: float(_attitude_update_error(cfg, dt)) / DEG for name, dt in (("dt", cfg.dt), ("half_dt", 0.5 * cfg.dt))
    }
    return {
        "attitude_update_max_err_deg": out["dt"],
        "attitude_update_order": math.log2(out["dt"] / out["half_dt"]),
    }


# --- the study ------------------------------------------------------------------------------------


def _mean_ci(x: np.ndarray) -> tuple[float, float, float]:
    m = float(np.mean(x))
    h = 1.96 * float(np.std(x, ddof=1)) / math.sqrt(len(x)) if len(x) > 1 else float("nan")
    return m, m - h, m + h


PAPER_BIAS_DEG = {"pitch": -0.041, "roll": 0.056, "heading": 0.158}  # Table 2, "after" (for the quantile)


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    metrics, gm_rows = gm_identity(cfg)
    metrics |= attitude_update_check(cfg)

    tuning = tune_complementary(cfg, progress)
    xo, kr = (float(tuning.result.params[k]) for k in ("crossover", "ki_ratio"))
    metrics |= {
        "cf_crossover_tuned": xo,
        "cf_ki_ratio_tuned": kr,
        "cf_tune_loss_start": float(tuning.tables["cf_tuning"][0]["loss"]),
        "cf_tune_loss_end": float(tuning.result.loss),
    }
    keys = jax.random.split(jax.random.PRNGKey(cfg.seed), cfg.n_runs)
    runs = [
        {k: np.asarray(v) for k, v in one_run(cfg, k, xo, kr).items()} for k in progress(list(keys), desc="flights")
    ]
    st = {k: np.stack([r[k] for r in runs]) for k in runs[0]}

    run_rows = []
    for i in range(cfg.n_runs):
        row: dict[str, Any] = {"run": i}
        for j, a in enumerate(ANGLES):
            row[f"drift_before_{a}_deg_h"] = float(st["drift_before"][i, j]) / DEG * 3600.0
            row[f"sigma_before_{a}_deg"] = float(st["sigma_before"][i, j]) / DEG
            row[f"bias_after_{a}_deg"] = float(st["bias_after"][i, j]) / DEG
            row[f"sigma_after_{a}_deg"] = float(st["sigma_after"][i, j]) / DEG
            row[f"drift_after_{a}_deg_h"] = float(st["drift_after"][i, j]) / DEG * 3600.0
            row[f"bias_cf_{a}_deg"] = float(st["bias_cf"][i, j]) / DEG
            row[f"sigma_cf_{a}_deg"] = float(st["sigma_cf"][i, j]) / DEG
        row["accel_accepted"] = float(st["accel_accepted"][i])
        run_rows.append(row)

    for a in ANGLES:
        col = lambda name: np.array([r[name] for r in run_rows])  # noqa: E731
        for name, key in (
            ("before_drift", f"drift_before_{a}_deg_h"),
            ("after_drift", f"drift_after_{a}_deg_h"),
        ):
            m, lo, hi = _mean_ci(np.abs(col(key)))
            metrics |= {f"{name}_{a}_deg_h": m, f"{name}_{a}_ci_low": lo, f"{name}_{a}_ci_high": hi}
        for name, key in (
            ("before_sigma", f"sigma_before_{a}_deg"),
            ("after_sigma", f"sigma_after_{a}_deg"),
            ("cf_sigma", f"sigma_cf_{a}_deg"),
        ):
            m, lo, hi = _mean_ci(col(key))
            metrics |= {f"{name}_{a}_deg": m, f"{name}_{a}_ci_low": lo, f"{name}_{a}_ci_high": hi}
        b = col(f"bias_after_{a}_deg")
        metrics[f"after_bias_{a}_rms_deg"] = float(np.sqrt(np.mean(b**2)))
        metrics[f"after_bias_{a}_mean_deg"] = float(np.mean(b))
        metrics[f"cf_bias_{a}_rms_deg"] = float(np.sqrt(np.mean(col(f"bias_cf_{a}_deg") ** 2)))
        # where the paper's single-run bias falls among our per-run |bias|
        metrics[f"after_bias_{a}_paper_quantile"] = float(np.mean(np.abs(b) <= abs(PAPER_BIAS_DEG[a])))

    # attitude NEES (3 dof) averaged over runs at each sampled time, against the χ² 95 % bounds
    nees = st["nees"]
    avg = nees.mean(axis=0)
    lo, hi = chi2_bounds(3, cfg.n_runs, 0.95)
    t_n = runs[0]["nees_t"]
    after = t_n >= cfg.settle
    metrics |= {
        "nees_mean": float(np.mean(nees[:, after])),
        "nees_fraction_in_bounds": float(np.mean((avg[after] >= lo) & (avg[after] <= hi))),
        "nees_bound_low": lo,
        "nees_bound_high": hi,
        "accel_accepted_fraction": float(np.mean(st["accel_accepted"])),
    }
    nees_rows = [
        {"t_s": float(t), "nees_run_mean": float(v), "bound_low": lo, "bound_high": hi} for t, v in zip(t_n, avg)
    ]

    notes = [
        "Table 1 is the input of the sensor generator; constant errors are drawn per run and axis as zero-mean "
        "Gaussians with the table's values as σ (the table gives magnitudes only)",
        f"before: raw gyro integration drifts {metrics['before_drift_pitch_deg_h']:.0f}/"
        f"{metrics['before_drift_roll_deg_h']:.0f}/{metrics['before_drift_heading_deg_h']:.0f} °/h (pitch/roll/"
        "heading, mean |slope| over runs); Table 1's 0.2 °/s bias alone is 720 °/h, so the paper's 300/300/600 °/h "
        "is one draw of a smaller bias or a partly compensated one",
        f"before: raw accelerometer/magnetometer σ {metrics['before_sigma_pitch_deg']:.1f}/"
        f"{metrics['before_sigma_roll_deg']:.1f}/{metrics['before_sigma_heading_deg']:.1f}° (pitch/roll/heading): "
        "roll is the bank of the turn that the uncorrected accelerometer cannot see; heading is dominated by the "
        "uncalibrated 30 %/10 µT magnetometer",
        f"after: MEKF σ {metrics['after_sigma_pitch_deg']:.3f}/{metrics['after_sigma_roll_deg']:.3f}/"
        f"{metrics['after_sigma_heading_deg']:.3f}° (paper 0.115/0.115/0.0551°); the paper's TAMCAL magnetometer "
        "calibration and temperature least squares are not given: replaced by assumed residuals (toml)",
        f"complementary filter, crossover and bias-integral ratio tuned by gradient (Adam, {cfg.tune_steps} steps, "
        f"{cfg.tune_runs} tuning flights; mean squared error {metrics['cf_tune_loss_start']:.3g} → "
        f"{metrics['cf_tune_loss_end']:.3g} deg²): ω_c = {xo:.3g} rad/s, k_i = {kr:.3g}·ω_c²; on the Monte-Carlo "
        "flights σ "
        f"{metrics['cf_sigma_pitch_deg']:.3f}/{metrics['cf_sigma_roll_deg']:.3f}/{metrics['cf_sigma_heading_deg']:.3f}°"
        " (pitch/roll/heading); it has no covariance, so no NEES (the consistency check applies to the MEKF)",
        "the paper's after-biases (−0.041/0.056/0.158°) are one realisation: reported as the quantile of |bias| "
        "among our runs (reproduced if it is a plausible draw, 2.5–97.5 %)",
        "the accelerometer bias (5 mg) is not calibrated by any of the paper's algorithms; in a coordinated turn the "
        "specific force stays along body z, so the body-frame tilt error it causes (≈ 0.3°) is unobservable, and as "
        "the heading sweeps the magnetometer (inclination 70°, tan I ≈ 2.7) turns it into a heading error that "
        "varies over the flight: this, not noise, sets our heading σ",
        f"attitude NEES: run mean {metrics['nees_mean']:.2f} (3 dof), inside the χ² 95 % bounds "
        f"[{lo:.2f}, {hi:.2f}] at {100 * metrics['nees_fraction_in_bounds']:.0f} % of the sampled times after "
        "settling (the airspeed-error state matters: without it the low-passed airspeed error times the turn rate "
        "biases the tilt and the NEES reaches ≈ 13 in the turn)",
    ]

    r0 = runs[0]
    ts = r0["t_series"]
    fig = figures.line_panels(
        [
            figures.panel(
                {f"{a}": (ts, r0["e_after"][:, j] / DEG) for j, a in enumerate(ANGLES)},
                "t, s",
                "attitude error, deg",
                title="after: MEKF (run 0)",
            ),
            figures.panel(
                {f"{a} (accel/mag)": (ts, r0["e_before_pos"][:, j] / DEG) for j, a in enumerate(ANGLES)}
                | {f"{a} (gyro)": (ts, r0["e_before_gyro"][:, j] / DEG, "--") for j, a in enumerate(ANGLES)},
                "t, s",
                "attitude error, deg",
                title="before: raw sensors (run 0)",
            ),
            figures.panel(
                {"NEES, run mean": (t_n, avg)},
                "t, s",
                "NEES (3 dof)",
                hline=3.0,
                log_y=True,
                title=f"χ² 95 % bounds [{lo:.2f}, {hi:.2f}]",
            ),
        ]
    )
    t, tr, _ = truth(cfg, cfg.dt)
    sub = slice(None, None, cfg.nees_every)
    fig_truth = figures.line_panels(
        [
            figures.panel(
                {a: (np.asarray(t[sub]), np.asarray(tr["euler"][sub, j]) / DEG) for j, a in enumerate(ANGLES)},
                "t, s",
                "attitude, deg",
                title="assumed flight (cf. the paper's Fig. 1)",
            )
        ]
    )
    own = stages.Stage(
        tables={"gauss_markov": gm_rows, "runs": run_rows, "nees": nees_rows},
        figures={"errors": fig, "flight": fig_truth},
    )
    return stages.merge(own, tuning, metrics=metrics, notes=notes)


def cf_problem(cfg: Config) -> Problem:
    """Tuning of the complementary filter's crossover and bias-integral ratio (log-scaled box) on a
    batch of ``tune_runs`` flights drawn apart from the Monte-Carlo ones."""
    keys = jax.random.split(jax.random.PRNGKey(cfg.seed + 7), cfg.tune_runs)
    data = jax.vmap(lambda k: flight_inputs(cfg, k))(keys)
    space = ParamSpace(
        crossover=Param(lo=0.005, hi=2.0, init=cfg.cf_crossover, log=True),
        ki_ratio=Param(lo=0.005, hi=5.0, init=cfg.cf_ki_ratio, log=True),
    )
    return Problem.from_loss(
        "complementary_crossover", space, lambda p, _d, _k: cf_loss(cfg, data, p["crossover"], p["ki_ratio"])
    )


def tune_complementary(cfg: Config, progress: Callable[..., Any]) -> stages.TuningStage:
    return stages.gradient_tuning(
        cf_problem(cfg),
        steps=cfg.tune_steps,
        optimizer=optax.adam(cfg.tune_learning_rate),
        progress=progress,
        loss_label="mean squared attitude error, deg²",
        table="cf_tuning",
        figure="cf_tuning",
        mode="forward",
    )


STUDY = Study(
    name="orientation_system_accuracy",
    description="Seed 004 §2.5: MEMS AHRS errors of Table 1, raw vs calibrated + MEKF attitude errors of Table 2",
    config=Config,
    presets=PRESETS,
    claims=CLAIMS,
    assumptions=ASSUMPTIONS,
    run=run,
)
