"""Study ``glider_course``: course control of an underwater glider with MEMS heading and rate sensors —
out along a pipeline and back to the start point (seed 004 part 4 B7, authors lost).

The paper models the course loop in Simulink, varies "the control functions and the static
characteristics of the sensors" until the glider's return to its start point is "satisfactory", and
concludes that "medium accuracy" is reachable with MEMS heading and rate sensors.  It prints the
kinematics (eq. (1)) and no number.  Here everything else is assumed (named in the paper-facts file):
the Nomoto course model with a drift angle (:mod:`jaxsim.plants.glider_course`), the MEMS error model
(gyro: turn-on bias, scale factor, angle random walk and bias instability from
:mod:`jaxsim.inertial.sensor_errors`; compass: bias, semicircular deviation, noise), and the autopilot
(:mod:`jaxsim.control.glider_autopilot`: complementary heading filter, dead reckoning with the modelled
drift, line-of-sight guidance, PD rudder law).

The mission: along the line ``η = 0`` for ``leg`` metres (dead-reckoned), turn, back along it; the miss
is the true distance from the start when the dead-reckoned along-track coordinate returns to 0.

Reported: the miss by Monte Carlo (all errors, and each error group alone: an error budget), checked
against closed forms — a constant heading error (compass bias, gyro bias through the filter) cancels
on an out-and-back leg, a semicircular deviation ``B cos ψ`` does not and gives ``miss ≈ 2·leg·|B|``;
the autopilot gains and filter crossover tuned by gradient against PSO on equal budgets for the
expected squared miss plus track keeping.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np

from experiments import figures, stages
from experiments.runner import Study, StudyResult, paper_facts
from jaxsim.control import glider_autopilot as ap
from jaxsim.core.integrators import RK4
from jaxsim.core.rotations import wrap_angle
from jaxsim.inertial.sensor_errors import GyroNoise, gyro_noise
from jaxsim.plants import glider_course as gc
from jaxsim.problem import Param, ParamSpace, Problem

DEG = np.pi / 180.0
GROUPS = ("compass bias", "compass deviation", "compass noise", "gyro bias", "gyro noise and scale", "drift model")
GAIN_NAMES = ("kp", "kd", "kc", "lookahead")


@dataclass(frozen=True)
class Config:
    leg: float = 1000.0  # m, outbound leg along the pipeline (assumed)
    dt: float = 1.0  # s, control, sensor and integration step (RK4)
    turn_time: float = 800.0  # s: mission time = 2·leg / V + turn_time (room for the turn)
    gyro_bias_deg_h: float = 50.0  # turn-on bias σ, °/h (spec: 10–100 °/h)
    gyro_bias_instability_deg_h: float = 10.0  # °/h (assumed)
    gyro_arw_deg_rt_h: float = 0.5  # °/√h (assumed)
    gyro_scale: float = 0.005  # scale-factor error σ (assumed)
    compass_bias_deg: float = 1.0  # σ (spec: compass error 1–3°)
    compass_deviation_deg: float = 1.0  # σ of each semicircular coefficient A, B (assumed)
    compass_noise_deg: float = 0.5  # white, per sample (assumed)
    drift_gain_rel: float = 0.2  # σ of the true drift gain relative to the model's (assumed)
    gains0: tuple[float, float, float, float] = (1.0, 10.0, 0.02, 30.0)  # kp, kd, kc 1/s, look-ahead m
    n_runs: int = 200  # Monte-Carlo runs per error group
    tune_scenarios: int = 16  # sensor-error draws the tuning loss averages over
    budget_evals: int = 48  # loss evaluations per tuner (each: tune_scenarios simulations)
    learning_rate: float = 0.1
    n_starts: int = 4
    n_particles: int = 8
    seed: int = 0


PRESETS = {
    "quick": dict(n_runs=64, budget_evals=24, tune_scenarios=8),
    "tiny": dict(leg=150.0, dt=2.0, n_runs=8, budget_evals=4, tune_scenarios=2, n_starts=2, n_particles=3),
}
CLAIMS, ASSUMPTIONS = paper_facts("glider_course")


def draw_errors(cfg: Config, key: jax.Array, n: int) -> dict[str, jax.Array]:
    """``n`` draws of the constant sensor errors (rad, rad/s, relative) and a noise key per draw."""
    ks = jax.random.split(key, 8)
    nrm = lambda k, s: s * jax.random.normal(k, (n,))  # noqa: E731
    return {
        "gyro_bias": nrm(ks[0], cfg.gyro_bias_deg_h * DEG / 3600),
        "gyro_scale": nrm(ks[1], cfg.gyro_scale),
        "compass_bias": nrm(ks[2], cfg.compass_bias_deg * DEG),
        "dev_a": nrm(ks[3], cfg.compass_deviation_deg * DEG),
        "dev_b": nrm(ks[4], cfg.compass_deviation_deg * DEG),
        "drift_gain": 1.0 + nrm(ks[5], cfg.drift_gain_rel),
        "noise_key": jax.random.split(ks[6], n),
    }


def n_steps(cfg: Config, p: gc.Params) -> int:
    return int(round((2.0 * cfg.leg / float(p.V) + cfg.turn_time) / cfg.dt))


def mission(cfg: Config, gains: ap.Gains, err: dict[str, jax.Array], on: jax.Array) -> dict[str, jax.Array]:
    """One out-and-back mission under the sensor errors ``err`` (one draw), each of the six error groups
    scaled by ``on (6,)`` (1 on, 0 off).  Returns the miss vector and distance (m), the RMS true
    cross-track error (m) and the true and dead-reckoned tracks ``(T, 2)``."""
    p = gc.Params()
    true_p = gc.Params(K_beta=p.K_beta * (1.0 + on[5] * (err["drift_gain"] - 1.0)))
    T = n_steps(cfg, p)
    kg, kc = jax.random.split(err["noise_key"])
    gnoise = GyroNoise(
        R=0.0, K=0.0, B=cfg.gyro_bias_instability_deg_h * DEG / 3600, N=cfg.gyro_arw_deg_rt_h * DEG / 60, Q=0.0
    )
    n_gyro = on[4] * gyro_noise(kg, gnoise, cfg.dt, T)
    n_comp = on[2] * cfg.compass_noise_deg * DEG * jax.random.normal(kc, (T,))
    b_g, s_g = on[3] * err["gyro_bias"], on[4] * err["gyro_scale"]
    c0, dev_a, dev_b = on[0] * err["compass_bias"], on[1] * err["dev_a"], on[1] * err["dev_b"]
    field = lambda x, u: lambda t, s: gc.dynamics(true_p, s, u, t)  # noqa: E731

    def step(carry, inp):
        x, nav, ret = carry
        ng, nc, k = inp
        r_m = (1.0 + s_g) * x[1] + b_g + ng
        psi_m = wrap_angle(x[0] + c0 + dev_a * jnp.sin(x[0]) + dev_b * jnp.cos(x[0]) + nc)
        nav = ap.nav_step(nav, r_m, psi_m, gains, p, cfg.dt)
        ret = ret | (nav.xi >= cfg.leg)
        psi_c = ap.los_heading(nav, jnp.where(ret, jnp.pi, 0.0), gains.lookahead)
        u = ap.rudder_command(nav, r_m, psi_c, gains)[None]
        x = RK4.step(field(x, u), k * cfg.dt, x, cfg.dt)
        return (x, nav, ret), (x[4:6], jnp.stack([nav.xi, nav.eta]), ret)

    x0 = jnp.zeros(6)
    nav0 = ap.NavState(*(jnp.zeros(()) for _ in range(4)))
    _, (true_xy, dr_xy, ret) = jax.lax.scan(
        step, (x0, nav0, jnp.asarray(False)), (n_gyro, n_comp, jnp.arange(T, dtype=float))
    )
    xi = dr_xy[:, 0]
    crossing = ret[:-1] & (xi[:-1] > 0) & (xi[1:] <= 0)
    k = jnp.argmax(crossing)
    w = xi[k] / (xi[k] - xi[k + 1])
    miss_vec = true_xy[k] + w * (true_xy[k + 1] - true_xy[k])
    return {
        "miss_vec": miss_vec,
        "miss": jnp.sqrt(miss_vec @ miss_vec + 1e-12),
        "returned": jnp.any(crossing),
        "xtrack_rms": jnp.sqrt(jnp.mean(true_xy[:, 1] ** 2)),
        "true_xy": true_xy,
        "dr_xy": dr_xy,
    }


def gains_of(cfg: Config, d: dict[str, Any]) -> ap.Gains:
    return ap.Gains(kp=d["kp"], kd=d["kd"], kc=d["kc"], lookahead=d["lookahead"])


def mission_loss(cfg: Config, d: dict[str, Any], err: dict[str, jax.Array]) -> jax.Array:
    """Squared miss + mean squared true cross-track error (m²) of one draw, all error groups on."""
    out = mission(cfg, gains_of(cfg, d), err, jnp.ones(6))
    return out["miss"] ** 2 + out["xtrack_rms"] ** 2


def problem_of(cfg: Config) -> Problem:
    g0 = dict(zip(GAIN_NAMES, cfg.gains0))
    space = ParamSpace(**{n: Param(lo=v / 10, hi=v * 10, init=v, log=True) for n, v in g0.items()})
    draws = draw_errors(cfg, jax.random.PRNGKey(cfg.seed + 1), cfg.tune_scenarios)
    return Problem.from_loss(
        "glider_course_gains", space, lambda d, draw, key: mission_loss(cfg, d, draw), scenarios=draws
    )


def monte_carlo_fn(cfg: Config) -> Callable:
    """Compiled ``(gains dict, draws, on (6,)) ->`` per-draw misses, miss vectors, RMS cross-track."""

    def one(d, err, on):
        out = mission(cfg, gains_of(cfg, d), err, on)
        return {k: out[k] for k in ("miss", "miss_vec", "xtrack_rms", "returned")}

    return jax.jit(jax.vmap(one, (None, 0, None)))


def closed_forms(cfg: Config) -> dict[str, float]:
    """Mean miss (m) of a one-way heading error of σ on each leg (``leg·σ·√(2/π)`` if it did not cancel)
    and of the semicircular deviation on an out-and-back (``2·leg·|B|``: ``2·leg·σ_B·√(2/π)``)."""
    c = np.sqrt(2.0 / np.pi)
    return {
        "deviation_mean_miss_m": 2 * cfg.leg * cfg.compass_deviation_deg * DEG * c,
        "compass_bias_uncancelled_m": 2 * cfg.leg * cfg.compass_bias_deg * DEG * c,
    }


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    mc = monte_carlo_fn(cfg)
    draws = draw_errors(cfg, jax.random.PRNGKey(cfg.seed), cfg.n_runs)
    g0 = {n: jnp.float64(v) for n, v in zip(GAIN_NAMES, cfg.gains0)}
    ref = closed_forms(cfg)
    metrics: dict[str, float] = {k: float(v) for k, v in ref.items()}
    budget_rows, results = [], {}
    cases = {"all errors": np.ones(6), **{g: np.eye(6)[i] for i, g in enumerate(GROUPS)}}
    for name, on in progress(list(cases.items()), desc="error budget", unit="group"):
        out = jax.tree_util.tree_map(np.asarray, mc(g0, draws, jnp.asarray(on)))
        results[name] = out
        m = out["miss"]
        budget_rows.append(
            {
                "errors": name,
                "mean_miss_m": float(m.mean()),
                "mean_miss_ci95_m": 1.96 * float(m.std(ddof=1)) / np.sqrt(m.size),
                "rms_miss_m": float(np.sqrt(np.mean(m**2))),
                "p95_miss_m": float(np.percentile(m, 95)),
                "miss_pct_of_route": 100 * float(m.mean()) / (2 * cfg.leg),
                "rms_cross_track_m": float(np.sqrt(np.mean(out["xtrack_rms"] ** 2))),
                "returned_fraction": float(out["returned"].mean()),
            }
        )
    row = {r["errors"]: r for r in budget_rows}
    metrics["all_errors_mean_miss_m"] = row["all errors"]["mean_miss_m"]
    metrics["all_errors_miss_pct_of_route"] = row["all errors"]["miss_pct_of_route"]
    metrics["all_returned_fraction"] = min(r["returned_fraction"] for r in budget_rows)
    metrics["deviation_only_mean_miss_m"] = row["compass deviation"]["mean_miss_m"]
    metrics["deviation_miss_over_closed_form"] = row["compass deviation"]["mean_miss_m"] / ref["deviation_mean_miss_m"]
    metrics["compass_bias_cancellation_ratio"] = row["compass bias"]["mean_miss_m"] / ref["compass_bias_uncancelled_m"]
    # the deviation's miss is 2·leg·B: its own miss vector against B draw by draw
    b = np.asarray(draws["dev_b"])
    metrics["deviation_miss_vs_2legB_corr"] = float(
        np.corrcoef(results["compass deviation"]["miss_vec"][:, 1], b)[0, 1]
    )

    problem = problem_of(cfg)
    comp = stages.tune_and_compare(
        problem,
        cfg.budget_evals * cfg.tune_scenarios,
        ("gradient", "pso"),
        key=jax.random.PRNGKey(cfg.seed + 2),
        learning_rate=cfg.learning_rate,
        n_starts=cfg.n_starts,
        n_particles=cfg.n_particles,
        progress=progress,
        loss_label="E[miss² + cross-track²], m²",
    )
    designs = comp.with_baseline("hand", g0)
    design_rows = []
    for name, d in designs.items():  # re-scored on the fresh Monte-Carlo draws (not the tuning ones)
        out = jax.tree_util.tree_map(np.asarray, mc(d, draws, jnp.ones(6)))
        loss = float(np.mean(out["miss"] ** 2 + out["xtrack_rms"] ** 2))
        design_rows.append(
            {
                "design": name,
                **{n: float(d[n]) for n in GAIN_NAMES},
                "mc_loss_m2": loss,
                "mean_miss_m": float(out["miss"].mean()),
                "rms_cross_track_m": float(np.sqrt(np.mean(out["xtrack_rms"] ** 2))),
            }
        )
    dr = {r["design"]: r for r in design_rows}
    metrics["tuned_gradient_over_hand_mc_loss"] = dr["gradient"]["mc_loss_m2"] / dr["hand"]["mc_loss_m2"]
    metrics["tuned_gradient_over_pso_mc_loss"] = dr["gradient"]["mc_loss_m2"] / dr["pso"]["mc_loss_m2"]
    fig = _figure(cfg, draws, g0)
    own = stages.Stage(
        metrics=metrics,
        tables={"error_budget": budget_rows, "designs": design_rows},
        figures={"missions": fig},
        notes=[
            f"{cfg.n_runs} Monte-Carlo draws per error group (the same draws for every group and design); "
            "the designs are re-scored on these draws, not on the tuning draws",
            "closed forms: a constant heading error cancels on an out-and-back leg; a semicircular compass "
            "deviation B·cos ψ gives a miss of 2·leg·|B| across the track",
        ],
    )
    return stages.merge(own, comp)


def _figure(cfg: Config, draws: dict, g0: dict):
    one = jax.jit(lambda err, on: mission(cfg, gains_of(cfg, g0), err, on))
    plt = figures._plt()
    fig, axes = plt.subplots(1, 2, figsize=(14, 5))
    for i in range(min(5, cfg.n_runs)):
        err = jax.tree_util.tree_map(lambda a: a[i], draws)
        out = jax.tree_util.tree_map(np.asarray, one(err, jnp.ones(6)))
        axes[0].plot(out["true_xy"][:, 0], out["true_xy"][:, 1], lw=0.8, label=f"draw {i}: true")
        axes[0].plot(out["dr_xy"][:, 0], out["dr_xy"][:, 1], "k:", lw=0.6)
        axes[1].plot(out["true_xy"][-200:, 0], out["true_xy"][-200:, 1], lw=0.8)
        axes[1].plot(*out["miss_vec"], "o", ms=5)
    axes[0].set(title="out along the pipeline and back (dotted: dead reckoning)", xlabel="ξ, m", ylabel="η, m")
    axes[1].plot(0, 0, "k*", ms=12, label="start")
    axes[1].set(title="near the start: true tracks and the misses", xlabel="ξ, m", ylabel="η, m")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


STUDY = Study(
    name="glider_course",
    description="Seed 004 part 4 B7: underwater glider course control with MEMS sensors, return-to-start miss",
    config=Config,
    presets=PRESETS,
    claims=CLAIMS,
    assumptions=ASSUMPTIONS,
    run=run,
)
