"""Study ``attitude_algorithms``: first-order vs coning-corrected attitude updates under classical
coning (seed 004 part 2, paper #2, spec §2.5).

The gyro increments of a classical coning motion (half-angle ``α``, frequency ``Ω``) are exact
(:func:`jaxsim.inertial.attitude.coning_increments`); four update rules (first order, two-sample with
the previous interval, two-sample, three-sample) propagate the attitude at each sample rate (a fixed
number of updates), and the drift rate about the coning axis (least-squares slope of the attitude
error against the exact attitude) is compared with the closed-form coning drift of each rule.  The error
orders are the log-log slopes of drift against sample rate (−2, −4, −4, −6).  A second table runs the
paper's setting (update steps 0.1, 0.01, 0.001 s over 100 s) with a 15° cone at an 8 s period.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np

from experiments import figures, stages
from experiments.runner import Study, StudyResult, paper_facts
from jaxsim.inertial.attitude import (
    ALGORITHMS,
    SAMPLES_PER_UPDATE,
    coning_attitude,
    coning_drift_rate,
    coning_increments,
    drift_rate,
    propagate,
    rotation_vectors,
)

CLAIMS, ASSUMPTIONS = paper_facts("attitude_algorithms")
DEG = math.pi / 180.0
ORDER = {"first_order": 2, "two_sample_previous": 4, "two_sample": 4, "three_sample": 6}


@dataclass(frozen=True)
class Config:
    cone_half_angle_deg: float = 1.0  # small, so the O(α²) closed form is the reference to ~1e-4
    cone_frequency_hz: float = 1.0
    sample_rates_hz: tuple[float, ...] = (10.0, 20.0, 40.0, 80.0, 160.0)  # gyro sub-sample rates
    updates: int = 480  # attitude updates per run at every rate (one compilation per algorithm)
    resolvable_error: float = 1e-11  # rad: points whose closed-form error over the run is below are not fitted
    paper_half_angle_deg: float = 15.0  # the paper's roll/yaw amplitude as a cone (assumption)
    paper_period: float = 8.0  # s, a ship-like period (the paper gives none)
    paper_steps: tuple[float, ...] = (0.1, 0.01, 0.001)  # s, the paper's update steps
    paper_duration: float = 100.0  # s, the paper's run length
    roundoff_floor_deg: float = 1e-9  # errors after the run below this are float64 round-off (~1e-13 °/step)


PRESETS = {
    "quick": dict(paper_steps=(0.1, 0.01)),
    "tiny": dict(  # every stage once at the smallest sizes (the test's preset)
        sample_rates_hz=(10.0, 20.0, 40.0), updates=120, paper_steps=(0.1, 0.05), paper_duration=12.0
    ),
}


@functools.partial(jax.jit, static_argnames=("updates", "algorithm"))
def _drift(alpha: Any, omega: Any, h: Any, updates: int, algorithm: str) -> jax.Array:
    m = SAMPLES_PER_UPDATE[algorithm]
    inc = coning_increments(updates * m, h, alpha, omega)
    prev = coning_increments(1, h, alpha, omega, t0=-h)[0]
    q = propagate(coning_attitude(0.0, alpha, omega), rotation_vectors(inc, algorithm, previous=prev))
    t = (jnp.arange(updates) + 1) * m * h
    return drift_rate(t, coning_attitude(t, alpha, omega), q)


def simulate(alpha: float, omega: float, h: float, updates: int, algorithm: str) -> np.ndarray:
    """Drift rates (rad/s; x = the coning axis) of ``algorithm`` with gyro sub-interval ``h`` over
    ``updates`` attitude updates (one compilation per ``(updates, algorithm)``)."""
    return np.asarray(_drift(alpha, omega, h, updates, algorithm))


def order_sweep(cfg: Config, progress: Callable[..., Any]) -> stages.Stage:
    alpha, omega = cfg.cone_half_angle_deg * DEG, 2 * math.pi * cfg.cone_frequency_hz
    rows, metrics, lines = [], {}, {}
    for alg in progress(ALGORITHMS, desc="algorithms", unit="algorithm"):
        rates, sims, closed = [], [], []
        for f in cfg.sample_rates_hz:
            h = 1.0 / f
            duration = cfg.updates * SAMPLES_PER_UPDATE[alg] * h
            drift = simulate(alpha, omega, h, cfg.updates, alg)
            ref = float(coning_drift_rate(alpha, omega, h, alg))
            resolvable = abs(ref) * duration >= cfg.resolvable_error
            rows.append(
                {
                    "algorithm": alg,
                    "sample_rate_hz": f,
                    "lambda": omega * h,
                    "duration_s": duration,
                    "drift_x_rad_s": float(drift[0]),
                    "closed_form_rad_s": ref,
                    "ratio": float(drift[0]) / ref,
                    "drift_yz_rad_s": float(np.hypot(*drift[1:])),
                    "fitted": resolvable,
                }
            )
            if resolvable:
                rates.append(f)
                sims.append(abs(float(drift[0])))
                closed.append(abs(ref))
        slope = float(np.polyfit(np.log(rates), np.log(sims), 1)[0]) if len(rates) >= 2 else math.nan
        metrics[f"slope_{alg}"] = slope
        metrics[f"order_{alg}"] = -slope
        fitted = [r["ratio"] for r in rows if r["algorithm"] == alg and r["fitted"]]
        metrics[f"max_rel_dev_from_closed_{alg}"] = float(max(abs(np.array(fitted) - 1))) if fitted else math.nan
        lines[f"{alg} (simulated)"] = (rates, sims, "o")
        ff = np.geomspace(min(cfg.sample_rates_hz), max(cfg.sample_rates_hz), 50)
        lines[f"{alg} (closed form)"] = (
            ff,
            np.abs(np.asarray([coning_drift_rate(alpha, omega, 1 / f, alg) for f in ff])),
            "-",
        )
    fig = figures.line_panels(
        [
            figures.panel(
                lines,
                "gyro sample rate, Hz",
                "coning drift rate, rad/s",
                log_y=True,
                title=f"classical coning, α = {cfg.cone_half_angle_deg:g}°, {cfg.cone_frequency_hz:g} Hz",
            )
        ],
        size=(7.5, 5.5),
    )
    fig.axes[0].set_xscale("log")
    notes = [
        "log-log slopes of the drift rate against the sample rate: "
        + ", ".join(f"{a} {metrics[f'slope_{a}']:.2f}" for a in ALGORITHMS)
        + " (expected −2, −4, −4, −6); the previous-interval two-sample rule has exactly the two-sample "
        "rule's coning error at the same gyro rate but updates twice as often"
    ]
    return stages.Stage(metrics=metrics, tables={"order_sweep": rows}, figures={"drift_vs_rate": fig}, notes=notes)


def paper_setting(cfg: Config, progress: Callable[..., Any]) -> stages.Stage:
    alpha, omega = cfg.paper_half_angle_deg * DEG, 2 * math.pi / cfg.paper_period
    rows = []
    for step in progress(cfg.paper_steps, desc="paper steps", unit="step"):
        for alg in ALGORITHMS:
            h = step / SAMPLES_PER_UPDATE[alg]  # the update step is the paper's h; sub-samples inside it
            drift = simulate(alpha, omega, h, int(round(cfg.paper_duration / step)), alg)
            ref = float(coning_drift_rate(alpha, omega, h, alg))
            rows.append(
                {
                    "update_step_s": step,
                    "algorithm": alg,
                    "drift_x_deg_per_h": float(drift[0]) / DEG * 3600,
                    "closed_form_deg_per_h": ref / DEG * 3600,
                    "error_after_run_deg": float(drift[0]) * cfg.paper_duration / DEG,
                }
            )
    best, ranked = {}, []
    for step in cfg.paper_steps:
        errs = {r["algorithm"]: abs(r["error_after_run_deg"]) for r in rows if r["update_step_s"] == step}
        best[step] = min(errs, key=errs.get)
        if errs["two_sample"] > cfg.roundoff_floor_deg:  # below it every corrected rule is round-off
            ranked.append([errs[a] for a in ALGORITHMS] == sorted(errs.values(), reverse=True))
    metrics = {"paper_setting_ranking_holds": float(all(ranked)) if ranked else math.nan}
    first = [abs(r["drift_x_deg_per_h"]) for r in rows if r["algorithm"] == "first_order"]
    if len(first) >= 2:
        steps = list(cfg.paper_steps)
        metrics["paper_setting_first_order_slope_vs_step"] = float(np.polyfit(np.log(steps), np.log(first), 1)[0])
    notes = [
        f"paper setting ({cfg.paper_half_angle_deg:g}° cone, {cfg.paper_period:g} s period, "
        f"{cfg.paper_duration:g} s): the update step is h and the multi-sample rules sample the gyro "
        "inside it; the smallest error after the run: "
        + ", ".join(f"h = {s:g} s: {b}" for s, b in best.items())
        + f"; the ranking first order > two-sample (previous) > two-sample > three-sample is checked where the "
        f"two-sample error exceeds {cfg.roundoff_floor_deg:g}° (below, all corrected rules sit at round-off); "
        "at a 15° cone the three-sample drift is set by O(α⁴) terms the coning corrections do not model, far "
        "above its O(α²) closed form (the paper's small-parameter / multiple-integral methods are not "
        "reconstructed: their formulas are lost)"
    ]
    return stages.Stage(metrics=metrics, tables={"paper_setting": rows}, notes=notes)


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    return stages.merge(order_sweep(cfg, progress), paper_setting(cfg, progress))


STUDY = Study(
    name="attitude_algorithms",
    description="Seed 004 #2: first-order vs coning-corrected two- and three-sample attitude updates under "
    "classical coning — drift against the closed-form coning drift, error orders by log-log slope",
    config=Config,
    presets=PRESETS,
    claims=CLAIMS,
    assumptions=ASSUMPTIONS,
    run=run,
)
