"""Study ``wind_estimation``: wind from air data + INS (seed 004 part 3, #11, Chechulina; spec
``seed004_part3.md`` §2.6).

Kernel :mod:`jaxsim.estimation.wind` (the algebraic estimator of eqs. (1)–(2), the wind of eq. (3), the
measurement covariance by first-order propagation, a 4-state Kalman model: random-walk mean +
Gauss–Markov turbulence).  The paper shows curves only ("the estimates approach the model values"), for
four wind directions with ideal sensors on a proprietary 6-DOF stand.  Here:

1. **Exactness** with ideal sensors for the paper's four cases ``(K_w, δ_w) = (0°, ±30°), (180°, ±30°)``
   on an assumed longitudinal flight (climbs and descents, varying airspeed and angle of attack).
2. **Monte Carlo against turbulence intensity** with noisy sensors: RMS error of the raw algebraic
   estimate, of the Kalman filter's wind and of its mean wind; filter consistency (NEES against χ²(4)
   bounds).
3. **Gradient maximum likelihood** of the turbulence intensity and correlation time through the
   filter's log-likelihood (``jax.value_and_grad`` + L-BFGS-B), against the generating values.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np
import scipy.optimize

from experiments import figures, stages
from experiments.runner import Study, StudyResult, paper_facts
from jaxsim.estimation import wind as we
from jaxsim.estimation.gating import chi2_bounds, nees
from jaxsim.estimation.lgssm import kalman_filter

CASES = ((0.0, 30.0), (0.0, -30.0), (180.0, 30.0), (180.0, -30.0))


@dataclass(frozen=True)
class Config:
    # flight (assumed): airspeed 25 ± 2 m/s, air-path angle ±0.08 rad, angle of attack 0.06 ± 0.02 rad
    duration: float = 300.0  # s
    dt: float = 0.1  # s, 10 Hz
    v_air: float = 25.0  # m/s
    h0: float = 300.0  # m
    # mean wind: power law W(H) = w_ref·(H/h_ref)^(1/7) (assumed; the paper's W(H) is not given)
    w_ref: float = 8.0  # m/s at h_ref
    h_ref: float = 300.0  # m
    # sensor noise (assumed, 1σ): ground speed, vertical rate, pitch, airspeed, angle of attack
    sensor_std: tuple[float, ...] = (0.1, 0.1, math.radians(0.1), 0.5, math.radians(0.5))
    # turbulence: Gauss–Markov per component, correlation time tau (assumed ≈ L/V, L = 125 m)
    tau: float = 5.0  # s
    intensities: tuple[float, ...] = (0.25, 0.5, 1.0, 2.0, 4.0)  # m/s
    q_mean: float = 5e-4  # (m/s)²/s, random-walk intensity of the filter's mean wind (≈ the profile's drift)
    mc_runs: int = 200
    ml_runs: int = 20  # runs pooled in the likelihood
    ml_sigma: float = 1.0  # m/s, generating intensity of the ML stage
    seed: int = 0


def flight(cfg: Config) -> dict[str, jax.Array]:
    """Air-relative flight (no wind): time, airspeed, air-path angle, angle of attack, pitch, altitude."""
    t = jnp.arange(int(round(cfg.duration / cfg.dt))) * cfg.dt
    v = cfg.v_air + 2.0 * jnp.sin(2 * jnp.pi * t / 60.0)
    gamma = 0.08 * jnp.sin(2 * jnp.pi * t / 90.0)
    alpha = 0.06 + 0.02 * jnp.sin(2 * jnp.pi * t / 20.0)
    h = cfg.h0 + jnp.cumsum(v * jnp.sin(gamma)) * cfg.dt
    return {"t": t, "v": v, "gamma": gamma, "alpha": alpha, "pitch": gamma + alpha, "h": h}


def mean_wind(cfg: Config, fl: dict[str, jax.Array], azimuth: Any, inclination: Any) -> jax.Array:
    """``(T, 2)``: eq. (3) with the power-law speed at each altitude."""
    speed = cfg.w_ref * (fl["h"] / cfg.h_ref) ** (1.0 / 7.0)
    return we.wind_components(speed, azimuth, inclination)


def turbulence(key: jax.Array, n: int, dt: float, tau: Any, sigma: Any) -> jax.Array:
    """``(n, 2)`` exact samples of the stationary Gauss–Markov turbulence."""
    phi = jnp.exp(-dt / tau)
    eps = jax.random.normal(key, (n, 2))

    def step(w, e):
        w = phi * w + sigma * jnp.sqrt(1 - phi**2) * e
        return w, w

    w0 = sigma * jax.random.normal(jax.random.fold_in(key, 1), (2,))
    return jnp.concatenate([w0[None], jax.lax.scan(step, w0, eps[1:])[1]])


def air_data(fl: dict[str, jax.Array], wind: jax.Array) -> we.AirData:
    """Ideal sensor readings for the air path ``fl`` in the wind ``(T, 2)``."""
    vg = fl["v"][:, None] * jnp.stack([jnp.cos(fl["gamma"]), jnp.sin(fl["gamma"])], axis=1) + wind
    return we.AirData(jnp.linalg.norm(vg, axis=1), vg[:, 1], fl["pitch"], fl["v"], fl["alpha"])


def noisy(d: we.AirData, key: jax.Array, std: tuple[float, ...]) -> we.AirData:
    noise = jax.random.normal(key, (len(std), d.v_ground.shape[0])) * jnp.asarray(std)[:, None]
    return we.AirData(*(x + e for x, e in zip(d, noise)))


def run_filter(cfg: Config, meas: we.AirData, tau: Any, sigma: Any):
    """Kalman filter over the algebraic estimates of ``meas``; returns ``(z (T, 2), FilterResult)``."""
    z = we.wind_from_air_data(meas)
    r = jax.vmap(lambda *s: we.measurement_cov(we.AirData(*s), jnp.asarray(cfg.sensor_std)))(*meas)
    model = we.wind_filter_model(cfg.dt, tau, sigma, cfg.q_mean, r)
    return z, kalman_filter(model, z)


def one_run(cfg: Config, fl: dict[str, jax.Array], key: jax.Array, sigma: Any) -> dict[str, jax.Array]:
    """Errors of one noisy flight with turbulence ``sigma`` (m/s), mean wind from azimuth 0, inclination 0."""
    k_turb, k_sens = jax.random.split(key)
    mean = mean_wind(cfg, fl, 0.0, 0.0)
    turb = turbulence(k_turb, fl["t"].shape[0], cfg.dt, cfg.tau, sigma)
    truth = mean + turb
    z, res = run_filter(cfg, noisy(air_data(fl, truth), k_sens, cfg.sensor_std), cfg.tau, sigma)
    skip = int(round(30.0 / cfg.dt))  # after the prior's transient
    est = res.means[:, :2] + res.means[:, 2:]
    rms = lambda e: jnp.sqrt(jnp.mean(jnp.sum(e[skip:] ** 2, axis=1) / 2))  # noqa: E731  per component
    x_true = jnp.concatenate([mean, turb], axis=1)
    return {
        "rms_algebraic": rms(z - truth),
        "rms_filter": rms(est - truth),
        "rms_filter_mean": rms(res.means[:, :2] - mean),
        "nees": jnp.mean(jax.vmap(nees)(x_true[skip:], res.means[skip:], res.covs[skip:])),
    }


def exactness_stage(cfg: Config, fl: dict[str, jax.Array]) -> stages.Stage:
    rows, metrics, lines = [], {}, {}
    worst = 0.0
    for az, inc in CASES:
        truth = mean_wind(cfg, fl, math.radians(az), math.radians(inc))
        est = we.wind_from_air_data(air_data(fl, truth))
        err = float(jnp.max(jnp.abs(est - truth)))
        worst = max(worst, err)
        rows.append({"azimuth_deg": az, "inclination_deg": inc, "max_abs_error_m_s": err})
        lines[f"K={az:g}°, δ={inc:g}°: W_x"] = (fl["t"], est[:, 0])
        lines[f"K={az:g}°, δ={inc:g}°: W_y"] = (fl["t"], est[:, 1], "--")
    metrics["ideal_sensors_max_abs_error"] = worst
    fig = figures.line_panels(
        [figures.panel(lines, "t, s", "wind estimate, m/s", title="algebraic estimate, ideal sensors")]
    )
    return stages.Stage(
        metrics=metrics,
        tables={"ideal_sensors": rows},
        figures={"ideal_sensors": fig},
        notes=[f"ideal sensors, the paper's four wind directions: largest |error| {worst:.2e} m/s (exact)"],
    )


def monte_carlo_stage(cfg: Config, fl: dict[str, jax.Array], progress: Callable[..., Any]) -> stages.Stage:
    keys = jax.random.split(jax.random.PRNGKey(cfg.seed), cfg.mc_runs)
    batch = jax.jit(jax.vmap(lambda k, s: one_run(cfg, fl, k, s), in_axes=(0, None)))
    lo, hi = chi2_bounds(4, cfg.mc_runs)
    rows, metrics = [], {}
    bar = progress(total=len(cfg.intensities), desc="wind: intensities", unit="σ") if progress else None
    for sigma in cfg.intensities:
        out = {k: np.asarray(v) for k, v in batch(keys, jnp.asarray(sigma)).items()}
        row = {"sigma_turbulence_m_s": sigma, "runs": cfg.mc_runs}
        for k in ("rms_algebraic", "rms_filter", "rms_filter_mean"):
            row[f"{k}_m_s"] = float(np.mean(out[k]))
        row["nees_mean"] = float(np.mean(out["nees"]))
        row["nees_lo"], row["nees_hi"] = lo, hi
        rows.append(row)
        tag = f"{sigma:g}".replace(".", "p")
        for k, v in row.items():
            if k not in ("sigma_turbulence_m_s", "runs", "nees_lo", "nees_hi"):
                metrics[f"{k}_sigma_{tag}"] = v
        if bar:
            bar.update(1)
    if bar:
        bar.close()
    sig = [r["sigma_turbulence_m_s"] for r in rows]
    fig = figures.line_panels(
        [
            figures.panel(
                {
                    "algebraic (raw)": (sig, [r["rms_algebraic_m_s"] for r in rows], "o-"),
                    "Kalman: wind": (sig, [r["rms_filter_m_s"] for r in rows], "s-"),
                    "Kalman: mean wind": (sig, [r["rms_filter_mean_m_s"] for r in rows], "^-"),
                },
                "turbulence intensity σ_t, m/s",
                "RMS error per component, m/s",
                title=f"{cfg.mc_runs} runs per intensity",
            ),
            figures.panel(
                {"average NEES": (sig, [r["nees_mean"] for r in rows], "o-")},
                "turbulence intensity σ_t, m/s",
                "NEES (4 states)",
                title=f"χ²(4) 95 % band [{lo:.2f}, {hi:.2f}]",
                hline=4.0,
            ),
        ]
    )
    inside = sum(lo <= r["nees_mean"] <= hi for r in rows)
    metrics["nees_inside_bounds_fraction"] = inside / len(rows)
    return stages.Stage(
        metrics=metrics,
        tables={"accuracy_vs_turbulence": rows},
        figures={"accuracy_vs_turbulence": fig},
        notes=[
            f"NEES inside the χ²(4) 95 % band of the {cfg.mc_runs}-run average at {inside} of {len(rows)} intensities "
            "(the true mean wind follows the altitude, the filter's is a random walk)"
        ],
    )


def ml_stage(cfg: Config, fl: dict[str, jax.Array]) -> stages.Stage:
    keys = jax.random.split(jax.random.PRNGKey(cfg.seed + 7), cfg.ml_runs)

    def measurements(key):
        k_turb, k_sens = jax.random.split(key)
        truth = mean_wind(cfg, fl, 0.0, 0.0) + turbulence(k_turb, fl["t"].shape[0], cfg.dt, cfg.tau, cfg.ml_sigma)
        return noisy(air_data(fl, truth), k_sens, cfg.sensor_std)

    meas = jax.vmap(measurements)(keys)

    @jax.jit
    def neg_ll(log_theta):
        tau, sigma = jnp.exp(log_theta)
        ll = jax.vmap(lambda m: run_filter(cfg, m, tau, sigma)[1].log_likelihood)(meas)
        return -jnp.sum(ll)

    vg = jax.jit(jax.value_and_grad(neg_ll))
    x0 = np.log([2.0 * cfg.tau, 0.5 * cfg.ml_sigma])
    res = scipy.optimize.minimize(lambda x: tuple(np.asarray(v, float) for v in vg(jnp.asarray(x))), x0, jac=True)
    tau_hat, sigma_hat = np.exp(res.x)
    # Hessian by central differences of the compiled gradient (no second compilation)
    step = 1e-4
    grad_at = lambda x: np.asarray(vg(jnp.asarray(x))[1], float)  # noqa: E731
    h = np.stack([(grad_at(res.x + step * e) - grad_at(res.x - step * e)) / (2 * step) for e in np.eye(2)])
    se = np.sqrt(np.diag(np.linalg.inv(0.5 * (h + h.T))))  # standard errors of log τ, log σ
    metrics = {
        "ml_tau_s": float(tau_hat),
        "ml_sigma_m_s": float(sigma_hat),
        "ml_tau_rel_error": float(tau_hat / cfg.tau - 1),
        "ml_sigma_rel_error": float(sigma_hat / cfg.ml_sigma - 1),
        "ml_tau_z": float(np.log(tau_hat / cfg.tau) / se[0]),
        "ml_sigma_z": float(np.log(sigma_hat / cfg.ml_sigma) / se[1]),
        "ml_iterations": float(res.nit),
    }
    return stages.Stage(
        metrics=metrics,
        tables={
            "maximum_likelihood": [
                {"parameter": "tau_s", "true": cfg.tau, "estimate": float(tau_hat), "se_log": float(se[0])},
                {"parameter": "sigma_m_s", "true": cfg.ml_sigma, "estimate": float(sigma_hat), "se_log": float(se[1])},
            ]
        },
        notes=[
            f"gradient ML over {cfg.ml_runs} flights: τ = {tau_hat:.2f} s (true {cfg.tau:g}), "
            f"σ_t = {sigma_hat:.3f} m/s (true {cfg.ml_sigma:g}); "
            f"z-scores {metrics['ml_tau_z']:.2f}, {metrics['ml_sigma_z']:.2f} "
            f"({res.nit} L-BFGS-B iterations)"
        ],
    )


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    fl = flight(cfg)
    return stages.merge(exactness_stage(cfg, fl), monte_carlo_stage(cfg, fl, progress), ml_stage(cfg, fl))


CLAIMS, ASSUMPTIONS = paper_facts("wind_estimation")

STUDY = Study(
    name="wind_estimation",
    description="Seed 004 #11 (part 3): wind from air data + INS — the algebraic estimator exact with ideal "
    "sensors, a Kalman filter's accuracy vs turbulence by Monte Carlo, turbulence by gradient ML",
    config=Config,
    presets={
        "quick": dict(mc_runs=64, ml_runs=8),
        "tiny": dict(duration=60.0, intensities=(0.5, 2.0), mc_runs=16, ml_runs=4),
    },
    claims=CLAIMS,
    assumptions=ASSUMPTIONS,
    run=run,
)
