"""Study ``station_slew``: fuel-optimal 180° yaw slew of a large orbital station (seed 004 #5, Prutko &
Atroshenkov; spec ``seed004_part2.md`` §2.6).

Plant :mod:`jaxsim.plants.orbital_station` (rigid body in the orbital frame, quaternions,
gravity-gradient torque, reaction jets), problem pieces :mod:`jaxsim.control.station_slew`, CasADi
transcription :mod:`optim.casadi_slew`.  The paper flew two optimal slews of 5400 s (a local minimum
forward, the global minimum in reverse: 6.42 and 4.61 kg) against 50.78 kg for a standard 3000-s slew
(simulation), and tracked them on board by the quaternion guidance law (1).  Every mass property is
assumed (the paper gives none), so only the fuel *ratios* are compared.  Here:

1. **IPOPT multi-start** (CasADi, direct multiple shooting): the distinct local minima of the smoothed
   fuel.
2. **JAX shooting multi-start**, vmapped: SQP from random torques.  The same discrete problem is
   written twice, so every minimum found by either solver is confirmed by the other: each IPOPT
   minimum is a KKT point of the JAX problem with the same cost; IPOPT started at each JAX minimum
   returns it.  The least of the pooled minima is the
   global candidate, the next the "local" slew.
3. **Standard slew**: the inverse-dynamics torque of a cycloidal eigen-axis yaw in 3000 s, its fuel,
   and the fuel ratios against the paper's.
4. **Guidance law (1)**: commands from quaternion nodes sampled every Δt along the global optimum,
   against the optimal attitude and rate between the nodes — for both readings of the garbled Δt
   (5 s or 55 s).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from functools import partial
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np

from experiments import figures, stages
from experiments.runner import Study, StudyResult, paper_facts
from jaxsim.control import station_slew as ss
from jaxsim.core.rotations import euler_from_rotation, rotation_from_quat
from jaxsim.plants import orbital_station as st
from optim import casadi_slew


@dataclass(frozen=True)
class Config:
    horizon: float = 5400.0  # s (paper, Table 1)
    yaw_deg: float = 180.0  # paper
    n_intervals: int = 24  # piecewise-constant torque intervals (225 s each)
    substeps: int = 4  # RK4 steps per interval
    eps: float = 0.5  # smoothing of |ũ| (scaled torque; the optimum's |ũ| reaches ≈ 20)
    standard_duration: float = 3000.0  # s (paper, Table 1)
    ipopt_starts: int = 8  # the first from zero torque, the others random
    jax_starts: int = 32  # random starts of the vmapped SQP
    jax_iters: int = 200
    start_scale: float = 3.0  # σ of the random starting torques (scaled)
    guidance_dt: tuple[float, ...] = (5.0, 55.0)  # s: the garbled "55t с" read both ways
    dense_step: float = 1.0  # s, the optimal trajectory's sampling for the guidance check
    seed: int = 0


def problem(cfg: Config) -> ss.SlewProblem:
    return ss.SlewProblem(st.StationParams(), cfg.horizon, cfg.yaw_deg, cfg.n_intervals, cfg.substeps, cfg.eps)


def distinct_minima(fuels: np.ndarray, rel: float = 1e-6) -> list[int]:
    """Indices of the distinct values of ``fuels`` (first occurrence, ascending; ``rel`` apart)."""
    order = np.argsort(fuels)
    keep: list[int] = []
    for i in order:
        if not keep or fuels[i] > fuels[keep[-1]] * (1 + rel):
            keep.append(int(i))
    return keep


def _kg(u: Any, prob: ss.SlewProblem) -> float:
    return float(ss.fuel_kg(jnp.asarray(u), prob))


def ipopt_stage(cfg: Config, prob: ss.SlewProblem) -> stages.Stage:
    """IPOPT from ``ipopt_starts`` starts (the first zero torque); ``data``: its distinct minima."""
    rng = np.random.default_rng(cfg.seed)
    starts = [None] + [rng.normal(0.0, cfg.start_scale, (cfg.n_intervals, 3)) for _ in range(cfg.ipopt_starts - 1)]
    runs = casadi_slew.solve_many(prob, starts)
    ok = [r for r in runs if r["status"] == "Solve_Succeeded"]
    minima = [ok[i] for i in distinct_minima(np.array([r["fuel"] for r in ok]))]
    rows = [
        {
            "start": k,
            "status": r["status"],
            "fuel_smoothed_scaled": r["fuel"],
            "fuel_kg": _kg(r["u"], prob),
            "iterations": r["iterations"],
            "wall_s": r["wall_s"],
        }
        for k, r in enumerate(runs)
    ]
    metrics = {
        "ipopt_solved_fraction": len(ok) / len(runs),
        "ipopt_distinct_minima": float(len(minima)),
        "ipopt_median_wall_s": float(np.median([r["wall_s"] for r in runs])),
    }
    return stages.Stage(
        metrics=metrics,
        tables={"ipopt_starts": rows},
        notes=[
            f"IPOPT from {len(runs)} starts: {len(ok)} solved, {len(minima)} distinct minima, fuel "
            + ", ".join(f"{_kg(r['u'], prob):.3f} kg" for r in minima)
        ],
        data=minima,
    )


def jax_stage(cfg: Config, prob: ss.SlewProblem, ipopt_minima: list[dict[str, Any]]) -> stages.Stage:
    """The vmapped JAX SQP from random starts, and the cross-checks: each IPOPT minimum is a KKT point
    of the JAX problem with the same cost, and IPOPT started at each JAX minimum returns it.  ``data``:
    the pooled distinct minima (IPOPT's solutions), least fuel first."""
    key = jax.random.PRNGKey(cfg.seed)
    starts = cfg.start_scale * jax.random.normal(key, (cfg.jax_starts, cfg.n_intervals, 3))
    batch = jax.jit(jax.vmap(lambda u: ss.shoot(u, prob, iters=cfg.jax_iters)))
    t0 = time.perf_counter()
    out = jax.block_until_ready(batch(starts))
    wall = time.perf_counter() - t0
    fuel, u = np.asarray(out["fuel"]), np.asarray(out["u"])
    err = np.abs(np.asarray(out["error"])).max(axis=1)
    conv = err < 1e-8
    rows = [
        {"start": k, "fuel_smoothed_scaled": float(f), "terminal_error": float(e), "converged": bool(c)}
        for k, (f, e, c) in enumerate(zip(fuel, err, conv))
    ]
    kkt = jax.jit(jax.vmap(lambda u: ss.kkt_residuals(u, prob)))(jnp.stack([jnp.asarray(r["u"]) for r in ipopt_minima]))
    kkt = {k: np.asarray(v) for k, v in kkt.items()}
    diffs = [abs(float(f) / r["fuel"] - 1) for f, r in zip(kkt["fuel"], ipopt_minima)]
    ok = np.flatnonzero(conv)
    jax_minima = [int(ok[i]) for i in distinct_minima(fuel[ok])] if ok.size else []
    nodes = [np.asarray(ss.rollout(jnp.asarray(u[i]), prob)) for i in jax_minima]
    confirmed = casadi_slew.solve_many(prob, [u[i] for i in jax_minima], states=nodes)
    for i, r in zip(jax_minima, confirmed):
        diffs.append(abs(float(fuel[i]) / r["fuel"] - 1) if r["status"] == "Solve_Succeeded" else np.inf)
    pooled = list(ipopt_minima) + [r for r in confirmed if r["status"] == "Solve_Succeeded"]
    pooled = [pooled[i] for i in distinct_minima(np.array([r["fuel"] for r in pooled]))]
    metrics: dict[str, float] = {
        "jax_converged_fraction": float(conv.mean()),
        "jax_distinct_minima": float(len(jax_minima)),
        "jax_wall_s_with_compile": wall,
        "cross_check_rel_diff_max": float(max(diffs)),
        "ipopt_minima_terminal_error_max": float(kkt["error"].max()),
        "ipopt_minima_stationarity_max": float(kkt["stationarity"].max()),
        "distinct_minima": float(len(pooled)),
        "ipopt_found_global": float(abs(ipopt_minima[0]["fuel"] / pooled[0]["fuel"] - 1) < 1e-6),
    }
    if jax_minima:
        metrics["jax_found_global"] = float(abs(fuel[jax_minima[0]] / pooled[0]["fuel"] - 1) < 1e-6)
    for name, r in zip(("global", "local"), pooled):
        metrics[f"fuel_kg_{name}"] = _kg(r["u"], prob)
        metrics[f"fuel_smoothed_{name}"] = r["fuel"]
    notes = [
        f"JAX SQP, {cfg.jax_starts} random starts vmapped, {cfg.jax_iters} iterations: "
        f"{int(conv.sum())} converged (terminal error < 1e-8), {len(jax_minima)} distinct minima, "
        f"{wall:.1f} s with compilation",
        f"IPOPT's minima in the JAX problem: terminal error ≤ {metrics['ipopt_minima_terminal_error_max']:.1e}, "
        f"stationarity ≤ {metrics['ipopt_minima_stationarity_max']:.1e}; IPOPT from the JAX minima returns them; "
        f"costs agree to {metrics['cross_check_rel_diff_max']:.1e} (relative)",
        f"{len(pooled)} distinct minima in all, fuel " + ", ".join(f"{_kg(r['u'], prob):.3f} kg" for r in pooled),
    ]
    return stages.Stage(metrics=metrics, tables={"jax_starts": rows}, notes=notes, data=pooled)


def standard_stage(cfg: Config, prob: ss.SlewProblem, metrics: dict[str, float]) -> stages.Stage:
    """The standard slew's fuel and the fuel ratios; ``data``: its torque history ``(t, u)``."""
    history = jax.jit(ss.standard_slew_history, static_argnums=(0, 1, 2))(
        prob.params, cfg.standard_duration, cfg.yaw_deg
    )
    kg = float(ss.standard_slew_fuel_kg(*history, prob.params))
    out = {"fuel_kg_standard": kg}
    for name in ("global", "local"):
        if f"fuel_kg_{name}" in metrics:
            out[f"fuel_ratio_standard_to_{name}"] = kg / metrics[f"fuel_kg_{name}"]
    if "fuel_kg_local" in metrics:
        out["fuel_ratio_local_to_global"] = metrics["fuel_kg_local"] / metrics["fuel_kg_global"]
    rows = [{"slew": "standard (cycloidal eigen-axis yaw)", "time_s": cfg.standard_duration, "fuel_kg": kg}]
    rows += [
        {"slew": f"optimal, {name} minimum", "time_s": cfg.horizon, "fuel_kg": metrics[f"fuel_kg_{name}"]}
        for name in ("global", "local")
        if f"fuel_kg_{name}" in metrics
    ]
    return stages.Stage(metrics=out, tables={"fuel": rows}, data=history)


def torque_rows(cfg: Config, prob: ss.SlewProblem, minima: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The optimal torque histories in N·m, one row per interval and minimum."""
    width = cfg.horizon / cfg.n_intervals
    return [
        {
            "minimum": name,
            "t_start_s": k * width,
            "t_end_s": (k + 1) * width,
            **{f"u_{ax}_Nm": float(v) * prob.torque_scale() for ax, v in zip("xyz", uk)},
        }
        for name, r in zip(("global", "local"), minima)
        for k, uk in enumerate(np.asarray(r["u"]))
    ]


def attitude_history(u: jax.Array, prob: ss.SlewProblem, steps_per_interval: int) -> tuple[np.ndarray, np.ndarray]:
    """SI states ``(M, 7)`` (rate in rad/s) and zyx Euler angles ``(M, 3)`` (deg) of the dense trajectory."""
    xs, euler = _dense_si(u, prob, steps_per_interval)
    return np.asarray(xs), np.degrees(np.unwrap(np.asarray(euler), axis=0))


@partial(jax.jit, static_argnums=(1, 2))
def _dense_si(u: jax.Array, prob: ss.SlewProblem, steps_per_interval: int) -> tuple[jax.Array, jax.Array]:
    xs = ss.trajectory(u, prob, steps_per_interval)
    xs = xs.at[:, 4:].divide(prob.horizon)
    return xs, jax.vmap(lambda q: euler_from_rotation(rotation_from_quat(q)))(xs[:, :4])


_guidance_error = jax.jit(ss.guidance_error, static_argnums=(1, 2, 3))


def guidance_stage(cfg: Config, prob: ss.SlewProblem, minima: list[dict[str, Any]]) -> stages.Stage:
    interval = cfg.horizon / cfg.n_intervals
    spi = int(round(interval / cfg.dense_step))
    dense_step = interval / spi
    metrics, rows, panels = {}, [], []
    histories = {name: attitude_history(jnp.asarray(r["u"]), prob, spi) for name, r in zip(("global", "local"), minima)}
    t = np.arange(cfg.n_intervals * spi + 1) * dense_step
    for name, (_, euler) in histories.items():
        metrics[f"max_abs_roll_deg_{name}"] = float(np.max(np.abs(euler[:, 0])))
        metrics[f"max_abs_pitch_deg_{name}"] = float(np.max(np.abs(euler[:, 1])))
    states = histories["global"][0]
    for dt in cfg.guidance_dt:
        every = int(round(dt / dense_step))
        if every < 1 or abs(every * dense_step - dt) > 1e-9 * dt:
            raise ValueError(
                f"guidance_dt: {dt:g} s is not a multiple of the trajectory's step {dense_step:g} s "
                f"(dense_step={cfg.dense_step:g} rounded to divide the {interval:g}-s intervals)"
            )
        e = _guidance_error(jnp.asarray(states), dense_step, every, prob.params.orbit_rate)
        tag = f"{dt:g}".replace(".", "p")
        metrics[f"guidance_angle_deg_dt{tag}"] = float(np.degrees(e["angle_rad"]))
        metrics[f"guidance_rate_deg_s_dt{tag}"] = float(np.degrees(e["rate_rad_s"]))
        rows.append(
            {
                "node_interval_s": every * dense_step,
                "max_attitude_error_deg": metrics[f"guidance_angle_deg_dt{tag}"],
                "max_rate_error_deg_s": metrics[f"guidance_rate_deg_s_dt{tag}"],
            }
        )
    for name, (_, euler) in histories.items():
        panels.append(
            figures.panel(
                {"roll φ": (t, euler[:, 0]), "pitch θ": (t, euler[:, 1]), "yaw ψ": (t, euler[:, 2])},
                "t, s",
                "attitude in the orbital frame, deg",
                title=f"{name} minimum ({metrics.get(f'max_abs_roll_deg_{name}', 0):.0f}° largest roll)",
            )
        )
    return stages.Stage(
        metrics=metrics,
        tables={"guidance_law": rows},
        figures={"attitude": figures.line_panels(panels)} if panels else {},
        notes=[
            f"guidance law (1) on the global optimum, nodes every {r['node_interval_s']:g} s: attitude within "
            f"{r['max_attitude_error_deg']:.2e}°, rate within {r['max_rate_error_deg_s']:.2e} °/s"
            for r in rows
        ],
    )


def torque_figure(cfg: Config, prob: ss.SlewProblem, minima: list[dict[str, Any]], standard: Any) -> Any:
    scale = prob.torque_scale()
    edges = np.arange(cfg.n_intervals + 1) * cfg.horizon / cfg.n_intervals
    panels = []
    for name, r in zip(("global", "local"), minima):
        u = np.asarray(r["u"]) * scale / 1e3
        steps = np.repeat(edges, 2)[1:-1]  # piecewise-constant: each value drawn over its interval
        lines = {f"u_{ax}": (steps, np.repeat(u[:, i], 2)) for i, ax in enumerate("xyz")}
        panels.append(figures.panel(lines, "t, s", "jet torque, kN·m", title=f"{name} minimum"))
    t, u = (np.asarray(a)[::20] for a in standard)
    panels.append(
        figures.panel(
            {f"u_{ax}": (t, u[:, i] / 1e3) for i, ax in enumerate("xyz")},
            "t, s",
            "jet torque, kN·m",
            title="standard slew",
        )
    )
    return figures.line_panels(panels)


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    if cfg.ipopt_starts < 1:
        raise ValueError(f"ipopt_starts: need at least 1, got {cfg.ipopt_starts}")
    if cfg.jax_starts < 1:
        raise ValueError(f"jax_starts: need at least 1, got {cfg.jax_starts}")
    prob = problem(cfg)
    bar = progress(total=4, desc="station slew", unit="stage") if progress else None

    def tick() -> None:
        if bar:
            bar.update(1)

    ipopt = ipopt_stage(cfg, prob)
    tick()
    if not ipopt.data:
        raise RuntimeError(f"station_slew: IPOPT solved none of its {cfg.ipopt_starts} starts")
    jaxs = jax_stage(cfg, prob, ipopt.data)
    tick()
    minima = jaxs.data
    standard = standard_stage(cfg, prob, jaxs.metrics)
    tick()
    guide = guidance_stage(cfg, prob, minima)
    tick()
    if bar:
        bar.close()
    return stages.merge(
        ipopt,
        jaxs,
        standard,
        guide,
        stages.Stage(
            figures={"torques": torque_figure(cfg, prob, minima, standard.data)},
            tables={"optimal_torques": torque_rows(cfg, prob, minima)},
        ),
    )


CLAIMS, ASSUMPTIONS = paper_facts("station_slew")

STUDY = Study(
    name="station_slew",
    description="Seed 004 #5: fuel-optimal 180° yaw slew of an orbital station — IPOPT and vmapped JAX "
    "shooting multi-start (local vs global minima), fuel against a standard slew, the quaternion guidance law",
    config=Config,
    presets={
        "quick": dict(ipopt_starts=4, jax_starts=16),
        "tiny": dict(n_intervals=12, substeps=4, ipopt_starts=3, jax_starts=4, jax_iters=120, dense_step=2.5),
    },
    claims=CLAIMS,
    assumptions=ASSUMPTIONS,
    run=run,
)
