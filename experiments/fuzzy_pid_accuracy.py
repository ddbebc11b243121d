"""Study ``fuzzy_pid_accuracy``: steady-state accuracy of fuzzy vs linear control (the fuzzy-PID paper).

Seed 000, paper 1 (spec ``seed000_fuzzy_pid_smo_predictor.md`` §1.1–1.4); plants, controllers and the
batched simulation of cases are :mod:`jaxsim.problem.fuzzy_accuracy`.

1. The linear baselines are designed by :func:`jaxsim.control.stability_degree.max_stability_degree`
   (P: ``K_mds`` = 0.4 and 1.25, PI: triple-root designs) — computed, not typed in.
2. The paper's four cases (static g = 1, f = 0 / 0.3; astatic g = 1 with f = 0.2 / 0.7) are solved
   analytically (:mod:`jaxsim.control.fuzzy_steady_state`: equations (1)/(2) and their domains) and
   simulated in closed loop; settling time (2 %) and overshoot of every case come from the simulation.
3. Analytic vs simulated steady-state error over a grid of ``(g, f, K_g, K_f)`` for linear/fuzzy
   P and PI on both plants, including the cases without a steady state (detected as drift).
4. Figures 2–6 of the paper: a Mamdani controller fitted to the paper's characteristic and its
   three-section least-squares approximation (Fig. 2), FC1/FC2 vs ``K_mds`` (Fig. 3), the
   transients of the four cases (Figs. 4–5) and fuzzy PI vs linear PI (Fig. 6).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np
import optax

from experiments import figures, stages
from experiments.runner import Claim, Study, StudyResult, paper_facts
from jaxsim.control import fuzzy as fz
from jaxsim.control.fuzzy_steady_state import section_domains, steady_state_error
from jaxsim.problem.fuzzy_accuracy import (
    CONTROLLERS,
    PLANTS,
    AccuracySetup,
    Case,
    channels,
    designs,
    mamdani_fit_problem,
    run_all,
    small_gain,
)


@dataclass(frozen=True)
class Config(AccuracySetup):  # + the plants, characteristics, fuzzy PI and simulation of AccuracySetup
    g: float = 1.0  # "single step reference g = 1"
    f_static: tuple = (0.0, 0.3)  # Fig. 4a, 4b
    f_astatic: tuple = (0.2, 0.7)  # Fig. 5a, 5b
    fc1_static: tuple = (0.5, 0.3, 1.2, 1.0)  # Fig. 3 "FC1" (larger K1): assumed
    fig6_f: float = 0.5  # Fig. 6 constant disturbance (assumed)
    grid_g: tuple = (0.5, 1.5)
    grid_f: tuple = (0.0, 0.3, 0.8, 2.5)
    grid_g_slope: tuple = (0.0, 0.3)
    grid_f_slope: tuple = (0.0, 0.15, 2.0)
    mamdani_fit_steps: int = 400  # Fig. 2: Adam steps fitting the Mamdani to the characteristic


PRESETS = {"quick": dict(grid_g=(1.5,), grid_f=(0.3, 2.5), mamdani_fit_steps=60)}
SOURCE = "seed 000 paper 1, §1.4 (spec; the paper prints two decimals)"
CLAIMS = [
    Claim("kp_mds_static", paper=0.4, rel_tol=1e-6, source="seed 000 paper 1, §1.3: K_mds = 0.4 (static plant)"),
    Claim("kp_mds_astatic", paper=1.25, rel_tol=1e-6, source="seed 000 paper 1, §1.3: K_mds = 1.25 (astatic plant)"),
    *(
        Claim(f"ess_{case}", paper=v, abs_tol=0.005, source=f"{SOURCE}, item {item}", note=note)
        for case, v, item, note in (
            ("static_f0_fuzzy", 0.56, 1, "exact 5/9"),
            ("static_f0_linear", 0.56, 1, "exact 5/9"),
            ("static_f03_fuzzy", 0.81, 2, "eq. (2)"),
            ("static_f03_linear", 0.89, 2, "exact 8/9"),
            ("astatic_f02_fuzzy", 0.16, 3, "f/K1"),
            ("astatic_f02_linear", 0.16, 3, "f/K1"),
            ("astatic_f07_fuzzy", 0.46, 4, "a + (f − b)/K2"),
            ("astatic_f07_linear", 0.56, 4, "the paper's formula is lost; f/K_mds [ours]"),
        )
    ),
]

_, ASSUMPTIONS = paper_facts("fuzzy_pid_accuracy")


def _case_key(plant: str, f: float) -> str:
    return f"{plant}_f{f:g}".replace(".", "")  # f = 0.3 → "static_f03"


def build_cases(cfg: Config, gains: dict) -> list[Case]:
    """The paper's four cases (fuzzy and linear P), Fig. 3's FC1, Fig. 6's PIs and the grid."""
    cases: list[Case] = []
    paper_f = {"static": cfg.f_static, "astatic": cfg.f_astatic}
    for plant in PLANTS:
        for f in paper_f[plant]:
            for ctrl in ("fuzzy P", "linear P"):
                p, i = channels(cfg, gains, plant, ctrl)
                cases.append(
                    Case(kind="paper", plant=plant, controller=ctrl, p=p, i=i, g=cfg.g, g_slope=0.0, f=f, f_slope=0.0)
                )
    cases.append(
        Case(
            kind="fig3",
            plant="static",
            controller="FC1",
            p=fz.three_section(*cfg.fc1_static),
            i=None,
            g=cfg.g,
            g_slope=0.0,
            f=0.0,
            f_slope=0.0,
        )
    )
    for ctrl in ("linear PI", "fuzzy PI"):
        p, i = channels(cfg, gains, "astatic", ctrl)
        cases.append(
            Case(
                kind="fig6", plant="astatic", controller=ctrl, p=p, i=i, g=cfg.g, g_slope=0.0, f=cfg.fig6_f, f_slope=0.0
            )
        )
    grid = list(itertools.product(cfg.grid_g, cfg.grid_f, cfg.grid_g_slope, cfg.grid_f_slope))
    for plant in PLANTS:
        for ctrl in CONTROLLERS:
            p, i = channels(cfg, gains, plant, ctrl)
            cases += [
                Case(kind="grid", plant=plant, controller=ctrl, p=p, i=i, g=g, g_slope=kg, f=f, f_slope=kf)
                for g, f, kg, kf in grid
            ]
    K = {"static": cfg.K_static, "astatic": cfg.K_astatic}
    for c in cases:
        c["op"] = steady_state_error(
            c["plant"], K[c["plant"]], c["p"], c["i"], g=c["g"], g_slope=c["g_slope"], f=c["f"], f_slope=c["f_slope"]
        )
    return cases


def paper_rows(cfg: Config, cases: list[Case]) -> tuple[dict[str, float], list[dict[str, Any]]]:
    """Metrics and table of the paper's four cases (analytic vs simulated, settling, overshoot)."""
    metrics, rows = {}, []
    for c in (c for c in cases if c["kind"] == "paper"):
        name = _case_key(c["plant"], c["f"]) + ("_fuzzy" if c["controller"] == "fuzzy P" else "_linear")
        op, e_sim = c["op"], float(c["e_sim"])
        metrics |= {
            f"ess_{name}": e_sim,
            f"ess_{name}_analytic": op.error,
            f"settling_{name}": float(c["settling"]),
            f"overshoot_{name}": float(c["overshoot"]),
        }
        lim1, lim2 = section_domains(c["plant"], cfg.K_static if c["plant"] == "static" else cfg.K_astatic, c["p"])
        rows.append(
            {
                "plant": c["plant"],
                "g": c["g"],
                "f": c["f"],
                "controller": c["controller"],
                "K1": small_gain(c["p"]),
                "demand": op.demand,
                "section": op.section,
                "equation": op.equation,
                "domain_section1_upper": lim1,
                "domain_section2_upper": lim2,
                "e_analytic": op.error,
                "e_simulated": e_sim,
                "abs_difference": abs(op.error - e_sim),
                "settling_time_2pct_s": float(c["settling"]),
                "overshoot_pct": float(c["overshoot"]),
            }
        )
    metrics["paper_cases_max_abs_difference"] = max(r["abs_difference"] for r in rows)
    return metrics, rows


def grid_rows(cases: list[Case]) -> tuple[dict[str, float], list[dict[str, Any]]]:
    """Analytic vs simulated steady-state error over the grid; relative error |Δe| / max(|e_an|, g)."""
    rows = []
    for c in (c for c in cases if c["kind"] == "grid"):
        op = c["op"]
        scale = max(abs(op.error), abs(c["g"])) if op.exists else np.nan
        rows.append(
            {
                "plant": c["plant"],
                "controller": c["controller"],
                "g": c["g"],
                "g_slope": c["g_slope"],
                "f": c["f"],
                "f_slope": c["f_slope"],
                "section": op.section,
                "channel": op.channel,
                "equation": op.equation,
                "e_analytic": op.error,
                "e_simulated": float(c["e_sim"]),
                "steady_state_analytic": bool(op.exists),
                "steady_state_simulated": bool(c["converged"]),
                "relative_error": abs(float(c["e_sim"]) - op.error) / scale if op.exists else np.nan,
            }
        )
    finite = [r for r in rows if r["steady_state_analytic"]]
    none = [r for r in rows if not r["steady_state_analytic"]]
    metrics = {
        "grid_n_cases": len(rows),
        "grid_n_finite": len(finite),
        "grid_n_finite_converged": sum(r["steady_state_simulated"] for r in finite),
        "grid_max_relative_error": max(r["relative_error"] for r in finite),
        "grid_n_no_steady_state": len(none),
        "grid_n_no_steady_state_detected": sum(not r["steady_state_simulated"] for r in none),
        **{f"grid_n_section{s}": sum(r["section"] == s for r in finite) for s in (1, 2, 3)},
    }
    return metrics, rows


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    gains = designs(cfg)
    cases = build_cases(cfg, gains)
    run_all(cfg, cases, progress)
    metrics = {
        "kp_mds_static": gains[("static", "P")]["kp"],
        "kp_mds_astatic": gains[("astatic", "P")]["kp"],
        **{f"pi_mds_{plant}_{k}": gains[(plant, "PI")][k] for plant in PLANTS for k in ("kp", "ki")},
    }
    m_paper, paper = paper_rows(cfg, cases)
    fig6 = {c["controller"]: c for c in cases if c["kind"] == "fig6"}
    for label, key in (("linear PI", "linear_pi"), ("fuzzy PI", "fuzzy_pi")):
        metrics |= {
            f"fig6_{q}_{key}": float(fig6[label][k])
            for q, k in (("settling", "settling"), ("overshoot", "overshoot"), ("ess", "e_sim"))
        }
    m_grid, grid = grid_rows(cases)

    e = jnp.linspace(-2.0, 2.0, 201)
    problem, build = mamdani_fit_problem(fz.three_section(*cfg.fc_static), e)
    fit_stage = stages.gradient_tuning(  # the last of steps + 1 evaluations is the point after `steps` updates
        problem,
        steps=cfg.mamdani_fit_steps + 1,
        optimizer=optax.adam(0.03),
        mode="reverse",
        loss_label="mean-square deviation from the paper's FC",
        table="mamdani_fit_history",
        figure="mamdani_fit",
    )
    mamdani = build(fit_stage.result.params)
    u_mamdani = np.asarray(jax.jit(fz.static_characteristic)(mamdani, e))
    fit = fz.fit_three_section(e, u_mamdani)
    metrics |= {
        **m_paper,
        **m_grid,
        **{f"fig2_fit_{k}": v for k, v in zip("abcd", fit.abcd)},
        "fig2_fit_rms": fit.rms,
        "fig2_mamdani_rms_to_paper_fc": float(np.sqrt(fit_stage.result.loss)),
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
    tables = {
        "paper_cases": paper,
        "steady_state_grid": grid,
        "fig6_pi": [
            {
                "controller": k,
                "settling_time_2pct_s": float(v["settling"]),
                "overshoot_pct": float(v["overshoot"]),
                "e_final": float(v["e_sim"]),
            }
            for k, v in fig6.items()
        ],
    }
    own = stages.Stage(
        tables=tables,
        figures=paper_figures(cfg, cases, gains, e, u_mamdani, fit) | {"steady_state_grid": _plot_grid(grid)},
    )
    return stages.merge(own, fit_stage, metrics=metrics, notes=notes)


_evaluate = jax.jit(lambda char, e: char(e))  # characteristics on a grid, for plots


def paper_figures(cfg: Config, cases: list[Case], gains: dict, e: Any, u_mamdani: Any, fit: Any) -> dict[str, Any]:
    """Figs. 2–6 of the paper, as :func:`figures.line_panels`."""
    kmds, e2 = gains[("static", "P")]["kp"], np.linspace(0, 2.0, 401)
    fc1, fc2 = fz.three_section(*cfg.fc1_static), fz.three_section(*cfg.fc_static)
    fig2 = figures.line_panels(
        [
            {
                "lines": {
                    "1: Mamdani FC (centroid)": (e, u_mamdani),
                    "2: three-section fit a={:.3f} b={:.3f} c={:.3f} d={:.3f}".format(*fit.abcd): (
                        e,
                        _evaluate(fit.params, e),
                        "--",
                    ),
                    "paper's FC (0.75, 0.3, 1.2, 1)": (e, _evaluate(fc2, e), ":"),
                    "linear K_mds·e": (e, kmds * np.asarray(e)),
                },
                "x_label": "e",
                "y_label": "u",
                "ylim": (-1.4, 1.4),
                "title": "Fig. 2: static characteristic of the FC and its approximation",
            }
        ]
    )
    pick = {
        c["controller"] if c["kind"] == "fig3" else ("FC2" if c["controller"] == "fuzzy P" else "K_mds"): c
        for c in cases
        if c["kind"] == "fig3" or (c["kind"] == "paper" and c["plant"] == "static" and c["f"] == 0.0)
    }
    fig3 = figures.line_panels(
        [
            {
                "lines": {
                    f"FC1 (K1 = {small_gain(fc1):.2f})": (e2, _evaluate(fc1, e2)),
                    f"FC2 (K1 = {small_gain(fc2):.2f})": (e2, _evaluate(fc2, e2)),
                    f"K_mds = {kmds:.3g}": (e2, kmds * e2, "k--"),
                },
                "x_label": "e",
                "y_label": "u",
                "ylim": (0, 1.3),
                "title": "(a) static characteristics",
            },
            {
                "lines": {
                    f"{k}: e(∞) = {float(pick[k]['e_sim']):.4f}": (pick[k]["t"], pick[k]["y"])
                    for k in ("FC1", "FC2", "K_mds")
                },
                "x_label": "t, s",
                "y_label": "y",
                "xlim": (0, 3),
                "title": "(b) transients, static plant, g = 1, f = 0",
            },
        ],
        title="Fig. 3 (FC1 assumed)",
    )
    out = {"fig2_static_characteristic": fig2, "fig3_fc1_fc2_kmds": fig3}
    for plant, name, fig in (
        ("static", "fig4_static_transients", "Fig. 4"),
        ("astatic", "fig5_astatic_transients", "Fig. 5"),
    ):
        sel = [c for c in cases if c["kind"] == "paper" and c["plant"] == plant]
        out[name] = figures.line_panels(
            [
                {
                    "lines": {
                        f"{c['controller']}: e(∞) = {float(c['e_sim']):.4f}, t_s = {float(c['settling']):.3f} s, "
                        f"σ = {float(c['overshoot']):.2f} %": (c["t"], c["y"])
                        for c in sel
                        if c["f"] == f
                    },
                    "x_label": "t, s",
                    "y_label": "y",
                    "xlim": (0, 3),
                    "hline": 1.0,
                    "title": f"f = {f}",
                }
                for f in sorted({c["f"] for c in sel})
            ],
            title=f"{fig}: {plant} plant, g = 1",
        )
    fig6 = {c["controller"]: c for c in cases if c["kind"] == "fig6"}
    out["fig6_pi_astatic"] = figures.line_panels(
        [
            {
                "lines": {
                    f"{k}: t_s = {float(c['settling']):.3f} s, σ = {float(c['overshoot']):.2f} %": (c["t"], c["y"])
                    for k, c in fig6.items()
                },
                "x_label": "t, s",
                "y_label": "y",
                "xlim": (0, 5),
                "hline": 1.0,
            },
            {
                "lines": {k: (c["t"], np.abs(1.0 - c["y"]) + 1e-16) for k, c in fig6.items()},
                "x_label": "t, s",
                "y_label": "|e(t)|",
                "xlim": (0, 8),
                "ylim": (1e-8, 2),
                "log_y": True,
            },
        ],
        title=f"Fig. 6: astatic plant, PI at maximum stability vs fuzzy PI (g = 1, f = {cfg.fig6_f})",
    )
    return out


def _plot_grid(rows: list[dict[str, Any]]):
    plt = figures._plt()
    fig, ax = plt.subplots(figsize=(6.5, 5))
    for k, ctrl in enumerate(CONTROLLERS):
        sel = [r for r in rows if r["controller"] == ctrl and r["steady_state_analytic"]]
        ax.scatter(
            [r["e_analytic"] for r in sel],
            [r["e_simulated"] for r in sel],
            marker="os^D"[k],
            facecolors="none",
            edgecolors=f"C{k}",
            label=ctrl,
        )
    lim = max(abs(r["e_analytic"]) for r in rows if r["steady_state_analytic"]) * 1.1
    ax.plot([-lim, lim], [-lim, lim], "k-", lw=0.6)
    n_none = sum(not r["steady_state_analytic"] for r in rows)
    n_det = sum((not r["steady_state_analytic"]) and (not r["steady_state_simulated"]) for r in rows)
    ax.set(
        title=f"steady-state error: analytic vs simulated\n(no steady state: {n_det}/{n_none} detected)",
        xlabel="analytic e(∞)",
        ylabel="simulated e(T)",
    )
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


STUDY = Study(
    name="fuzzy_pid_accuracy",
    description="Fuzzy-PID paper: steady-state accuracy of fuzzy vs linear control, analytic vs simulated, Figs. 2–6",
    config=Config,
    presets=PRESETS,
    claims=CLAIMS,
    assumptions=ASSUMPTIONS,
    run=run,
)
