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
from experiments.runner import Study, StudyResult, paper_facts
from jaxsim.control import fuzzy as fz
from jaxsim.control.fuzzy_steady_state import section_domains
from jaxsim.problem.fuzzy_accuracy import (
    CONTROLLERS,
    PLANTS,
    AccuracySetup,
    Case,
    channels,
    designs,
    make_case,
    mamdani_fit_problem,
    plant_gain,
    run_all,
    small_gain,
    with_steady_states,
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
CLAIMS, ASSUMPTIONS = paper_facts("fuzzy_pid_accuracy")


def _case_key(plant: str, f: float) -> str:
    return f"{plant}_f{f:g}".replace(".", "")  # f = 0.3 → "static_f03"


def build_cases(cfg: Config, gains: dict) -> list[Case]:
    """The paper's four cases (fuzzy and linear P), Fig. 3's FC1, Fig. 6's PIs and the grid, each with its
    analytic steady state."""

    def case(kind, plant, ctrl, g=cfg.g, f=0.0, g_slope=0.0, f_slope=0.0, chars=None):
        return make_case(kind, plant, ctrl, chars or channels(cfg, gains, plant, ctrl), g, f, g_slope, f_slope)

    paper_f = {"static": cfg.f_static, "astatic": cfg.f_astatic}
    grid = list(itertools.product(cfg.grid_g, cfg.grid_f, cfg.grid_g_slope, cfg.grid_f_slope))
    return with_steady_states(
        cfg,
        [
            case("paper", plant, ctrl, f=f)
            for plant in PLANTS
            for f in paper_f[plant]
            for ctrl in ("fuzzy P", "linear P")
        ]
        + [case("fig3", "static", "FC1", chars=(fz.three_section(*cfg.fc1_static), None))]
        + [case("fig6", "astatic", ctrl, f=cfg.fig6_f) for ctrl in ("linear PI", "fuzzy PI")]
        + [case("grid", pl, ctrl, g, f, kg, kf) for pl in PLANTS for ctrl in CONTROLLERS for g, f, kg, kf in grid],
    )


def _fields(source: Any, *names: str) -> dict[str, Any]:
    """``{name: source[name]}`` (a case) or ``{name: source.name}`` (an operating point), in order."""
    return {k: source[k] if isinstance(source, dict) else getattr(source, k) for k in names}


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
        lim1, lim2 = section_domains(c["plant"], plant_gain(cfg, c["plant"]), c["p"])
        rows.append(
            {
                **_fields(c, "plant", "g", "f", "controller"),
                "K1": small_gain(c["p"]),
                **_fields(op, "demand", "section", "equation"),
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
                **_fields(c, "plant", "controller", "g", "g_slope", "f", "f_slope"),
                **_fields(op, "section", "channel", "equation"),
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
    sim = ("settling", "overshoot", "e_sim")
    fig6 = [{"controller": c["controller"], **{k: float(c[k]) for k in sim}} for c in cases if c["kind"] == "fig6"]
    for r in fig6:  # "linear PI" → fig6_settling_linear_pi, fig6_overshoot_linear_pi, fig6_ess_linear_pi
        key = r["controller"].lower().replace(" ", "_")
        metrics |= {
            f"fig6_{q}_{key}": r[k] for q, k in (("settling", "settling"), ("overshoot", "overshoot"), ("ess", "e_sim"))
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

    pi_p, pi_i = (
        tuple(round(float(v), 4) for v in (c.a, c.b, c.c, c.d)) for c in channels(cfg, gains, "astatic", "fuzzy PI")
    )
    notes = [
        f"simulation: RK4, dt = controller period = {cfg.dt} s, horizon {cfg.t_final} s; "
        f"steady state = last sample; no steady state = drift over the last {cfg.drift_window} s above rtol "
        f"{cfg.drift_rtol}",
        "settling time: 2 % band around the final output (python-control's definition), overshoot in %",
        f"fuzzy PI (astatic) channels: P (a, b, c, d) = {pi_p}, I = {pi_i}",
    ]
    tables = {
        "paper_cases": paper,
        "steady_state_grid": grid,
        "fig6_pi": [
            dict(zip(("controller", "settling_time_2pct_s", "overshoot_pct", "e_final"), r.values())) for r in fig6
        ],
    }
    own = stages.Stage(
        tables=tables,
        figures=paper_figures(cfg, cases, gains, e, u_mamdani, fit) | {"steady_state_grid": grid_figure(grid)},
    )
    return stages.merge(own, fit_stage, metrics=metrics, notes=notes)


_evaluate = jax.jit(lambda char, e: char(e))  # characteristics on a grid, for plots


def paper_figures(cfg: Config, cases: list[Case], gains: dict, e: Any, u_mamdani: Any, fit: Any) -> dict[str, Any]:
    """Figs. 2–6 of the paper, as :func:`figures.line_panels`."""
    kmds, e2 = gains[("static", "P")]["kp"], np.linspace(0, 2.0, 401)
    fc1, fc2 = fz.three_section(*cfg.fc1_static), fz.three_section(*cfg.fc_static)
    fig2 = {
        "1: Mamdani FC (centroid)": (e, u_mamdani),
        "2: three-section fit a={:.3f} b={:.3f} c={:.3f} d={:.3f}".format(*fit.abcd): (
            e,
            _evaluate(fit.params, e),
            "--",
        ),
        "paper's FC (0.75, 0.3, 1.2, 1)": (e, _evaluate(fc2, e), ":"),
        "linear K_mds·e": (e, kmds * np.asarray(e)),
    }
    fig2_title = "Fig. 2: static characteristic of the FC and its approximation"
    chars = {
        f"FC1 (K1 = {small_gain(fc1):.2f})": (e2, _evaluate(fc1, e2)),
        f"FC2 (K1 = {small_gain(fc2):.2f})": (e2, _evaluate(fc2, e2)),
        f"K_mds = {kmds:.3g}": (e2, kmds * e2, "k--"),
    }
    pick = {  # the paper's FC (FC2) and K_mds: the static f = 0 cases
        "FC2" if c["controller"] == "fuzzy P" else "K_mds" if c["kind"] == "paper" else c["controller"]: c
        for c in cases
        if c["kind"] == "fig3" or (c["kind"] == "paper" and c["plant"] == "static" and c["f"] == 0.0)
    }
    fig3 = {
        f"{k}: e(∞) = {float(c['e_sim']):.4f}": (c["t"], c["y"])
        for k, c in ((k, pick[k]) for k in ("FC1", "FC2", "K_mds"))
    }
    out = {
        "fig2_static_characteristic": figures.line_panels(
            [figures.panel(fig2, "e", "u", ylim=(-1.4, 1.4), title=fig2_title)]
        ),
        "fig3_fc1_fc2_kmds": figures.line_panels(
            [
                figures.panel(chars, "e", "u", ylim=(0, 1.3), title="(a) static characteristics"),
                figures.panel(fig3, "t, s", "y", xlim=(0, 3), title="(b) transients, static plant, g = 1, f = 0"),
            ],
            title="Fig. 3 (FC1 assumed)",
        ),
    }
    for plant, name, fig in (("static", "fig4_static_transients", 4), ("astatic", "fig5_astatic_transients", 5)):
        sel = [c for c in cases if c["kind"] == "paper" and c["plant"] == plant]
        lines = {
            f: {_transient_label(c): (c["t"], c["y"]) for c in sel if c["f"] == f}
            for f in sorted({c["f"] for c in sel})
        }
        out[name] = figures.line_panels(
            [figures.panel(v, "t, s", "y", xlim=(0, 3), hline=1.0, title=f"f = {f}") for f, v in lines.items()],
            title=f"Fig. {fig}: {plant} plant, g = 1",
        )
    fig6 = {c["controller"]: c for c in cases if c["kind"] == "fig6"}
    y = {_transient_label(c, e_final=False): (c["t"], c["y"]) for c in fig6.values()}
    abs_e = {k: (c["t"], np.abs(1.0 - c["y"]) + 1e-16) for k, c in fig6.items()}
    out["fig6_pi_astatic"] = figures.line_panels(
        [
            figures.panel(y, "t, s", "y", xlim=(0, 5), hline=1.0),
            figures.panel(abs_e, "t, s", "|e(t)|", xlim=(0, 8), ylim=(1e-8, 2), log_y=True),
        ],
        title=f"Fig. 6: astatic plant, PI at maximum stability vs fuzzy PI (g = 1, f = {cfg.fig6_f})",
    )
    return out


def _transient_label(c: Case, e_final: bool = True) -> str:
    e = f"e(∞) = {float(c['e_sim']):.4f}, " if e_final else ""
    return f"{c['controller']}: {e}t_s = {float(c['settling']):.3f} s, σ = {float(c['overshoot']):.2f} %"


def grid_figure(rows: list[dict[str, Any]]):
    """Analytic vs simulated steady-state error of the grid cases that have one, per controller."""
    finite = [r for r in rows if r["steady_state_analytic"]]
    none = [r for r in rows if not r["steady_state_analytic"]]
    points = {
        ctrl: tuple([r[k] for r in finite if r["controller"] == ctrl] for k in ("e_analytic", "e_simulated"))
        for ctrl in CONTROLLERS
    }
    n_det = sum(not r["steady_state_simulated"] for r in none)
    title = f"steady-state error: analytic vs simulated\n(no steady state: {n_det}/{len(none)} detected)"
    return figures.parity(points, x_label="analytic e(∞)", y_label="simulated e(T)", title=title)


STUDY = Study(
    name="fuzzy_pid_accuracy",
    description="Fuzzy-PID paper: steady-state accuracy of fuzzy vs linear control, analytic vs simulated, Figs. 2–6",
    config=Config,
    presets=PRESETS,
    claims=CLAIMS,
    assumptions=ASSUMPTIONS,
    run=run,
)
