"""Study ``helicopter_energy_control``: adaptive speed-gradient energy control of the 3-DOF helicopter
(seed 004 #15, Plotnikov; spec ``seed004_part1.md`` §B2).

Plant: :mod:`jaxsim.plants.helicopter_3dof` (rigid body from the Quanser parameters, equations of motion
by Lagrangian autodiff, motor lag).  Controller: :mod:`jaxsim.control.speed_gradient`, laws (7)–(10) on the
pitch ``ψ`` and elevation ``θ`` energies ``V = q̇²/2 + a0(1 − cos q)``.  The two virtual inputs ``u``
(pitch) and ``v`` (elevation) map to the motor voltages by (stated, assumed)::

    V_f − V_b = u·cos ψ
    V_f + V_b = [Fg·cos θ/Kf − (Je·a_θ0/(Kf·la))·sin θ + v·cos θ] / cos ψ

so the pitch axis has the form (1) with ``b_ψ = Kf·lh/Jp`` and ``a_ψ0 = g·hp/lh²`` (the body hangs
``hp`` below its axis), and the elevation axis — which on the rig is not a pendulum — gets gravity
compensation plus a shaped potential ``a_θ0`` (assumed) and the form (2) with ``b_θ = Kf·la/Je``.
Travel is left uncontrolled (the paper's switching schedule is not given).

The paper gives no numbers; the study validates by invariants (energy conservation of the uncontrolled
undamped plant and its step-size order; the Lyapunov function of the reduced model (1)–(2) non-increasing),
then tunes the four adaptation gains by gradient vs PSO on equal budgets and runs a vmapped Monte Carlo
over the unknown damping and thrust constant.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np

import jaxsim.montecarlo as mc
from experiments import figures, stages
from experiments.runner import Study, StudyResult, paper_facts
from jaxsim.control import speed_gradient as sg
from jaxsim.core.costs import Breakdown
from jaxsim.core.integrators import RK4, RK4_ROLLED
from jaxsim.plants import helicopter_3dof as heli
from jaxsim.problem import Param, ParamSpace, Problem

GAIN_NAMES = ("g1_pitch", "g1_elev", "g2_pitch", "g2_elev")
# XLA options of the study's own programs: the Lagrangian's nested derivatives compile ~3× faster at the
# lowest backend optimisation level and run ~2.5× slower (seconds either way); results are unchanged
LOW_OPT = {"xla_backend_optimization_level": 0, "xla_llvm_disable_expensive_passes": True}


def compile_low(fn: Callable[..., Any], *args: Any) -> Any:
    """``jit(fn)`` compiled for ``args`` with :data:`LOW_OPT`, then called on them."""
    return jax.jit(fn).lower(*args).compile(LOW_OPT)(*args)


@dataclass(frozen=True)
class Config:
    a_elev0: float = 1.0  # 1/s², shaped elevation potential a_θ0 (assumed)
    amp_pitch_deg: float = 20.0  # target pitch swing (sets V_ψ*; assumed)
    amp_elev_deg: float = 10.0  # target elevation swing (sets V_θ*; assumed)
    pitch0_deg: float = 5.0  # initial pitch (at rest; assumed)
    elev0_deg: float = 3.0  # initial elevation (at rest; assumed)
    t_final: float = 30.0  # s
    dt: float = 0.01  # s, RK4 step (controller evaluated continuously)
    tail: float = 5.0  # s, window of the final energy error
    rho: float = 1e-3  # weight of ∫(u² + v²) dt (1/V² · rad⁴/s⁴; assumed)
    gains0: tuple[float, float, float, float] = (20.0, 300.0, 5.0, 50.0)  # hand γ1ψ, γ1θ, γ2ψ, γ2θ
    gain_lo: float = 0.1
    gain_hi: float = 1e4
    budget: int = 96  # simulations per tuner
    n_particles: int = 8
    learning_rate: float = 0.1
    damping_lo: float = 0.1  # 1/s, Monte Carlo of the unknown damping a_·1 (paper: 0.1–1)
    damping_hi: float = 1.0
    kf_lo: float = 0.4  # N/V, Monte Carlo of the thrust constant (nominal 0.5)
    kf_hi: float = 0.6
    mc_runs: int = 256
    # invariants
    lyap_t: float = 20.0  # s, reduced-model Lyapunov check
    lyap_dt: float = 0.002
    lyap_a1: tuple[float, float] = (0.2, 0.2)  # 1/s, reduced model's true damping (assumed)
    seed: int = 0


def targets(cfg: Config, p: heli.HelicopterParams) -> tuple[jax.Array, jax.Array]:
    """``(a0 (2,), V* (2,))`` for (pitch, elevation)."""
    a0 = jnp.array([heli.GRAVITY * p.hp / p.lh**2, cfg.a_elev0])
    amp = jnp.deg2rad(jnp.array([cfg.amp_pitch_deg, cfg.amp_elev_deg]))
    return a0, a0 * (1.0 - jnp.cos(amp))


def voltages(cfg: Config, p_nom: heli.HelicopterParams, x: jax.Array, w: jax.Array) -> jax.Array:
    """Virtual inputs ``w = (u, v)`` → motor voltages ``(V_f, V_b)`` (module docstring; nominal ``p_nom``)."""
    theta, psi = x[1], x[2]
    cpsi = jnp.cos(psi)
    cpsi = jnp.where(cpsi >= 0, jnp.maximum(cpsi, 0.1), jnp.minimum(cpsi, -0.1))
    diff = w[0] * jnp.cos(psi)
    total = (
        p_nom.fg * jnp.cos(theta) / p_nom.kf
        - p_nom.je * cfg.a_elev0 / (p_nom.kf * p_nom.la) * jnp.sin(theta)
        + w[1] * jnp.cos(theta)
    ) / cpsi
    return jnp.stack([0.5 * (total + diff), 0.5 * (total - diff)])


def _law(cfg: Config, gains: jax.Array):
    p_nom = heli.HelicopterParams()
    a0, v_star = targets(cfg, p_nom)
    g = sg.SpeedGradientGains(gamma1=gains[:2], gamma2=gains[2:], v_star=v_star, a0=a0)

    def law(z):
        q, qd = z[jnp.array([2, 1])], z[jnp.array([5, 4])]
        return sg.control(g, q, qd, z[8:]), q, qd

    return g, law, a0, v_star


def initial_state(cfg: Config) -> jax.Array:
    """Closed-loop start ``(10,)``: at rest at (pitch0, elev0), motors at hover thrust, ``â = 0``."""
    p_nom = heli.HelicopterParams()
    z0 = jnp.zeros(10).at[2].set(jnp.deg2rad(cfg.pitch0_deg)).at[1].set(jnp.deg2rad(cfg.elev0_deg))
    return z0.at[6:8].set(heli.hover_voltage(p_nom) * p_nom.kf)


def plant_rollout(
    cfg: Config, gains: jax.Array, damping: Any, kf: Any, dt: Any, closed: Any, z0: jax.Array
) -> jax.Array:
    """Full plant + laws (7)–(10) through the voltage mapping, ``round(t_final/cfg.dt)`` RK4 steps of ``dt``:
    states ``(N+1, 10)`` = plant (8,) + ``â`` (2,).  ``closed = 0`` opens the loop (zero voltage, frozen ``â``):
    one compiled program serves the closed loops and the energy-conservation check."""
    p_nom = heli.HelicopterParams()
    p = heli.HelicopterParams(damping=damping, kf=kf)
    g, law, _, _ = _law(cfg, gains)

    def f(t, z):
        w, q, qd = law(z)
        xdot = heli.dynamics(p, z[:8], closed * voltages(cfg, p_nom, z, w), t)
        return jnp.concatenate([xdot, closed * sg.adaptation(g, q, qd)])

    n = int(round(cfg.t_final / cfg.dt))
    dt = jnp.asarray(dt, float)

    def body(z, t):
        z1 = RK4_ROLLED.step(f, t, z, dt)  # the Lagrangian plant traced once per step
        return z1, z1

    _, zs = jax.lax.scan(body, z0, dt * jnp.arange(n))
    return jnp.concatenate([z0[None], zs])


def loop_signals(cfg: Config, gains: jax.Array, zs: jax.Array) -> tuple[jax.Array, jax.Array]:
    """Virtual inputs ``(N+1, 2)`` and energy errors ``V − V*`` ``(N+1, 2)`` (pitch, elevation) along ``zs``."""
    _, law, a0, v_star = _law(cfg, gains)
    w, q, qd = jax.vmap(law)(zs)
    return w, sg.energy(q, qd, a0) - v_star


def rig_coefficients(p: heli.HelicopterParams, a_elev0: float) -> tuple[jax.Array, jax.Array]:
    """Reduced-model coefficients of the rig under the voltage mapping: ``a0 = (g·hp/lh², a_θ0)`` and
    ``b = (Kf·lh/Jp, Kf·la/Je)`` (per volt); the damping ``a1`` is the plant's ``damping`` on both axes."""
    a0 = jnp.stack([heli.GRAVITY * p.hp / p.lh**2, jnp.asarray(a_elev0, float)])
    return a0, jnp.stack([p.kf * p.lh / p.jp, p.kf * p.la / p.je])


def reduced_simulate(cfg: Config, gains: jax.Array, damping: Any, kf: Any) -> tuple[jax.Array, jax.Array, jax.Array]:
    """Reduced model (1)–(2) with the rig's coefficients, laws (7)–(10): ``(xs (N+1, 6), w (N+1, 2),
    V − V* (N+1, 2))``; ``xs = (ψ, θ, ψ̇, θ̇, â_ψ, â_θ)``."""
    p_nom = heli.HelicopterParams()
    a0, v_star = targets(cfg, p_nom)
    _, b = rig_coefficients(heli.HelicopterParams(kf=kf), cfg.a_elev0)
    a1 = jnp.stack([damping, damping])
    g = sg.SpeedGradientGains(gamma1=gains[:2], gamma2=gains[2:], v_star=v_star, a0=a0)
    x0 = jnp.concatenate([jnp.deg2rad(jnp.array([cfg.pitch0_deg, cfg.elev0_deg])), jnp.zeros(4)])
    n = int(round(cfg.t_final / cfg.dt))
    dt = jnp.asarray(cfg.dt)

    def body(x, t):
        x1 = RK4.step(lambda tt, xx: sg.reduced_dynamics(g, a1, b, xx, tt), t, x, dt)
        return x1, x1

    _, xs = jax.lax.scan(body, x0, dt * jnp.arange(n))
    xs = jnp.concatenate([x0[None], xs])
    w = jax.vmap(lambda x: sg.control(g, x[:2], x[2:4], x[4:]))(xs)
    return xs, w, sg.energy(xs[:, :2], xs[:, 2:4], a0) - v_star


def loss_terms(cfg: Config, gains: jax.Array, damping: Any, kf: Any) -> Breakdown:
    """``J = ∫Σ(V − V*)² dt + ρ∫(u² + v²) dt`` on the reduced model, and the final RMS energy errors."""
    _, w, err = reduced_simulate(cfg, gains, damping, kf)
    energy_cost = cfg.dt * jnp.sum(err**2)
    effort = cfg.dt * jnp.sum(w**2)
    n_tail = max(1, int(round(cfg.tail / cfg.dt)))
    final = jnp.sqrt(jnp.mean(err[-n_tail:] ** 2, axis=0))
    terms = {"energy": energy_cost, "effort": effort, "final_err_pitch": final[0], "final_err_elev": final[1]}
    return Breakdown(terms, energy_cost + cfg.rho * effort)


def problem_of(cfg: Config) -> Problem:
    space = ParamSpace(
        **{n: Param(lo=cfg.gain_lo, hi=cfg.gain_hi, init=cfg.gains0[i], log=True) for i, n in enumerate(GAIN_NAMES)}
    )

    def loss_fn(theta, d, key):
        gains = jnp.stack([theta[n] for n in GAIN_NAMES])
        return loss_terms(cfg, gains, d["damping"], d["kf"])

    return Problem.from_loss(
        "helicopter_speed_gradient",
        space,
        loss_fn,
        nominal={"damping": 0.2, "kf": 0.5},
        uncertainty={"damping": mc.uniform(cfg.damping_lo, cfg.damping_hi), "kf": mc.uniform(cfg.kf_lo, cfg.kf_hi)},
    )


# ----------------------------------------------------------------------------------------- invariants
ENERGY_X0 = (0.0, 0.3, 0.4, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)  # travel rate 0.5 rad/s, θ = 0.3, ψ = 0.4 rad


def mechanical_energy(zs: jax.Array) -> jax.Array:
    """``T + V`` (J) of the undamped plant along states ``(N, 10)``."""
    kinetic, potential = heli.energies(heli.HelicopterParams(damping=0.0))
    return jax.vmap(lambda z: kinetic(z[:3], z[3:6]) + potential(z[:3]))(zs)


def lyapunov_check(cfg: Config) -> dict[str, float]:
    """Reduced model (1)–(2), hand gains: max step increase of L relative to L(0), and L's decrease."""
    p = heli.HelicopterParams()
    a0, v_star = targets(cfg, p)
    gains = jnp.asarray(cfg.gains0)
    g = sg.SpeedGradientGains(gamma1=gains[:2], gamma2=gains[2:], v_star=v_star, a0=a0)
    a1 = jnp.asarray(cfg.lyap_a1)
    _, b = rig_coefficients(p, cfg.a_elev0)
    x0 = jnp.concatenate([jnp.deg2rad(jnp.array([cfg.pitch0_deg, cfg.elev0_deg])), jnp.zeros(4)])
    n = int(round(cfg.lyap_t / cfg.lyap_dt))

    def body(x, t):
        x1 = RK4.step(lambda tt, xx: sg.reduced_dynamics(g, a1, b, xx, tt), t, x, jnp.asarray(cfg.lyap_dt))
        return x1, x1

    _, xs = compile_low(lambda x: jax.lax.scan(body, x, cfg.lyap_dt * jnp.arange(n)), x0)
    xs = jnp.concatenate([x0[None], xs])
    lyap = np.asarray(sg.lyapunov(g, a1, b, xs))
    v = np.asarray(sg.energy(xs[:, :2], xs[:, 2:4], a0) - v_star)
    return {
        "lyap_L0": float(lyap[0]),
        "lyap_L_final": float(lyap[-1]),
        "lyap_max_increase_rel": float(np.max(np.diff(lyap)) / lyap[0]),
        "lyap_final_over_initial": float(lyap[-1] / lyap[0]),
        "reduced_final_err_pitch": float(abs(v[-1, 0])),
        "reduced_final_err_elev": float(abs(v[-1, 1])),
        "reduced_a_hat_pitch": float(xs[-1, 4]),
        "reduced_a_hat_elev": float(xs[-1, 5]),
        "reduced_a1_over_b_pitch": float(a1[0] / b[0]),
        "reduced_a1_over_b_elev": float(a1[1] / b[1]),
    }, (np.arange(n + 1) * cfg.lyap_dt, lyap)


def invariant_stage(cfg: Config, e_dt: np.ndarray, e_half: np.ndarray, t_kin: float) -> stages.Stage:
    """``e_dt``, ``e_half``: energies of the open-loop undamped plant with steps dt and dt/2 (N+1 samples);
    the drift is compared over the common horizon (first half of the dt run)."""
    m = (len(e_dt) - 1) // 2
    d1 = float(np.max(np.abs(e_dt[: m + 1] - e_dt[0])))
    d2 = float(np.max(np.abs(e_half[: 2 * m + 1] - e_half[0])))
    lyap, (tl, lcurve) = lyapunov_check(cfg)
    metrics = {
        "energy_drift_rel": d1 / t_kin,
        "energy_drift_rel_half_step": d2 / t_kin,
        "energy_drift_order": math.log2(d1 / d2),
        **lyap,
    }
    fig = figures.line_panels(
        [figures.panel({"L(t)": (tl, lcurve)}, "t, s", "L = Q + b/(2γ2)(â − a1/b)²", log_y=True, title="reduced model")]
    )
    note = (
        f"uncontrolled undamped plant over {m * cfg.dt:g} s: energy drift {d1 / t_kin:.2e} (of the initial kinetic "
        f"energy) at dt = {cfg.dt:g} s, {d2 / t_kin:.2e} at dt/2 — order {metrics['energy_drift_order']:.2f} (RK4: 4); "
        f"reduced-model Lyapunov function: largest step increase {lyap['lyap_max_increase_rel']:.1e} of L(0), "
        f"L(T)/L(0) = {lyap['lyap_final_over_initial']:.2e}"
    )
    return stages.Stage(metrics=metrics, figures={"lyapunov": fig}, notes=[note])


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    problem = problem_of(cfg)
    tuned = stages.tune_and_compare(
        problem,
        cfg.budget,
        ("gradient", "pso"),
        key=jax.random.PRNGKey(cfg.seed),
        learning_rate=cfg.learning_rate,
        n_starts=1,
        n_particles=cfg.n_particles,
        progress=progress,
        loss_label="J = ∫Σ(V − V*)² dt + ρ∫(u² + v²) dt",
    )
    designs = {"hand": jnp.asarray(cfg.gains0)}
    for name, theta in tuned.designs.items():
        designs[name] = jnp.stack([jnp.asarray(theta[n]) for n in GAIN_NAMES])
    # nominal responses
    stacked = jnp.stack(list(designs.values()))
    # one compiled full-plant program: the designs' closed loops + the open-loop energy check at dt and dt/2
    nd = len(designs)
    z_cl = jnp.tile(initial_state(cfg), (nd, 1))
    z_e = jnp.tile(jnp.asarray(ENERGY_X0), (2, 1))
    zs_all = compile_low(
        jax.vmap(lambda g, d, dt, c, z0: plant_rollout(cfg, g, d, 0.5, dt, c, z0)),
        jnp.concatenate([stacked, jnp.zeros((2, 4)) + 1.0]),
        jnp.array([0.2] * nd + [0.0, 0.0]),
        jnp.array([cfg.dt] * nd + [cfg.dt, 0.5 * cfg.dt]),
        jnp.array([1.0] * nd + [0.0, 0.0]),
        jnp.concatenate([z_cl, z_e]),
    )
    p_nom = heli.HelicopterParams()

    def post(zs):
        w, err = jax.vmap(lambda g, z: loop_signals(cfg, g, z))(stacked, zs[:nd])
        volts = jax.vmap(jax.vmap(lambda z, ww: voltages(cfg, p_nom, z, ww)))(zs[:nd], w)
        kin0 = heli.energies(p_nom)[0](zs[nd, 0, :3], zs[nd, 0, 3:6])
        return jax.vmap(mechanical_energy)(zs[nd:]), w, err, volts, kin0

    energies, w_all, err_all, volts_all, kin0 = (np.asarray(v) for v in compile_low(post, zs_all))
    kin0 = float(kin0)
    inv = invariant_stage(cfg, energies[0], energies[1], kin0)
    # one compiled reduced-model batch: the designs at the nominal draw + hand and gradient over the MC draws
    draws = problem.sample(jax.random.PRNGKey(cfg.seed + 1), cfg.mc_runs)
    n_mc = cfg.mc_runs
    batch = compile_low(
        jax.vmap(lambda g, d, k: loss_terms(cfg, g, d, k)),
        jnp.concatenate([stacked, jnp.tile(designs["hand"], (n_mc, 1)), jnp.tile(designs["gradient"], (n_mc, 1))]),
        jnp.concatenate([jnp.full(nd, 0.2), draws["damping"], draws["damping"]]),
        jnp.concatenate([jnp.full(nd, 0.5), draws["kf"], draws["kf"]]),
    )
    reduced = jax.tree_util.tree_map(lambda a: a[:nd], batch)
    mc_out = {
        "hand": jax.tree_util.tree_map(lambda a: a[nd : nd + n_mc], batch.terms),
        "gradient": jax.tree_util.tree_map(lambda a: a[nd + n_mc :], batch.terms),
    }
    a0, v_star = targets(cfg, heli.HelicopterParams())
    t = np.arange(int(round(cfg.t_final / cfg.dt)) + 1) * cfg.dt
    n_tail = max(1, int(round(cfg.tail / cfg.dt)))
    metrics: dict[str, float] = {"v_star_pitch": float(v_star[0]), "v_star_elev": float(v_star[1])}
    lines_v, lines_amp, rows = {}, {}, []
    for i_d, (name, gains) in enumerate(designs.items()):
        zs = np.asarray(zs_all[i_d])
        err = err_all[i_d]
        rel = np.sqrt(np.mean(err[-n_tail:] ** 2, axis=0)) / np.asarray(v_star)
        amp_p = np.degrees(np.max(np.abs(zs[-n_tail:, 2])))
        amp_e = np.degrees(np.max(np.abs(zs[-n_tail:, 1])))
        volts = volts_all[i_d]
        row = {
            "design": name,
            **{n: float(gains[i]) for i, n in enumerate(GAIN_NAMES)},
            "final_rel_err_pitch": float(rel[0]),
            "final_rel_err_elev": float(rel[1]),
            "final_amp_pitch_deg": float(amp_p),
            "final_amp_elev_deg": float(amp_e),
            "a_hat_pitch": float(zs[-1, 8]),
            "a_hat_elev": float(zs[-1, 9]),
            "max_abs_voltage": float(np.max(np.abs(volts))),
            "reduced_final_rel_err_pitch": float(reduced.terms["final_err_pitch"][i_d] / v_star[0]),
            "reduced_final_rel_err_elev": float(reduced.terms["final_err_elev"][i_d] / v_star[1]),
            "loss": float(reduced.total[i_d]),
        }
        rows.append(row)
        for k in (
            "final_rel_err_pitch",
            "final_rel_err_elev",
            "final_amp_pitch_deg",
            "final_amp_elev_deg",
            "reduced_final_rel_err_pitch",
            "reduced_final_rel_err_elev",
            "loss",
        ):
            metrics[f"{name}_{k}"] = row[k]
        lines_v[f"{name} pitch"] = (t, err[:, 0] + float(v_star[0]))
        lines_v[f"{name} elevation"] = (t, err[:, 1] + float(v_star[1]))
        lines_amp[f"{name} pitch"] = (t, np.degrees(zs[:, 2]))
        lines_amp[f"{name} elevation"] = (t, np.degrees(zs[:, 1]))
    metrics["gradient_over_pso_loss"] = metrics["gradient_loss"] / metrics["pso_loss"]
    metrics["gradient_over_hand_loss"] = metrics["gradient_loss"] / metrics["hand_loss"]
    fig = figures.line_panels(
        [
            figures.panel(lines_v, "t, s", "V, rad²/s²", title="energies → V*"),
            figures.panel(lines_amp, "t, s", "angle, deg", title="pitch and elevation"),
        ]
    )
    # robustness: vmapped Monte Carlo over damping and thrust constant
    mc_rows = []
    for name in ("hand", "gradient"):
        out = mc_out[name]
        for axis, vs in (("pitch", float(v_star[0])), ("elev", float(v_star[1]))):
            rel = np.asarray(out[f"final_err_{axis}"]) / vs
            mean = float(np.mean(rel))
            half = 1.96 * float(np.std(rel, ddof=1)) / math.sqrt(len(rel)) if len(rel) > 1 else float("nan")
            mc_rows.append(
                {
                    "design": name,
                    "axis": axis,
                    "runs": len(rel),
                    "mean_rel_err": mean,
                    "ci95_lo": mean - half,
                    "ci95_hi": mean + half,
                    "p95_rel_err": float(np.quantile(rel, 0.95)),
                    "max_rel_err": float(np.max(rel)),
                }
            )
            metrics[f"mc_{name}_{axis}_mean_rel_err"] = mean
            metrics[f"mc_{name}_{axis}_p95_rel_err"] = float(np.quantile(rel, 0.95))
    note = (
        f"full plant, nominal damping 0.2 s⁻¹: gradient-tuned gains reach V* within "
        f"{100 * metrics['gradient_final_rel_err_pitch']:.2g} % (pitch) and "
        f"{100 * metrics['gradient_final_rel_err_elev']:.2g} % (elevation) RMS over the last {cfg.tail:g} s; "
        f"loss gradient/PSO = {metrics['gradient_over_pso_loss']:.3f}, gradient/hand = "
        f"{metrics['gradient_over_hand_loss']:.3f}. Monte Carlo ({cfg.mc_runs} draws, damping U[{cfg.damping_lo:g}, "
        f"{cfg.damping_hi:g}] s⁻¹, Kf U[{cfg.kf_lo:g}, {cfg.kf_hi:g}] N/V, gravity compensation uses the nominal Kf)"
    )
    res = stages.Stage(
        metrics=metrics, tables={"designs": rows, "robustness": mc_rows}, figures={"responses": fig}, notes=[note]
    )
    return stages.merge(inv, tuned, res)


CLAIMS, ASSUMPTIONS = paper_facts("helicopter_energy_control")

STUDY = Study(
    name="helicopter_energy_control",
    description="Seed 004 #15: adaptive speed-gradient energy control of the 3-DOF helicopter (pitch and "
    "elevation energies), invariants, gradient vs PSO gains, Monte Carlo over damping and thrust",
    config=Config,
    presets={
        "quick": dict(budget=48, mc_runs=64),
        "tiny": dict(
            budget=6,
            n_particles=3,
            mc_runs=4,
            t_final=8.0,
            tail=2.0,
            dt=0.02,
            lyap_t=5.0,
            lyap_dt=0.005,
        ),
    },
    claims=CLAIMS,
    assumptions=ASSUMPTIONS,
    run=run,
)
