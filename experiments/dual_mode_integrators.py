"""Study ``dual_mode_integrators``: dual-mode control of a triple integrator with a bounded input and
a bounded disturbance (seed 004 #31, Ahi, Adelipour, Haeri; spec seed004_part3 §2.10).

* Plant :mod:`jaxsim.plants.integrator_chain` (n = 3, |u| ≤ u_m, |d| ≤ d_m, a sinusoidal d).
* Mode 1 (outside the set): nested saturated feedback (6) with the linear ESO's disturbance
  estimate (:mod:`jaxsim.control.nested_saturation`, :mod:`jaxsim.estimation.extended_state_observer`).
* Mode 2 (inside): ``u = −d̂ − Kx`` with K the LQR gain (SciPy CARE) and the set ``{xᵀPx ≤ c}`` the largest LQR
  level set on which ``|Kx| ≤ u_m − d_m`` — the stated stand-in for the paper's LMI (Kothare-type)
  RPI set, which needs an SDP solver.  Switching law (10) on the measured state.
* Tuning: NSF slopes k₁…k₃ and the ESO bandwidth ω_o (zones L_i from (7) held tight, so the design
  constraints hold by construction) for a smooth surrogate of the settling time (time with ‖x‖
  above the tolerance, sigmoid of temperature ``temp``) over a few initial states; gradient (Adam
  through the rollout) vs PSO on equal budgets (a gradient counted as ``grad_cost`` simulations).
* Monte Carlo over initial states: exact settling times of NSF alone and of the dual scheme with the
  tuned parameters, the paired difference with a 95 % interval (the paper's Fig. 1 claim).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np
import optax
import scipy.linalg

from experiments import figures, stages
from experiments.runner import Study, StudyResult, paper_facts
from jaxsim.control import nested_saturation as ns
from jaxsim.estimation import extended_state_observer as eso
from jaxsim.plants import integrator_chain as ic
from optim.pso import pso
from optim.tune import tune


@dataclass(frozen=True)
class Config:
    u_m: float = 1.0  # assumed (spec: "e.g. u_m = 1, d_m = 0.2")
    d_m: float = 0.2
    d_omega: float = 0.2  # rad/s, d(t) = d_m sin(d_omega t + d_phase) (assumed)
    d_phase: float = 0.3
    f: float = 2.0  # (7): M_i = L_{i+1}/f
    k0: tuple[float, float, float] = (0.1, 0.3, 1.0)  # hand design of the NSF slopes (start of tuning)
    omega_o0: float = 5.0  # ESO bandwidth of the hand design, rad/s
    q_lqr: float = 1.0  # LQR weights Q = q·I, R = r (assumed)
    r_lqr: float = 1.0
    dt: float = 0.01
    t_final: float = 40.0
    tol: float = 0.05  # ‖x‖ settling tolerance
    temp: float = 1.0  # sigmoid temperature (in log ‖x‖) of the smooth settling time
    tune_states: tuple[tuple[float, float, float], ...] = ((3.0, 0.0, 0.0), (-2.0, 1.5, 0.0), (0.0, -1.0, 1.0))
    k_lo: float = 0.02  # PSO box for k_i and ω_o
    k_hi: float = 3.0
    wo_lo: float = 1.0
    wo_hi: float = 20.0
    grad_steps: int = 60
    grad_lr: float = 0.2
    grad_cost: float = 3.0  # loss evaluations per gradient (assumed) for the equal budget
    pso_particles: int = 12
    pso_span: float = 4.0  # PSO box in θ (sigmoid coordinates): ±4 covers 1.8–98.2 % of each log range
    n_mc: int = 256  # Monte-Carlo initial states, uniform in the box below
    x0_box: tuple[float, float, float] = (4.0, 2.0, 1.0)
    seed: int = 0


def _box(cfg: Config) -> tuple[jax.Array, jax.Array]:
    return jnp.log(jnp.array([cfg.k_lo] * 3 + [cfg.wo_lo])), jnp.log(jnp.array([cfg.k_hi] * 3 + [cfg.wo_hi]))


def physical(cfg: Config, theta: jax.Array) -> jax.Array:
    """Unconstrained ``θ`` (4,) → ``[k1, k2, k3, ω_o]`` inside the box (log-uniform, sigmoid)."""
    lo, hi = _box(cfg)
    return jnp.exp(lo + (hi - lo) * jax.nn.sigmoid(theta))


def unconstrained(cfg: Config, values: Any) -> jax.Array:
    """Inverse of :func:`physical`."""
    lo, hi = _box(cfg)
    s = (jnp.log(jnp.asarray(values, dtype=float)) - lo) / (hi - lo)
    return jnp.log(s / (1.0 - s))


def _theta_to(cfg: Config, theta: jax.Array) -> tuple[jax.Array, jax.Array, jax.Array]:
    """``θ`` → ``(k, L, ESO gains)``; L from (7) held tight."""
    v = physical(cfg, theta)
    k = v[:3]
    return k, ns.constrained_levels(k, cfg.u_m, cfg.d_m, cfg.f), eso.bandwidth_gains(v[3], 3)


def linear_mode(cfg: Config) -> tuple[jax.Array, jax.Array, jax.Array]:
    """``(K, P, c)``: LQR gain, Riccati matrix, level of the invariant set."""
    a, b = (np.asarray(m) for m in ic.matrices(3))
    # SciPy's CARE: a 3×3 solve once per run (the toolkit's differentiable solver compiles for seconds
    # and no gradient is taken through this set)
    p = scipy.linalg.solve_continuous_are(a, b, cfg.q_lqr * np.eye(3), cfg.r_lqr * np.eye(1))
    gain = jnp.asarray(b.T @ p / cfg.r_lqr)[0]
    p = jnp.asarray(p)
    return gain, p, ns.lqr_level(gain, p, cfg.u_m, cfg.d_m)


def rollout(cfg: Config, theta: jax.Array, x0: jax.Array, dual: bool, lin: Any) -> dict[str, jax.Array]:
    """Closed loop (plant + ESO, RK4 at ``dt``, control held over a step): ``norm`` ‖x(t)‖, ``u``,
    ``inside`` (the switch's state), ``d_err`` (d − d̂)."""
    k, levels, g = _theta_to(cfg, theta)
    gain, p, level = lin
    plant = ic.Params(u_m=cfg.u_m, d_m=cfg.d_m)
    n_steps = int(round(cfg.t_final / cfg.dt))

    def dist(t: jax.Array) -> jax.Array:
        return cfg.d_m * jnp.sin(cfg.d_omega * t + cfg.d_phase)

    def f(t: jax.Array, z: jax.Array, u: jax.Array) -> jax.Array:
        x, xh = z[:3], z[3:]
        ua = jnp.clip(u, -cfg.u_m, cfg.u_m)
        return jnp.concatenate([ic.dynamics(plant, x, jnp.stack([u, dist(t)]), t), eso.derivative(g, xh, x[0], ua)])

    def step(z: jax.Array, t: jax.Array) -> tuple[jax.Array, dict[str, jax.Array]]:
        x, dh = z[:3], z[6]
        if dual:
            u, inside = ns.dual_control(k, levels, gain, p, level, x, dh, cfg.u_m)
        else:
            u, inside = ns.nsf_control(k, levels, x, dh, cfg.u_m), jnp.array(False)
        h = cfg.dt
        k1 = f(t, z, u)
        k2 = f(t + h / 2, z + h / 2 * k1, u)
        k3 = f(t + h / 2, z + h / 2 * k2, u)
        k4 = f(t + h, z + h * k3, u)
        zn = z + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        return zn, {"norm": jnp.linalg.norm(zn[:3]), "u": u, "inside": inside, "d_err": dist(t + h) - zn[6]}

    z0 = jnp.concatenate([x0, jnp.zeros(4)]).at[3].set(x0[0])  # ESO starts at the measured x1
    _, out = jax.lax.scan(step, z0, cfg.dt * jnp.arange(n_steps))
    return out


def settling_time(cfg: Config, norm: jax.Array) -> jax.Array:
    """Exact: end of the last step with ‖x‖ > tol (``t_final`` if it never settles; 0 if never out)."""
    idx = jnp.arange(norm.shape[0])
    last = jnp.max(jnp.where(norm > cfg.tol, idx, -1))
    return (last + 1) * cfg.dt


def smooth_settling(cfg: Config, norm: jax.Array) -> jax.Array:
    """Time spent with ‖x‖ above ``tol``, the step replaced by a sigmoid of ``log(‖x‖/tol)/temp`` (in
    log scale, so that runs far from settling still have a gradient)."""
    return cfg.dt * jnp.sum(jax.nn.sigmoid(jnp.log(norm / cfg.tol) / cfg.temp))


def tuning_loss(cfg: Config, lin: Any) -> Callable[[jax.Array], jax.Array]:
    states = jnp.asarray(cfg.tune_states)

    def loss(theta: jax.Array) -> jax.Array:
        ts = jax.vmap(lambda x0: smooth_settling(cfg, rollout(cfg, theta, x0, False, lin)["norm"]))(states)
        return jnp.mean(ts)

    return loss


def tuning_stage(cfg: Config, lin: Any) -> tuple[stages.Stage, dict[str, jax.Array]]:
    loss = tuning_loss(cfg, lin)
    theta0 = unconstrained(cfg, [*cfg.k0, cfg.omega_o0])
    n_scen = len(cfg.tune_states)
    g_res = tune(
        loss,
        theta0,
        optimizer=optax.adam(cfg.grad_lr),
        steps=cfg.grad_steps,
        sims_per_eval=n_scen,
        grad_cost=cfg.grad_cost,
    )
    budget_evals = int(cfg.grad_steps * cfg.grad_cost)
    n_iters = max(1, math.ceil(budget_evals / cfg.pso_particles))
    lo, hi = -cfg.pso_span * jnp.ones(4), cfg.pso_span * jnp.ones(4)
    p_res = pso(
        loss,
        lo,
        hi,
        n_particles=cfg.pso_particles,
        n_iters=n_iters,
        key=jax.random.PRNGKey(cfg.seed),
        sims_per_eval=n_scen,
    )
    theta_g, theta_p = jnp.asarray(g_res.params), jnp.asarray(p_res.params)
    designs = {"hand": theta0, "gradient": theta_g, "pso": theta_p}
    loss_j = jax.jit(loss)
    rows = []
    for name, th in designs.items():
        k, levels, g = _theta_to(cfg, th)
        res = ns.design_residuals(k, levels, cfg.u_m, cfg.d_m, cfg.f)
        rows.append(
            {
                "design": name,
                "k1": float(k[0]),
                "k2": float(k[1]),
                "k3": float(k[2]),
                "L1": float(levels[0]),
                "L2": float(levels[1]),
                "L3": float(levels[2]),
                "omega_o": float(physical(cfg, th)[3]),
                "smooth_settling_s": float(loss_j(th)),
                "max_constraint_residual": float(jnp.max(res)),
            }
        )
    by = {r["design"]: r for r in rows}
    metrics = {
        "tune_hand_smooth_s": by["hand"]["smooth_settling_s"],
        "tune_gradient_smooth_s": by["gradient"]["smooth_settling_s"],
        "tune_pso_smooth_s": by["pso"]["smooth_settling_s"],
        "tune_gradient_over_pso": by["gradient"]["smooth_settling_s"] / by["pso"]["smooth_settling_s"],
        "tune_gradient_sims": float(g_res.n_sims),
        "tune_pso_sims": float(p_res.n_sims),
        "tune_max_constraint_residual": max(r["max_constraint_residual"] for r in rows),
    }
    hist = {
        "gradient": (np.asarray(g_res.history.sims), np.asarray(g_res.history.best_loss)),
        "pso": (np.asarray(p_res.history.sims), np.asarray(p_res.history.best_loss)),
    }
    fig = figures.line_panels(
        [figures.panel(hist, "simulations", "smooth settling time, s", title="NSF + ESO tuning, equal budgets")]
    )
    note = (
        f"tuning (k₁, k₂, k₃, ω_o; L from (7) held tight, f = {cfg.f:g}) over {n_scen} initial states: hand "
        f"{metrics['tune_hand_smooth_s']:.2f} s → gradient {metrics['tune_gradient_smooth_s']:.2f} s "
        f"({int(g_res.n_sims)} sims, a gradient counted as {cfg.grad_cost:g}), "
        f"PSO {metrics['tune_pso_smooth_s']:.2f} s "
        f"({int(p_res.n_sims)} sims, {cfg.pso_particles} particles × {n_iters} iterations); wall "
        f"{g_res.wall_s:.1f} s vs {p_res.wall_s:.1f} s"
    )
    return stages.Stage(metrics=metrics, tables={"designs": rows}, figures={"tuning": fig}, notes=[note]), designs


def monte_carlo_stage(cfg: Config, lin: Any, theta: jax.Array) -> stages.Stage:
    key = jax.random.PRNGKey(cfg.seed + 1)
    box = jnp.asarray(cfg.x0_box)
    x0s = jax.random.uniform(key, (cfg.n_mc, 3), minval=-box, maxval=box)
    x0s = x0s.at[0].set(jnp.asarray(cfg.tune_states[0]))  # run 0: the trajectory of the figure

    def both(x0: jax.Array) -> dict[str, jax.Array]:
        nsf = rollout(cfg, theta, x0, False, lin)
        dual = rollout(cfg, theta, x0, True, lin)
        ins = dual["inside"]
        first_in = jnp.argmax(ins)
        exits = jnp.sum(ins[:-1] & ~ins[1:])
        return {
            "ts_nsf": settling_time(cfg, nsf["norm"]),
            "ts_dual": settling_time(cfg, dual["norm"]),
            "switch_t": jnp.where(jnp.any(ins), (first_in + 1) * cfg.dt, jnp.inf),
            "exits": exits,
            "u_max": jnp.max(jnp.abs(dual["u"])),
            "d_err_end": jnp.max(jnp.abs(dual["d_err"][-100:])),
            "traj": jnp.stack([nsf["norm"], dual["norm"], nsf["u"], dual["u"], dual["inside"].astype(float)]),
        }

    t0 = time.perf_counter()
    out = {k: np.asarray(v) for k, v in jax.jit(jax.vmap(both))(x0s).items()}
    wall = time.perf_counter() - t0
    diff = out["ts_nsf"] - out["ts_dual"]
    n = cfg.n_mc
    half = 1.96 * diff.std(ddof=1) / np.sqrt(n) if n > 1 else float("nan")

    def ci(v: np.ndarray) -> tuple[float, float]:
        h = 1.96 * v.std(ddof=1) / np.sqrt(len(v)) if len(v) > 1 else float("nan")
        return float(v.mean() - h), float(v.mean() + h)

    metrics = {
        "mc_ts_nsf_mean": float(out["ts_nsf"].mean()),
        "mc_ts_dual_mean": float(out["ts_dual"].mean()),
        "mc_ts_nsf_ci95_lo": ci(out["ts_nsf"])[0],
        "mc_ts_nsf_ci95_hi": ci(out["ts_nsf"])[1],
        "mc_ts_dual_ci95_lo": ci(out["ts_dual"])[0],
        "mc_ts_dual_ci95_hi": ci(out["ts_dual"])[1],
        "mc_speedup_mean_s": float(diff.mean()),
        "mc_speedup_ci95_lo_s": float(diff.mean() - half),
        "mc_speedup_ci95_hi_s": float(diff.mean() + half),
        "mc_dual_faster_fraction": float(np.mean(diff > 0)),
        "mc_settled_fraction_nsf": float(np.mean(out["ts_nsf"] < cfg.t_final)),
        "mc_settled_fraction_dual": float(np.mean(out["ts_dual"] < cfg.t_final)),
        "mc_switched_fraction": float(np.mean(np.isfinite(out["switch_t"]))),
        "mc_set_exits_total": float(out["exits"].sum()),
        "mc_u_max": float(out["u_max"].max()),
        "mc_d_err_end_max": float(out["d_err_end"].max()),
        "mc_wall_s": wall,
    }
    rows = [
        {
            "x1_0": float(a[0]),
            "x2_0": float(a[1]),
            "x3_0": float(a[2]),
            "ts_nsf_s": float(b),
            "ts_dual_s": float(c),
            "switch_t_s": float(s) if np.isfinite(s) else None,
            "set_exits": int(e),
        }
        for a, b, c, s, e in zip(np.asarray(x0s), out["ts_nsf"], out["ts_dual"], out["switch_t"], out["exits"])
    ]
    note = (
        f"Monte Carlo, {n} initial states uniform in ±{list(cfg.x0_box)}, tuned parameters: settling "
        f"(‖x‖ ≤ {cfg.tol:g}) NSF {metrics['mc_ts_nsf_mean']:.2f} s, dual {metrics['mc_ts_dual_mean']:.2f} s; "
        f"NSF − dual = {diff.mean():.2f} s (95 % CI {diff.mean() - half:.2f}…{diff.mean() + half:.2f}), dual "
        f"faster in {100 * metrics['mc_dual_faster_fraction']:.0f} % of the runs; exits from the set after "
        f"entering: {int(out['exits'].sum())}; |u| ≤ {metrics['mc_u_max']:.3f}"
    )
    return stages.Stage(metrics=metrics, tables={"monte_carlo": rows}, notes=[note], data=out["traj"][0])


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    ic.validate(ic.Params(u_m=cfg.u_m, d_m=cfg.d_m))
    lin = linear_mode(cfg)
    gain, p, level = lin
    tuned, designs = tuning_stage(cfg, lin)
    best = "gradient" if tuned.metrics["tune_gradient_smooth_s"] <= tuned.metrics["tune_pso_smooth_s"] else "pso"
    mc = monte_carlo_stage(cfg, lin, designs[best])
    t = cfg.dt * (1 + np.arange(int(round(cfg.t_final / cfg.dt))))
    tr = mc.data
    nsf = {"norm": tr[0], "u": tr[2]}
    dual = {"norm": tr[1], "u": tr[3]}
    ins = tr[4] > 0.5
    t_sw = round(float(t[int(np.argmax(ins))]), 2) if ins.any() else None
    fig = figures.line_panels(
        [
            figures.panel(
                {"NSF + ESO": (t, nsf["norm"]), "dual": (t, dual["norm"], "--")},
                "t, s",
                "‖x‖",
                log_y=True,
                hline=cfg.tol,
                title=f"x0 = {list(cfg.tune_states[0])}, switch at {t_sw} s",
            ),
            figures.panel({"NSF + ESO": (t, nsf["u"]), "dual": (t, dual["u"], "--")}, "t, s", "u"),
        ]
    )
    lin_metrics = {
        "lqr_k1": float(gain[0]),
        "lqr_k2": float(gain[1]),
        "lqr_k3": float(gain[2]),
        "set_level": float(level),
        "fig1_ts_nsf": float(settling_time(cfg, jnp.asarray(nsf["norm"]))),
        "fig1_ts_dual": float(settling_time(cfg, jnp.asarray(dual["norm"]))),
        "mc_design_is_gradient": float(best == "gradient"),
    }
    return stages.merge(
        tuned,
        mc,
        stages.Stage(figures={"fig1_norm_and_input": fig}),
        metrics=lin_metrics,
        notes=[
            f"linear mode: LQR (Q = {cfg.q_lqr:g} I, R = {cfg.r_lqr:g}) K = {np.round(np.asarray(gain), 4).tolist()}, "
            f"set xᵀPx ≤ {float(level):.4f} (largest LQR level set with |Kx| ≤ u_m − d_m; the paper's LMI "
            "set needs an SDP solver: approximation stated)"
        ],
    )


CLAIMS, ASSUMPTIONS = paper_facts("dual_mode_integrators")

STUDY = Study(
    name="dual_mode_integrators",
    description="Seed 004 #31: dual-mode control of a triple integrator (NSF + ESO outside an invariant set, "
    "linear feedback inside); NSF/ESO tuned by gradient vs PSO; Monte Carlo dual vs NSF",
    config=Config,
    presets={
        "quick": dict(n_mc=64, grad_steps=30),
        "tiny": dict(n_mc=8, grad_steps=4, pso_particles=4, dt=0.05, t_final=30.0, tune_states=((3.0, 0.0, 0.0),)),
    },
    claims=CLAIMS,
    assumptions=ASSUMPTIONS,
    run=run,
)
