"""Study ``imu_bench_calibration``: bench calibration of a strapdown IMU on a single-axis table by the
24-state Kalman filter of Parusnikov's method (seed 004 part 1, B3, Golovan's lecture).

Kernels: :mod:`jaxsim.inertial.bench_calibration`.  Three stages:

* observability — ranks of the prior-normalised Fisher information of plans that differ in one respect
  each: one, two or three horizontal-rotation cycles (one per instrument axis); one table rate or two
  (time skew τ); temperature constant, a function of the rate, or a ramp (temperature coefficients).
  Structural ranks use the model without Earth rate (the paper's argument); the Earth rate alone adds
  the azimuth β_U;
* consistency — Monte-Carlo runs of the filter on the three-cycle plan: the mean final NEES against the
  two-sided 95 % χ² interval;
* plan — the six rotation rates of the three-cycle plan tuned by gradient (L-BFGS-B, JAX gradient) of
  the trace of the final covariance normalised by the prior.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import partial
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np
import scipy.optimize

from experiments import figures, stages
from experiments.runner import Study, StudyResult, paper_facts
from jaxsim.estimation.gating import chi2_bounds, nees
from jaxsim.inertial import bench_calibration as bc

CLAIMS, ASSUMPTIONS = paper_facts("imu_bench_calibration")
DEG = math.pi / 180


@dataclass(frozen=True)
class Config:
    latitude_deg: float = 55.7  # Moscow (assumed: the lecture's lab)
    dt: float = 1.0  # s
    rest_steps: int = 20  # steps at rest before each cycle
    rot_steps: int = 36  # steps of each of the two rotation segments of a cycle
    rate_deg: float = 10.0  # °/s, first rotation rate
    rate2_deg: float = 20.0  # °/s, second rotation rate
    gyro_noise: float = 1e-5  # rad/√s
    accel_noise: float = 1e-4  # m/s/√s
    sigma_beta: float = 1e-3  # rad, prior σ of the attitude errors (after a coarse alignment)
    sigma_accel_bias: float = 1e-2  # m/s²
    sigma_scale: float = 1e-3  # Γ, Θ entries
    sigma_gyro_bias: float = 1e-4  # rad/s
    sigma_skew: float = 1e-2  # s
    sigma_thermal: float = 1e-3  # m/s²/K
    temperature_span: float = 10.0  # K over the plan
    mc_runs: int = 400
    seed: int = 0
    opt_iterations: int = 30
    rate_bounds_deg: tuple[float, float] = (2.0, 40.0)


PRESETS = {
    "quick": dict(mc_runs=400, opt_iterations=20),
    "tiny": dict(mc_runs=40, opt_iterations=4, rot_steps=24, rest_steps=10, rate_deg=15.0, rate2_deg=30.0),
}

N_FULL = bc.n_states(skew=True, thermal=True)
BASE = list(range(bc.N_BASE))
SKEW = BASE + [bc.N_BASE]
THERMAL = BASE + [bc.N_BASE + 1, bc.N_BASE + 2, bc.N_BASE + 3]


def _prior_sigma(cfg: Config) -> np.ndarray:
    return np.concatenate(
        [
            np.full(3, cfg.sigma_beta),
            np.full(3, cfg.sigma_accel_bias),
            np.full(6, cfg.sigma_scale),
            np.full(3, cfg.sigma_gyro_bias),
            np.full(9, cfg.sigma_scale),
            [cfg.sigma_skew],
            np.full(3, cfg.sigma_thermal),
        ]
    )


def _plan(cfg: Config, axes, rest_rate, rate2, temperature=None) -> bc.Plan:
    """Each cycle: ``rest_steps`` at ``rest_rate``, ``rot_steps`` at the first rate, ``rot_steps`` at ``rate2``."""
    ax, rt, st = [], [], []
    for a in axes:
        ax += [a, a, a]
        rt += [rest_rate, cfg.rate_deg * DEG, rate2]
        st += [cfg.rest_steps, cfg.rot_steps, cfg.rot_steps]
    return bc.plan_from_segments(ax, rt, st, cfg.dt, temperature)


def _n_steps(cfg: Config) -> int:
    return 3 * (cfg.rest_steps + 2 * cfg.rot_steps)


def observability(cfg: Config, progress: Callable[..., Any]) -> stages.Stage:
    lat, dt = math.radians(cfg.latitude_deg), cfg.dt
    R = bc.noise(N_FULL, dt, cfg.gyro_noise, cfg.accel_noise)[1]
    sig = _prior_sigma(cfg)

    def info1(plan, earth_rate):
        F, H = bc.model_arrays(plan, lat, dt, skew=True, thermal=True, earth_rate=earth_rate)
        return bc.information(F, H, R)

    info = jax.jit(jax.vmap(jax.vmap(info1, (None, 0)), (0, None)))  # plans × (no Earth rate, Earth rate)

    r1, r2, n = cfg.rate_deg * DEG, cfg.rate2_deg * DEG, _n_steps(cfg)
    one_rate = _plan(cfg, (0, 1, 2), r1, r1)  # no rest, a single rate throughout
    three = _plan(cfg, (0, 1, 2), 0.0, r1)  # rest + one rate = two rates (0 and ω)
    two_rates = _plan(cfg, (0, 1, 2), 0.0, r2)
    t_rate = (jnp.abs(two_rates.rate) / r2) * cfg.temperature_span  # T a function of the rate alone
    cases = [
        ("1 cycle (axis 1)", _plan(cfg, (0, 0, 0), 0.0, r1), BASE),
        ("2 cycles (axes 1, 2)", _plan(cfg, (0, 1, 1), 0.0, r1), BASE),
        ("3 cycles (axes 1, 2, 3)", three, BASE),
        ("3 cycles, one rate, no rest", one_rate, BASE),
        ("τ: one rate, no rest", one_rate, SKEW),
        ("τ: rest + one rate", three, SKEW),
        ("τ: two rates", two_rates, SKEW),
        ("k_f: T constant", _plan(cfg, (0, 1, 2), 0.0, r2, jnp.full(n, 5.0)), THERMAL),
        ("k_f: T = c·|ω| (3 rate levels)", _plan(cfg, (0, 1, 2), 0.0, r2, t_rate), THERMAL),
        ("k_f: T constant, one rate", _plan(cfg, (0, 1, 2), r1, r1, t_rate[-1] * jnp.ones(n)), THERMAL),
        ("k_f: T ramp in time", _plan(cfg, (0, 1, 2), 0.0, r2, jnp.linspace(0, cfg.temperature_span, n)), THERMAL),
    ]
    plans = jax.tree.map(lambda *a: jnp.stack(a), *[c[1] for c in cases])
    Js = np.asarray(info(plans, jnp.array([0.0, bc.EARTH_RATE])))
    rows, spectra = [], {}
    for (name, _, idx), Jp in zip(progress(cases, desc="rank tests", unit="plan"), Js):
        row = {"plan": name, "states": len(idx)}
        for tag, J in (("structural", Jp[0]), ("with_earth_rate", Jp[1])):
            J = J[np.ix_(idx, idx)]
            row[f"rank_{tag}"] = bc.rank(J, sig[idx])
            if tag == "structural":
                s = np.linalg.svd(sig[idx][:, None] * J * sig[idx][None, :], compute_uv=False)
                spectra[name] = s / s[0]
        rows.append(row)
    rk = {r["plan"]: r for r in rows}
    base_rank = {
        c: rk[c]["rank_structural"] for c in ("1 cycle (axis 1)", "2 cycles (axes 1, 2)", "3 cycles (axes 1, 2, 3)")
    }
    need = [k for k, c in enumerate(base_rank.values(), 1) if c == bc.N_BASE - 1]
    metrics = {
        "rank_1_cycle": base_rank["1 cycle (axis 1)"],
        "rank_2_cycles": base_rank["2 cycles (axes 1, 2)"],
        "rank_3_cycles": base_rank["3 cycles (axes 1, 2, 3)"],
        "cycles_for_full_rank": need[0] if need else math.nan,
        "rank_3_cycles_with_earth_rate": rk["3 cycles (axes 1, 2, 3)"]["rank_with_earth_rate"],
        "rank_3_cycles_one_rate_no_rest": rk["3 cycles, one rate, no rest"]["rank_structural"],
        "skew_gain_one_rate": rk["τ: one rate, no rest"]["rank_structural"]
        - rk["3 cycles, one rate, no rest"]["rank_structural"],
        "skew_gain_two_rates": rk["τ: two rates"]["rank_structural"] - base_rank["3 cycles (axes 1, 2, 3)"],
        "thermal_gain_constant": rk["k_f: T constant"]["rank_structural"] - base_rank["3 cycles (axes 1, 2, 3)"],
        "thermal_gain_constant_one_rate": rk["k_f: T constant, one rate"]["rank_structural"]
        - rk["3 cycles, one rate, no rest"]["rank_structural"],
        "thermal_gain_rate_function": rk["k_f: T = c·|ω| (3 rate levels)"]["rank_structural"]
        - base_rank["3 cycles (axes 1, 2, 3)"],
        "thermal_gain_ramp": rk["k_f: T ramp in time"]["rank_structural"] - base_rank["3 cycles (axes 1, 2, 3)"],
    }
    fig = figures.line_panels(
        [
            figures.panel(
                {k: (np.arange(1, len(v) + 1), np.maximum(v, 1e-22), "o-") for k, v in list(spectra.items())[:4]},
                "index",
                "singular value / largest (prior-normalised information)",
                log_y=True,
                title="structural (no Earth rate), 24 states",
            )
        ],
        size=(8.0, 5.0),
    )
    notes = [
        "structural ranks of the 24-state model (no Earth rate): 1 cycle %d, 2 cycles %d, 3 cycles %d "
        "(all but the azimuth β_U); with the Earth rate the 3-cycle plan has rank %d; time skew adds %d with "
        "one rate, %d with two; temperature coefficients add %d (T constant), %d (T ramp), %d (T a function of "
        "the rate over three rate levels)"
        % (
            metrics["rank_1_cycle"],
            metrics["rank_2_cycles"],
            metrics["rank_3_cycles"],
            metrics["rank_3_cycles_with_earth_rate"],
            metrics["skew_gain_one_rate"],
            metrics["skew_gain_two_rates"],
            metrics["thermal_gain_constant"],
            metrics["thermal_gain_ramp"],
            metrics["thermal_gain_rate_function"],
        )
    ]
    return stages.Stage(
        metrics=metrics, tables={"observability": rows}, figures={"information_spectra": fig}, notes=notes
    )


@partial(jax.jit, static_argnums=0)
def _model(cfg: Config, rates: jax.Array):
    """The 24-state model of the three-cycle plan with cycle ``k``'s two rates ``rates[2k], rates[2k+1]``."""
    lat, dt = math.radians(cfg.latitude_deg), cfg.dt
    ax, rt, st = [], [], []
    for a in range(3):
        ax += [a, a, a]
        rt += [0.0 * rates[0], rates[2 * a], rates[2 * a + 1]]
        st += [cfg.rest_steps, cfg.rot_steps, cfg.rot_steps]
    plan = bc.plan_from_segments(ax, jnp.stack(rt), st, dt)
    F, H = bc.model_arrays(plan, lat, dt)
    Q, R = bc.noise(bc.N_BASE, dt, cfg.gyro_noise, cfg.accel_noise)
    return F, H, Q, R


def consistency(cfg: Config, progress: Callable[..., Any]) -> stages.Stage:
    rates = jnp.array([cfg.rate_deg, cfg.rate2_deg] * 3) * DEG
    F, H, Q, R = _model(cfg, rates)
    P0 = jnp.diag(jnp.asarray(_prior_sigma(cfg)[: bc.N_BASE]) ** 2)
    x, m, P = bc.run_monte_carlo(np.random.default_rng(cfg.seed), cfg.mc_runs, F, H, Q, R, P0)
    sig = _prior_sigma(cfg)[: bc.N_BASE]  # NEES in prior-normalised units (the same number, better conditioned)
    Pn = jnp.broadcast_to(P / np.outer(sig, sig), (cfg.mc_runs, *P.shape))
    e = np.asarray(nees(jnp.asarray(x / sig), jnp.asarray(m / sig), Pn))
    lo, hi = chi2_bounds(bc.N_BASE, cfg.mc_runs, 0.95)
    mean = float(e.mean())
    metrics = {"nees_mean": mean, "nees_lo": lo, "nees_hi": hi, "nees_inside": float(lo <= mean <= hi)}
    rows = [{"runs": cfg.mc_runs, "dof": bc.N_BASE, "nees_mean": mean, "chi2_lo_95": lo, "chi2_hi_95": hi}]
    notes = [f"final NEES over {cfg.mc_runs} runs: mean {mean:.3g}, 95 % χ² interval [{lo:.3g}, {hi:.3g}]"]
    return stages.Stage(metrics=metrics, tables={"consistency": rows}, notes=notes)


def plan_design(cfg: Config, progress: Callable[..., Any]) -> stages.Stage:
    sig = jnp.asarray(_prior_sigma(cfg)[: bc.N_BASE])
    P0 = jnp.diag(sig**2)

    def objective(log_rates):
        F, H, Q, R = _model(cfg, jnp.exp(log_rates))
        P = bc.covariance_run(F, H, Q, R, P0)
        return jnp.log(bc.normalised_trace(P, sig) - P[2, 2] / sig[2] ** 2)  # β_U: Earth rate only, left out

    vg = jax.jit(jax.value_and_grad(objective))
    history = []

    def fun(x):
        v, g = vg(jnp.asarray(x))
        history.append(float(np.exp(v)))
        return float(v), np.asarray(g, float)

    x0 = np.log(np.array([cfg.rate_deg, cfg.rate2_deg] * 3) * DEG)
    lo, hi = (math.log(b * DEG) for b in cfg.rate_bounds_deg)
    res = scipy.optimize.minimize(
        fun, x0, jac=True, method="L-BFGS-B", bounds=[(lo, hi)] * 6, options={"maxiter": cfg.opt_iterations}
    )
    fun(res.x)
    t0, t1 = history[0], history[-1]
    rates_opt = np.exp(res.x) / DEG
    rows = [
        {"cycle_axis": a + 1, "rate1_deg_s": float(rates_opt[2 * a]), "rate2_deg_s": float(rates_opt[2 * a + 1])}
        for a in range(3)
    ]
    metrics = {"trace_initial": t0, "trace_optimised": t1, "trace_reduction": 1 - t1 / t0}
    fig = figures.line_panels(
        [figures.panel({"tr(D⁻¹PD⁻¹)": (np.arange(len(history)), history, "o-")}, "evaluation", "normalised trace")]
    )
    notes = [
        "plan optimised by L-BFGS-B on the JAX gradient of log tr(D⁻¹ P_N D⁻¹): %.4g → %.4g (%.1f %% less); rates "
        "%s °/s" % (t0, t1, 100 * metrics["trace_reduction"], ", ".join(f"{r:.3g}" for r in rates_opt))
    ]
    return stages.Stage(
        metrics=metrics, tables={"optimised_plan": rows}, figures={"plan_optimisation": fig}, notes=notes
    )


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    return stages.merge(observability(cfg, progress), consistency(cfg, progress), plan_design(cfg, progress))


STUDY = Study(
    name="imu_bench_calibration",
    description="Seed 004 B3: 24-state IMU bench calibration on a single-axis table — observability by "
    "information rank (3 cycles, time skew, temperature), NEES consistency, plan rates by gradient",
    config=Config,
    presets=PRESETS,
    claims=CLAIMS,
    assumptions=ASSUMPTIONS,
    run=run,
)
