"""Study ``capsule_robot``: a body on a rough plane driven by an internal mass — the fastest periodic
gaits under dry friction (seed 004 #1, Chernousko's lecture; spec part 1 §B5).

The lecture prints two optima of the average body speed (its ref. [7], dry friction):
``V1 = 0.545`` (velocity control; the body moves both forward and backward within a period) and
``V2 = 0.707`` (acceleration control; forward motion alternates with rest), in units extracted as
"kLgμ" — ``μ√(kgL)`` or ``√(μkgL)`` — and without the constraint set.  Without constraints the
speed is unbounded (shown here by the symmetric two-phase gait).

Here (:mod:`jaxsim.plants.capsule_robot`, :mod:`jaxsim.control.capsule_gait`): the body with exact,
event-free stick–slip; in natural units the model has no parameter left, so any optimum is a number
times ``√(μkgL)`` — the reading the study checks by the speed's exponent in ``μ``.  Constraint set
stated for V2: the stroke ``ξ ∈ [0, L]``, the relative acceleration at most ``kg/μ`` (the drive never
pushes a resting body backwards, so the body only moves forwards), braking unbounded.  Its optimum
in closed form is the three-phase gait with ``V = √(μkgL/2)``; a gradient search over *all*
admissible gaits on a grid (64 free accelerations and the period) against PSO on equal budgets finds
the same structure.  For V1 the constraint set is not identified: the natural candidate (two moving
phases, the body at rest when each period starts) tops out at ``0.5·√(μkgL)``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np

from experiments import figures, stages
from experiments.runner import Study, StudyResult, paper_facts
from jaxsim.control import capsule_gait as cg
from jaxsim.plants import capsule_robot as cr
from jaxsim.problem import Param, ParamSpace, Problem


@dataclass(frozen=True)
class Config:
    M: float = 1.0  # kg, body (assumed, spec example)
    m: float = 0.2  # kg, internal mass (assumed)
    k: float = 0.3  # Coulomb coefficient (assumed)
    L: float = 0.05  # m, stroke (assumed)
    n_steps: int = 64  # steps per period of the searched gaits
    periods: int = 3  # periods simulated; the speed is the last one's
    period0: float = 3.0  # initial period of the search, time units √(μL/(kg))
    budget_evals: int = 600  # simulations per tuner
    learning_rate: float = 0.05
    n_starts: int = 2
    n_particles: int = 32
    grid_steps: tuple[int, ...] = (64, 256, 1024, 4096)  # three-phase gait on refining grids
    mass_ratios: tuple[float, ...] = (0.05, 0.2, 0.5)  # μ for the speed's exponent in μ
    u1_grid: int = 401  # forward speeds of the velocity-control family (log grid 0.05 … 20)
    u2_values: tuple[float, ...] = (1.0, 3.0, 10.0, 100.0, 1000.0)  # return speeds (units √(kgL/μ))
    symmetric_speeds: tuple[float, ...] = (1.0, 2.0, 4.0, 8.0)  # units √(kgL/μ)
    seed: int = 0


PRESETS = {
    "quick": dict(budget_evals=300, grid_steps=(64, 256, 1024)),
    "tiny": dict(
        n_steps=16,
        periods=2,
        budget_evals=32,
        n_particles=8,
        grid_steps=(16, 64),
        u1_grid=41,
        u2_values=(1.0, 1000.0),
        symmetric_speeds=(1.0, 4.0),
    ),
}
CLAIMS, ASSUMPTIONS = paper_facts("capsule_robot")


def plant_of(cfg: Config, mu: float | None = None) -> cr.Params:
    """The assumed plant, or one with the mass ratio ``mu`` (``m`` changed, ``M + m`` kept)."""
    if mu is None:
        return cr.Params(M=cfg.M, m=cfg.m, k=cfg.k, L=cfg.L)
    total = cfg.M + cfg.m
    return cr.Params(M=(1 - mu) * total, m=mu * total, k=cfg.k, L=cfg.L)


def initial_theta(n: int) -> np.ndarray:
    """A start that moves the body a little (one braking burst per period), so gradients are not zero."""
    return 2.0 * np.cos(2 * np.pi * np.arange(n) / n)


def gait_of(cfg: Config, p: cr.Params, params: dict[str, Any]) -> tuple[jax.Array, jax.Array]:
    """``(u (N,), dt)`` of the admissible gait coded by ``params`` (``theta``, ``period`` in time units)."""
    dt = params["period"] * cr.time_unit(p) / cfg.n_steps
    return cg.bounded_acceleration_gait(params["theta"], cr.hold_acceleration(p), p.L, dt), dt


def problem_of(cfg: Config, p: cr.Params) -> Problem:
    """Maximise the average body speed (minimise −V/√(μkgL)) over admissible acceleration-control gaits."""
    space = ParamSpace(
        theta=Param(lo=-6.0, hi=6.0, init=initial_theta(cfg.n_steps)),
        period=Param(lo=0.5, hi=20.0, init=cfg.period0, log=True),
    )
    unit = cr.speed_unit(p)

    def loss(params, draw, key):
        u, dt = gait_of(cfg, p, params)
        return -cr.periodic_speed(p, u, dt, cfg.periods) / unit

    return Problem.from_loss("capsule_gait", space, loss)


def velocity_control(cfg: Config, p: cr.Params) -> tuple[list[dict], dict[str, float], dict]:
    """The resting two-phase family over (u1, u2), and the unbounded symmetric gait."""
    unit = float(cr.speed_unit(p))
    u1 = np.geomspace(0.05, 20.0, cfg.u1_grid)
    family = jax.jit(jax.vmap(lambda a, b: cg.resting_two_phase_speed(p, a, b) / unit, (0, None)))
    curves, best = {}, (-np.inf, 0.0, 0.0)
    for u2 in cfg.u2_values:
        v = np.asarray(family(jnp.asarray(u1), u2))
        curves[u2] = v
        i = int(np.argmax(v))
        if v[i] > best[0]:
            best = (float(v[i]), float(u1[i]), float(u2))
    mass_scale = float(cr.mass_speed_unit(p))
    rows = []
    for s in cfg.symmetric_speeds:
        u, dt = cg.symmetric_two_phase_gait(p, s * mass_scale, 64)
        rows.append(
            {
                "gait": "symmetric two-phase, no rest",
                "speed_mass_units": s,
                "v_over_unit": float(cr.periodic_speed(p, u, dt, 1) / unit),
            }
        )
    for u2 in cfg.u2_values:
        i = int(np.argmax(curves[u2]))
        rows.append(
            {
                "gait": f"resting two-phase, return u2 = {u2:g}",
                "speed_mass_units": float(u1[i]),
                "v_over_unit": float(curves[u2][i]),
            }
        )
    sym = [r["v_over_unit"] for r in rows[: len(cfg.symmetric_speeds)]]
    metrics = {
        "v1_resting_two_phase_over_unit": best[0],
        "v1_best_u1": best[1],
        "v1_best_u2": best[2],
        "symmetric_gait_growth": abs(sym[-1]) / max(abs(sym[0]), 1e-300),
    }
    return rows, metrics, {"u1": u1, "curves": curves}


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    p = plant_of(cfg)
    unit = float(cr.speed_unit(p))
    metrics: dict[str, float] = {}
    opt = cg.three_phase_optimum(p)
    metrics["v2_closed_form_over_unit"] = float(opt["speed"]) / unit
    speed = jax.jit(lambda u, dt: cr.periodic_speed(p, u, dt, cfg.periods))
    grid_rows = []
    for n in progress(list(cfg.grid_steps), desc="three-phase gait, refining grids", unit="grid"):
        u, dt = cg.three_phase_gait(p, n)
        grid_rows.append({"steps_per_period": n, "v_over_unit": float(speed(u, dt)) / unit})
    metrics["v2_three_phase_simulated_over_unit"] = grid_rows[-1]["v_over_unit"]
    u_same, dt_same = cg.three_phase_gait(p, cfg.n_steps)
    three_same = float(speed(u_same, dt_same)) / unit
    metrics["v2_three_phase_same_grid_over_unit"] = three_same

    mu_rows = []
    for mu in cfg.mass_ratios:
        pm = plant_of(cfg, mu)
        u, dt = cg.three_phase_gait(pm, cfg.grid_steps[-1])
        mu_rows.append(
            {
                "mu": mu,
                "v_m_s": float(cr.periodic_speed(pm, u, dt, cfg.periods)),
                "sqrt_mu_kgL": float(cr.speed_unit(pm)),
                "mu_sqrt_kgL": float(mu * np.sqrt(pm.k * pm.g * pm.L)),
            }
        )
    lo, hi = mu_rows[0], mu_rows[-1]
    metrics["speed_exponent_in_mu"] = float(np.log(hi["v_m_s"] / lo["v_m_s"]) / np.log(hi["mu"] / lo["mu"]))

    problem = problem_of(cfg, p)
    comp = stages.tune_and_compare(
        problem,
        cfg.budget_evals,
        ("gradient", "pso"),
        reference=-three_same,
        key=jax.random.PRNGKey(cfg.seed),
        learning_rate=cfg.learning_rate,
        n_starts=cfg.n_starts,
        n_particles=cfg.n_particles,
        progress=progress,
        loss_label="−V/√(μkgL) (acceleration control, exact friction)",
    )
    gait_rows, traces = [], {}
    for name, params in comp.designs.items():
        u, dt = gait_of(cfg, p, params)
        v = float(speed(u, dt)) / unit
        states = np.asarray(cr.rollout(p, jnp.tile(u, cfg.periods), dt, u[-1]))
        gait_rows.append(
            {
                "design": name,
                "v_over_unit": v,
                "period_time_units": float(params["period"]),
                "stroke_over_L": float(cg.stroke_of(u, dt) / p.L),
                "max_accel_over_kg_mu": float(cg.max_acceleration_of(u, dt) / cr.hold_acceleration(p)),
                "min_body_velocity_m_s": float(states[:, 1].min()),
            }
        )
        metrics[f"v2_{name}_over_unit"] = v
        traces[name] = (np.asarray(u), float(dt), states)
    metrics["v2_gradient_over_three_phase_same_grid"] = metrics["v2_gradient_over_unit"] / three_same
    metrics["v2_pso_over_three_phase_same_grid"] = metrics["v2_pso_over_unit"] / three_same
    states_same = np.asarray(cr.rollout(p, jnp.tile(u_same, cfg.periods), dt_same, u_same[-1]))
    traces["three-phase (closed form)"] = (np.asarray(u_same), float(dt_same), states_same)

    vel_rows, vel_metrics, family = velocity_control(cfg, p)
    metrics.update(vel_metrics)
    figs = {"gaits": _gait_figure(cfg, p, traces), "velocity_control": _velocity_figure(cfg, family, vel_rows)}
    own = stages.Stage(
        metrics=metrics,
        tables={"grid_convergence": grid_rows, "mass_ratio": mu_rows, "gaits": gait_rows, "velocity_control": vel_rows},
        figures=figs,
        notes=[
            f"speeds in units of √(μkgL) = {unit:.4g} m/s (μ = {float(cr.mass_ratio(p)):.4g}, k = {cfg.k:g}, "
            f"L = {cfg.L:g} m); gaits searched on {cfg.n_steps} steps per period, speed over the last of "
            f"{cfg.periods} periods; friction stepped exactly (stick–slip) everywhere, also inside the loss",
            "constraint set for V2 (stated, not the paper's — ref. [7] is not available): stroke ξ ∈ [0, L], "
            "relative acceleration ≤ kg/μ (the body never moves backwards), braking unbounded",
        ],
    )
    return stages.merge(own, comp)


def _gait_figure(cfg: Config, p: cr.Params, traces: dict):
    tu, unit = float(cr.time_unit(p)), float(cr.speed_unit(p))
    xi_panel, x_panel = {}, {}
    for name, (u, dt, states) in traces.items():  # states: the body over cfg.periods periods
        n = u.size
        t = np.arange(1, n + 1) * dt / tu
        xi = np.cumsum(u) * dt
        xi_panel[name] = (t, (xi - xi.min()) / p.L)
        t_all = np.arange(1, states.shape[0] + 1) * dt / tu
        x_panel[name] = (t_all, states[:, 0] / (unit * tu))
    return figures.line_panels(
        [
            figures.panel(xi_panel, "t / √(μL/kg)", "ξ / L", title="internal mass over one period"),
            figures.panel(x_panel, "t / √(μL/kg)", "x / (μL)", title=f"body over {cfg.periods} periods (from rest)"),
        ]
    )


def _velocity_figure(cfg: Config, family: dict, rows: list):
    sym = [r for r in rows if r["gait"].startswith("symmetric")]
    return figures.line_panels(
        [
            figures.panel(
                {f"return u2 = {u2:g}": (family["u1"], v) for u2, v in family["curves"].items()},
                "forward speed u1 / √(kgL/μ)",
                "V / √(μkgL)",
                title="resting two-phase velocity control",
                hline=0.545,
            ),
            figures.panel(
                {
                    "symmetric, no rest": (
                        [r["speed_mass_units"] for r in sym],
                        [abs(r["v_over_unit"]) for r in sym],
                        "o-",
                    )
                },
                "relative speed / √(kgL/μ)",
                "|V| / √(μkgL)",
                title="unconstrained: speed grows without bound",
            ),
        ]
    )


STUDY = Study(
    name="capsule_robot",
    description="Seed 004 #1: capsule robot, internal mass and dry friction — fastest gaits, V1/V2 of Chernousko",
    config=Config,
    presets=PRESETS,
    claims=CLAIMS,
    assumptions=ASSUMPTIONS,
    run=run,
)
