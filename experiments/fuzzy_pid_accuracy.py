"""Study ``fuzzy_pid_accuracy``: steady-state accuracy of fuzzy vs linear control (the fuzzy-PID paper).

Seed 000, paper 1 (spec ``seed000_fuzzy_pid_smo_predictor.md`` §1.1–1.4).  Plants: static
``2/((0.1s+1)(0.5s+1))`` and astatic ``2/(s(0.1s+1))``; the disturbance enters as ``u − f``.

1. The linear baselines are designed by :func:`jaxsim.control.stability_degree.max_stability_degree`
   (P: ``K_mds`` = 0.4 and 1.25, PI: triple-root designs) — computed, not typed in.
2. The paper's four cases (static g = 1, f = 0 / 0.3; astatic g = 1 with f = 0.2 / 0.7) are solved
   analytically (:mod:`jaxsim.control.fuzzy_steady_state`: equations (1)/(2) and their domains) and
   simulated in closed loop with the paper's fuzzy characteristics and the linear controllers; the
   settling time (2 %) and overshoot of every case come from the simulation.
3. Analytic vs simulated steady-state error over a grid of ``(g, f, K_g, K_f)`` for linear/fuzzy
   P and PI on both plants, including the cases without a steady state (detected as drift).
4. Figures 2–6 of the paper: the static characteristic of a Mamdani controller and its
   three-section least-squares approximation (Fig. 2), FC1/FC2 vs ``K_mds`` (Fig. 3), the
   transients of the four cases (Figs. 4–5) and fuzzy PI vs linear PI (Fig. 6).

All simulations: RK4, plant step = controller period = ``dt``, zero initial state, steps and ramps
applied at t = 0.  One vmapped rollout per (plant, controller structure).
"""

from __future__ import annotations

import dataclasses
import itertools
from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np
import optax

from experiments.study import Study, StudyResult, assumption
from jaxsim.control import fuzzy as fz
from jaxsim.control.fuzzy_steady_state import section_domains, steady_state_error
from jaxsim.control.stability_degree import max_stability_degree
from jaxsim.core.metrics import step_info, steady_state
from jaxsim.core.rollout import ClosedLoop, Timing, simulate
from jaxsim.core.signals import Ramp, Step, Sum
from jaxsim.plants.second_order import (
    AstaticParams,
    StaticParams,
    astatic_plant,
    astatic_transfer_function,
    static_plant,
    static_transfer_function,
)

PLANTS = ("static", "astatic")
CONTROLLERS = ("linear P", "fuzzy P", "linear PI", "fuzzy PI")


@dataclass(frozen=True)
class Config:
    quick: bool = False
    K_static: float = 2.0  # paper lines 468–470
    T1: float = 0.1
    T2: float = 0.5
    K_astatic: float = 2.0  # paper line 609
    T_astatic: float = 0.1
    fc_static: tuple = (0.75, 0.3, 1.2, 1.0)  # (a, b, c, d), paper line 488
    fc_astatic: tuple = (0.2, 0.25, 1.2, 2.0)  # paper lines 619–620
    g: float = 1.0  # "single step reference g = 1"
    f_static: tuple = (0.0, 0.3)  # Fig. 4a, 4b
    f_astatic: tuple = (0.2, 0.7)  # Fig. 5a, 5b
    fc1_static: tuple = (0.5, 0.3, 1.2, 1.0)  # Fig. 3 "FC1" (larger K1): assumed
    pi_p_gain_ratio: float = 1.5  # fuzzy PI, P channel: K2/K1 (assumed)
    pi_i_breakpoints: tuple = (0.05, 0.3)  # fuzzy PI, I channel: (a_i, c_i) (assumed)
    pi_i_gain_ratio: float = 2.0  # fuzzy PI, I channel: K2/K1 (assumed)
    fig6_f: float = 0.5  # Fig. 6 constant disturbance (assumed)
    grid_g: tuple = (0.5, 1.5)
    grid_f: tuple = (0.0, 0.3, 0.8, 2.5)
    grid_g_slope: tuple = (0.0, 0.3)
    grid_f_slope: tuple = (0.0, 0.15, 2.0)
    dt: float = 1e-3  # s, plant step and controller period
    t_final: float = 20.0  # s: the slowest grid case (fuzzy PI, f = 2.5 and ramps) needs ~15 s
    drift_window: float = 1.0  # s: a steady state must not drift over the last window
    drift_rtol: float = 1e-6
    mamdani_fit_steps: int = 400  # Fig. 2: Adam steps fitting the Mamdani to the characteristic


ASSUMPTIONS = {
    "disturbance_sign": assumption("u − f", "the sign that reproduces every number in the paper"),
    "initial_conditions": assumption("zero", "not stated in the paper"),
    "time_unit": assumption("s", "the paper gives no time unit"),
    "astatic_reference": assumption(
        "g = 1 step together with the disturbance step at t = 0",
        "Fig. 5 applies g(t) and f 'simultaneously'; the amplitude of g is not given"),
    "fc1_static": assumption(
        [0.5, 0.3, 1.2, 1.0],
        "Fig. 3 shows FC1 (larger K1) and FC2 without parameters; FC2 is taken as the paper's FC "
        "(K1 = K_mds = 0.4) and FC1 as the same characteristic with a = 0.5 (K1 = 0.6)"),
    "fuzzy_pi": assumption(
        "P channel: a, c of the plant's paper FC, K1 = Kp of the maximum-stability PI, K2 = 1.5·K1; "
        "I channel: a = 0.05, c = 0.3, K1 = Ki of the maximum-stability PI, K2 = 2·K1",
        "the paper gives no fuzzy PI parameters (Fig. 6 is curves only); the small gains follow the "
        "paper's rule K1 = the linear maximum-stability gain, the section gains are chosen larger"),
    "fig6_scenario": assumption(
        "astatic plant, g = 1 and f = 0.5 steps at t = 0",
        "Fig. 6 says only 'a constant disturbance'"),
    "fig2_mamdani": assumption(
        "five-term odd Mamdani (templates.odd_mamdani), breakpoints fitted by Adam to the paper's "
        "static-plant FC",
        "the paper's FC membership functions, rules and defuzzification are not given (curve 1 of "
        "Fig. 2 is unknown); this builds a Mamdani FC whose approximation (curve 2) is the paper's"),
    "grid": assumption(
        "g ∈ grid_g, f ∈ grid_f, K_g ∈ grid_g_slope, K_f ∈ grid_f_slope; relative error "
        "|e_sim − e_an| / max(|e_an|, g)",
        "covers every section (small gain, large gain, saturated) and the no-steady-state cases"),
}


# ---------------------------------------------------------------------------------------------
# Controllers of the study


def designs(cfg: Config) -> dict[tuple[str, str], dict[str, float]]:
    """Maximum-stability-degree P and PI gains for both plants (computed)."""
    tfs = {"static": static_transfer_function(StaticParams(cfg.K_static, cfg.T1, cfg.T2)),
           "astatic": astatic_transfer_function(AstaticParams(cfg.K_astatic, cfg.T_astatic))}
    out = {}
    for plant, (num, den) in tfs.items():
        for structure in ("P", "PI"):
            out[(plant, structure)] = max_stability_degree(np.asarray(num), np.asarray(den), structure).gains
    return out


def channels(cfg: Config, gains: dict, plant: str, controller: str) -> tuple[Any, Any]:
    """``(p, i)`` characteristics of one of the four controllers on one plant."""
    fc = cfg.fc_static if plant == "static" else cfg.fc_astatic
    if controller == "linear P":
        return fz.linear(gains[(plant, "P")]["kp"]), None
    if controller == "fuzzy P":
        return fz.three_section(*fc), None
    pi = gains[(plant, "PI")]
    if controller == "linear PI":
        return fz.linear(pi["kp"]), fz.linear(pi["ki"])
    a, _, c, _ = fc
    a_i, c_i = cfg.pi_i_breakpoints
    p = fz.from_gains(pi["kp"], cfg.pi_p_gain_ratio * pi["kp"], a, c)
    i = fz.from_gains(pi["ki"], cfg.pi_i_gain_ratio * pi["ki"], a_i, c_i)
    return p, i


def _plant(cfg: Config, name: str):
    if name == "static":
        return static_plant(StaticParams(cfg.K_static, cfg.T1, cfg.T2))
    return astatic_plant(AstaticParams(cfg.K_astatic, cfg.T_astatic))


# ---------------------------------------------------------------------------------------------
# Batched closed-loop simulation


class Case(dict):
    """One simulation: plant, controller label, channel characteristics and the input signals."""


def _stack(trees: list) -> Any:
    return jax.tree_util.tree_map(lambda *xs: np.stack([np.asarray(x, float) for x in xs]), *trees)


def simulate_cases(cfg: Config, cases: list[Case], timing: Timing, tail: int, save_every: int):
    """Simulate cases of one plant and one controller structure in one vmapped rollout.

    Returns per case: final error, drift flag, settling time, overshoot, and decimated (t, y, u).
    """
    plant = _plant(cfg, cases[0]["plant"])
    params = _stack([fz.fuzzy_pid(c["p"], c["i"]).params for c in cases])
    template = fz.fuzzy_pid(cases[0]["p"], cases[0]["i"])
    sig = jnp.asarray([[c["g"], c["g_slope"], c["f"], c["f_slope"]] for c in cases], float)

    def one(p, s):
        ref = Sum((Step(s[0]), Ramp(s[1])))
        dist = Sum((Step(s[2]), Ramp(s[3])))
        loop = ClosedLoop(plant, dataclasses.replace(template, params=p), reference=ref, disturbance=dist)
        tr = simulate(loop, jnp.zeros(plant.n_states), timing)
        e = tr.r[:, 0] - tr.y[:, 0]
        ss = steady_state(e, tail, rtol=cfg.drift_rtol)
        info = step_info(tr.t, tr.y[:, 0])
        return (ss.value, ss.converged, info.settling_time, info.overshoot,
                tr.t[::save_every], tr.y[::save_every, 0], tr.u[::save_every, 0])

    out = jax.jit(jax.vmap(one))(params, sig)
    return [tuple(np.asarray(o[k]) for o in out) for k in range(len(cases))]


def _structure_key(case: Case) -> tuple:
    return (case["plant"], jax.tree_util.tree_structure(fz.fuzzy_pid(case["p"], case["i"]).params))


def run_all(cfg: Config, cases: list[Case], progress: Callable[..., Any]) -> None:
    """Simulate every case (grouped by plant and controller structure); results are stored in place."""
    timing = Timing(t_final=cfg.t_final, dt=cfg.dt)
    tail = max(2, int(round(cfg.drift_window / cfg.dt)))
    save_every = 10
    groups: dict[tuple, list[Case]] = {}
    for c in cases:
        groups.setdefault(_structure_key(c), []).append(c)
    for key in progress(list(groups), desc="fuzzy_pid_accuracy", unit="group"):
        group = groups[key]
        for c, res in zip(group, simulate_cases(cfg, group, timing, tail, save_every)):
            c["e_sim"], c["converged"], c["settling"], c["overshoot"], c["t"], c["y"], c["u"] = res


# ---------------------------------------------------------------------------------------------
# Fig. 2: a Mamdani controller whose three-section approximation is the paper's


def _sorted_positive(theta: jax.Array) -> jax.Array:
    return jnp.cumsum(jax.nn.softplus(theta))


def fit_mamdani_to_characteristic(cfg: Config, target: Any, e: jax.Array):
    """Breakpoints of :func:`fz.odd_mamdani` fitted (Adam, least squares) to ``target(e)``."""
    u_range = 1.6 * float(target.d)
    u_ref = target(e)

    def build(theta):
        return fz.odd_mamdani(_sorted_positive(theta[:2]), _sorted_positive(theta[2:4]),
                              jax.nn.softplus(theta[4]), u_range=u_range, n_grid=161)

    def loss(theta):
        return jnp.mean((fz.static_characteristic(build(theta), e) - u_ref) ** 2)

    a, b, c, d = (float(v) for v in (target.a, target.b, target.c, target.d))
    inv = lambda x: np.log(np.expm1(x))  # noqa: E731  (softplus⁻¹)
    theta = jnp.asarray([inv(a), inv(c - a), inv(b), inv(d - b), inv(0.2 * d)])
    opt = optax.adam(0.03)

    @jax.jit
    def step(theta, state):
        value, grad = jax.value_and_grad(loss)(theta)
        updates, state = opt.update(grad, state)
        return optax.apply_updates(theta, updates), state, value

    state = opt.init(theta)
    steps = 60 if cfg.quick else cfg.mamdani_fit_steps
    for _ in range(steps):
        theta, state, _ = step(theta, state)
    _, _, final = step(theta, state)  # the loss at the final theta (same compiled function)
    return build(theta), float(jnp.sqrt(final))


# ---------------------------------------------------------------------------------------------


def _small_gain(char: Any) -> float:
    if isinstance(char, fz.Linear):
        return float(char.gain)
    return float(char.b) / float(char.a)


_evaluate = jax.jit(lambda char, e: char(e))  # characteristics on a grid, for plots


def _case_key(plant: str, f: float) -> str:
    return f"{plant}_f{f:g}".replace(".", "")  # f = 0.3 → "static_f03"


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    gains = designs(cfg)
    K = {"static": cfg.K_static, "astatic": cfg.K_astatic}
    cases: list[Case] = []

    # the paper's four cases, both controllers
    paper_f = {"static": cfg.f_static, "astatic": cfg.f_astatic}
    for plant in PLANTS:
        for f in paper_f[plant]:
            for ctrl in ("fuzzy P", "linear P"):
                p, i = channels(cfg, gains, plant, ctrl)
                cases.append(Case(kind="paper", plant=plant, controller=ctrl, p=p, i=i, g=cfg.g,
                                  g_slope=0.0, f=f, f_slope=0.0))
    # Fig. 3 (FC1) and Fig. 6 (PI on the astatic plant)
    cases.append(Case(kind="fig3", plant="static", controller="FC1", p=fz.three_section(*cfg.fc1_static),
                      i=None, g=cfg.g, g_slope=0.0, f=0.0, f_slope=0.0))
    for ctrl in ("linear PI", "fuzzy PI"):
        p, i = channels(cfg, gains, "astatic", ctrl)
        cases.append(Case(kind="fig6", plant="astatic", controller=ctrl, p=p, i=i, g=cfg.g, g_slope=0.0,
                          f=cfg.fig6_f, f_slope=0.0))
    # the (g, f, K_g, K_f) grid
    if cfg.quick:
        grid = list(itertools.product((cfg.grid_g[-1],), (cfg.grid_f[1], cfg.grid_f[-1]),
                                      cfg.grid_g_slope, cfg.grid_f_slope))
    else:
        grid = list(itertools.product(cfg.grid_g, cfg.grid_f, cfg.grid_g_slope, cfg.grid_f_slope))
    for plant in PLANTS:
        for ctrl in CONTROLLERS:
            p, i = channels(cfg, gains, plant, ctrl)
            for g, f, kg, kf in grid:
                cases.append(Case(kind="grid", plant=plant, controller=ctrl, p=p, i=i, g=g, g_slope=kg,
                                  f=f, f_slope=kf))
    for c in cases:
        c["op"] = steady_state_error(c["plant"], K[c["plant"]], c["p"], c["i"], g=c["g"], g_slope=c["g_slope"],
                                     f=c["f"], f_slope=c["f_slope"])
    run_all(cfg, cases, progress)

    metrics: dict[str, float] = {
        "kp_mds_static": gains[("static", "P")]["kp"],
        "kp_mds_astatic": gains[("astatic", "P")]["kp"],
        "pi_mds_static_kp": gains[("static", "PI")]["kp"],
        "pi_mds_static_ki": gains[("static", "PI")]["ki"],
        "pi_mds_astatic_kp": gains[("astatic", "PI")]["kp"],
        "pi_mds_astatic_ki": gains[("astatic", "PI")]["ki"],
    }
    paper_rows = []
    for c in (c for c in cases if c["kind"] == "paper"):
        name = _case_key(c["plant"], c["f"]) + ("_fuzzy" if c["controller"] == "fuzzy P" else "_linear")
        metrics[f"ess_{name}"] = float(c["e_sim"])
        metrics[f"ess_{name}_analytic"] = c["op"].error
        metrics[f"settling_{name}"] = float(c["settling"])
        metrics[f"overshoot_{name}"] = float(c["overshoot"])
        lim1, lim2 = section_domains(c["plant"], K[c["plant"]], c["p"])
        paper_rows.append({
            "plant": c["plant"], "g": c["g"], "f": c["f"], "controller": c["controller"],
            "K1": _small_gain(c["p"]),
            "demand": c["op"].demand, "section": c["op"].section, "equation": c["op"].equation,
            "domain_section1_upper": lim1, "domain_section2_upper": lim2,
            "e_analytic": c["op"].error, "e_simulated": float(c["e_sim"]),
            "abs_difference": abs(c["op"].error - float(c["e_sim"])),
            "settling_time_2pct_s": float(c["settling"]), "overshoot_pct": float(c["overshoot"]),
        })
    metrics["paper_cases_max_abs_difference"] = max(r["abs_difference"] for r in paper_rows)

    fig6 = {c["controller"]: c for c in cases if c["kind"] == "fig6"}
    for label, key in (("linear PI", "linear_pi"), ("fuzzy PI", "fuzzy_pi")):
        metrics[f"fig6_settling_{key}"] = float(fig6[label]["settling"])
        metrics[f"fig6_overshoot_{key}"] = float(fig6[label]["overshoot"])
        metrics[f"fig6_ess_{key}"] = float(fig6[label]["e_sim"])

    grid_rows = []
    for c in (c for c in cases if c["kind"] == "grid"):
        op = c["op"]
        scale = max(abs(op.error), abs(c["g"])) if op.exists else np.nan
        rel = abs(float(c["e_sim"]) - op.error) / scale if op.exists else np.nan
        grid_rows.append({
            "plant": c["plant"], "controller": c["controller"], "g": c["g"], "g_slope": c["g_slope"],
            "f": c["f"], "f_slope": c["f_slope"], "section": op.section, "channel": op.channel,
            "equation": op.equation, "e_analytic": op.error, "e_simulated": float(c["e_sim"]),
            "steady_state_analytic": bool(op.exists), "steady_state_simulated": bool(c["converged"]),
            "relative_error": rel,
        })
    finite = [r for r in grid_rows if r["steady_state_analytic"]]
    none = [r for r in grid_rows if not r["steady_state_analytic"]]
    metrics.update({
        "grid_n_cases": len(grid_rows),
        "grid_n_finite": len(finite),
        "grid_n_finite_converged": sum(r["steady_state_simulated"] for r in finite),
        "grid_max_relative_error": max(r["relative_error"] for r in finite),
        "grid_n_no_steady_state": len(none),
        "grid_n_no_steady_state_detected": sum(not r["steady_state_simulated"] for r in none),
    })
    for s in (1, 2, 3):
        metrics[f"grid_n_section{s}"] = sum(r["section"] == s for r in finite)

    e = jnp.linspace(-2.0, 2.0, 201)
    mamdani, rms_to_paper = fit_mamdani_to_characteristic(cfg, fz.three_section(*cfg.fc_static), e)
    u_mamdani = np.asarray(jax.jit(fz.static_characteristic)(mamdani, e))
    fit = fz.fit_three_section(e, u_mamdani)
    metrics.update({f"fig2_fit_{k}": v for k, v in zip("abcd", fit.abcd)})
    metrics["fig2_fit_rms"] = fit.rms
    metrics["fig2_mamdani_rms_to_paper_fc"] = rms_to_paper

    figures = {
        "fig2_static_characteristic": _plot_fig2(cfg, e, u_mamdani, fit, gains),
        "fig3_fc1_fc2_kmds": _plot_fig3(cfg, cases, gains),
        "fig4_static_transients": _plot_transients([c for c in cases if c["kind"] == "paper" and c["plant"] == "static"],
                                                   "Fig. 4: static plant, g = 1"),
        "fig5_astatic_transients": _plot_transients([c for c in cases if c["kind"] == "paper" and c["plant"] == "astatic"],
                                                     "Fig. 5: astatic plant, g = 1"),
        "fig6_pi_astatic": _plot_fig6(cfg, fig6),
        "steady_state_grid": _plot_grid(grid_rows),
    }
    fuzzy_pi_p, fuzzy_pi_i = channels(cfg, gains, "astatic", "fuzzy PI")
    notes = [
        f"simulation: RK4, dt = controller period = {cfg.dt} s, horizon {cfg.t_final} s; "
        f"steady state = last sample; no steady state = drift over the last {cfg.drift_window} s above rtol "
        f"{cfg.drift_rtol}",
        "settling time: 2 % band around the final output (python-control's definition), overshoot in %",
        "fuzzy PI (astatic) channels: P (a, b, c, d) = "
        f"{tuple(round(float(v), 4) for v in (fuzzy_pi_p.a, fuzzy_pi_p.b, fuzzy_pi_p.c, fuzzy_pi_p.d))}, "
        f"I = {tuple(round(float(v), 4) for v in (fuzzy_pi_i.a, fuzzy_pi_i.b, fuzzy_pi_i.c, fuzzy_pi_i.d))}",
    ]
    return StudyResult(
        metrics=metrics,
        tables={"paper_cases": paper_rows, "steady_state_grid": grid_rows,
                "fig6_pi": [{"controller": k, "settling_time_2pct_s": float(v["settling"]),
                             "overshoot_pct": float(v["overshoot"]), "e_final": float(v["e_sim"])}
                            for k, v in fig6.items()]},
        assumptions=ASSUMPTIONS,
        figures=figures,
        notes=notes,
    )


# ---------------------------------------------------------------------------------------------
# Plots


def _plot_fig2(cfg, e, u_mamdani, fit, gains):
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    e_np = np.asarray(e)
    ax.plot(e_np, u_mamdani, lw=2, label="1: Mamdani FC (centroid)")
    ax.plot(e_np, np.asarray(_evaluate(fit.params, e)), "--", lw=1.5,
            label="2: three-section fit a={:.3f} b={:.3f} c={:.3f} d={:.3f}".format(*fit.abcd))
    ax.plot(e_np, np.asarray(_evaluate(fz.three_section(*cfg.fc_static), e)), ":", color="k", lw=1.2,
            label="paper's FC (0.75, 0.3, 1.2, 1)")
    ax.plot(e_np, gains[("static", "P")]["kp"] * e_np, color="gray", lw=0.8, label="linear K_mds·e")
    ax.set_xlabel("e")
    ax.set_ylabel("u")
    ax.set_ylim(-1.4, 1.4)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("Fig. 2: static characteristic of the FC and its approximation")
    fig.tight_layout()
    return fig


def _plot_fig3(cfg, cases, gains):
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.5))
    e = np.linspace(0, 2.0, 401)
    fc1, fc2 = fz.three_section(*cfg.fc1_static), fz.three_section(*cfg.fc_static)
    kmds = gains[("static", "P")]["kp"]
    ax1.plot(e, np.asarray(_evaluate(fc1, e)), label=f"FC1 (K1 = {_small_gain(fc1):.2f})")
    ax1.plot(e, np.asarray(_evaluate(fc2, e)), label=f"FC2 (K1 = {_small_gain(fc2):.2f})")
    ax1.plot(e, kmds * e, "k--", lw=1, label=f"K_mds = {kmds:.3g}")
    ax1.set_xlabel("e")
    ax1.set_ylabel("u")
    ax1.set_ylim(0, 1.3)
    ax1.legend()
    ax1.grid(alpha=0.3)
    ax1.set_title("(a) static characteristics")
    picks = {"FC1": next(c for c in cases if c["kind"] == "fig3"),
             "FC2": next(c for c in cases if c["kind"] == "paper" and c["plant"] == "static" and c["f"] == 0.0
                         and c["controller"] == "fuzzy P"),
             "K_mds": next(c for c in cases if c["kind"] == "paper" and c["plant"] == "static" and c["f"] == 0.0
                           and c["controller"] == "linear P")}
    for label, c in picks.items():
        ax2.plot(c["t"], c["y"], label=f"{label}: e(∞) = {float(c['e_sim']):.4f}")
    ax2.set_xlim(0, 3)
    ax2.set_xlabel("t, s")
    ax2.set_ylabel("y")
    ax2.grid(alpha=0.3)
    ax2.legend()
    ax2.set_title("(b) transients, static plant, g = 1, f = 0")
    fig.suptitle("Fig. 3 (FC1 assumed)")
    fig.tight_layout()
    return fig


def _plot_transients(cases, title):
    import matplotlib.pyplot as plt

    fs = sorted({c["f"] for c in cases})
    fig, axes = plt.subplots(1, len(fs), figsize=(6 * len(fs), 4.5))
    for ax, f in zip(np.atleast_1d(axes), fs):
        for c in (c for c in cases if c["f"] == f):
            ax.plot(c["t"], c["y"], label=f"{c['controller']}: e(∞) = {float(c['e_sim']):.4f}, "
                    f"t_s = {float(c['settling']):.3f} s, σ = {float(c['overshoot']):.2f} %")
        ax.axhline(1.0, color="k", lw=0.6)
        ax.set_xlim(0, 3)
        ax.set_xlabel("t, s")
        ax.set_ylabel("y")
        ax.set_title(f"f = {f}")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def _plot_fig6(cfg, fig6):
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.5))
    for label, c in fig6.items():
        ax1.plot(c["t"], c["y"], label=f"{label}: t_s = {float(c['settling']):.3f} s, σ = {float(c['overshoot']):.2f} %")
        ax2.semilogy(c["t"], np.abs(1.0 - c["y"]) + 1e-16, label=label)
    ax1.axhline(1.0, color="k", lw=0.6)
    ax1.set_xlim(0, 5)
    ax1.set_xlabel("t, s")
    ax1.set_ylabel("y")
    ax1.legend(fontsize=8)
    ax1.grid(alpha=0.3)
    ax2.set_xlim(0, 8)
    ax2.set_ylim(1e-8, 2)
    ax2.set_xlabel("t, s")
    ax2.set_ylabel("|e(t)|")
    ax2.legend(fontsize=8)
    ax2.grid(alpha=0.3)
    fig.suptitle(f"Fig. 6: astatic plant, PI at maximum stability vs fuzzy PI (g = 1, f = {cfg.fig6_f})")
    fig.tight_layout()
    return fig


def _plot_grid(rows):
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 5))
    markers = {"linear P": "o", "fuzzy P": "s", "linear PI": "^", "fuzzy PI": "D"}
    for ctrl, m in markers.items():
        sel = [r for r in rows if r["controller"] == ctrl and r["steady_state_analytic"]]
        ax.scatter([r["e_analytic"] for r in sel], [r["e_simulated"] for r in sel], marker=m,
                   facecolors="none", edgecolors=f"C{list(markers).index(ctrl)}", label=ctrl)
    lim = max(abs(r["e_analytic"]) for r in rows if r["steady_state_analytic"]) * 1.1
    ax.plot([-lim, lim], [-lim, lim], "k-", lw=0.6)
    n_none = sum(not r["steady_state_analytic"] for r in rows)
    n_det = sum((not r["steady_state_analytic"]) and (not r["steady_state_simulated"]) for r in rows)
    ax.set_title(f"steady-state error: analytic vs simulated\n(no steady state: {n_det}/{n_none} detected)")
    ax.set_xlabel("analytic e(∞)")
    ax.set_ylabel("simulated e(T)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


STUDY = Study(
    name="fuzzy_pid_accuracy",
    description="Fuzzy-PID paper: steady-state accuracy of fuzzy vs linear P/PI control, analytic vs simulated, Figs. 2–6",
    config_cls=Config,
    run=run,
)
