"""Study ``fuzzy_pid_tuning``: tuning the fuzzy-PID paper's fuzzy controller.

Seed 000, paper 1 (spec §1.5): the paper picks the breakpoints ``(a, b, c, d)`` of its fuzzy P
controller by hand ("from the requirement of a monotonic transient", procedure not given).  Here
they are tuned on the static plant ``2/((0.1s+1)(0.5s+1))`` over a set of operating points
``(g, f)``: minimise ``J = mean_i ITAE_i + (w/2)·Σ_k max(0, h_k)²`` with the constraints ``h ≤ 0``
(e_ss no worse than the linear maximum-stability P controller, overshoot ≤ σ_max, |u| ≤ u_max) of
:class:`jaxsim.problem.fuzzy_tuning.FuzzyPTuning` — the same ``J`` for every method.

``e = (a, c)``, ``u = (b, d)`` are declared :class:`~jaxsim.problem.Sorted` (search coordinates
``(a, c − a, b, d − b)``: the box of swarm and grid).  Methods, on equal budgets of loss evaluations
(each simulates every point), through :func:`experiments.stages.tune_and_compare`: gradient (Adam,
forward mode, ``n_starts`` starts from the paper's controller, augmented Lagrangian, on the smooth
characteristic and overshoot surrogate; re-scored with the exact ``J``), :func:`optim.pso` and
:func:`optim.grid_search` (exact ``J``); references: the paper's controller and the linear
maximum-stability one.

Then a full Mamdani and a zero-order Sugeno controller (:mod:`jaxsim.control.fuzzy.templates`,
seven input terms) have their membership-function breakpoints tuned directly by gradient (same
objective and constraints), and their static characteristics are plotted with their three-section
fits.  The zero-order Sugeno template reproduces a piecewise-linear characteristic exactly, so its
initial point *is* the paper's controller.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np
import optax

from experiments import figures, stages
from experiments.runner import Study, StudyResult, paper_facts
from jaxsim.control import fuzzy as fz
from jaxsim.problem import ParamSpace, Sorted
from jaxsim.problem.fuzzy_tuning import FuzzyPSetup, FuzzyPTuning, three_section_of
from optim import grid_search, pso, tune


@dataclass(frozen=True)
class Config(FuzzyPSetup):  # + plant, operating points, constraints, timing and box of FuzzyPSetup
    budget: int = 256  # loss evaluations per method
    learning_rate: float = 0.05
    smooth_temperature: float = 0.01  # error units: softplus corners of the smooth characteristic
    n_starts: int = 8  # gradient: starts stepping together (steps = budget / n_starts)
    init_spread: float = 1.0  # gradient: spread of the extra starts in unconstrained space
    pso_particles: int = 16  # iterations = budget / particles
    grid_points_per_dim: int = 4  # 4⁴ = 256 = budget
    fis_steps: int = 150  # gradient steps for the Mamdani and Sugeno controllers
    fis_learning_rate: float = 0.02
    fis_grid: int = 101  # Mamdani output grid
    seed: int = 0


CLAIMS, ASSUMPTIONS = paper_facts("fuzzy_pid_tuning")


def report(
    loop: FuzzyPTuning, char: Any, name: str, sims: int = 0, wall_s: float = 0.0, compile_s: float = 0.0
) -> dict:
    """Exact J and closed-loop metrics of one tuned (or reference) characteristic."""
    J, (f, h, d) = loop.exact(char)
    row = {
        "method": name,
        "loss_J": float(J),
        "mean_itae": float(f),
        "max_violation": float(jnp.max(h)),
        "feasible": bool(jnp.all(h <= 1e-9)),
        "settling_mean_s": float(jnp.mean(d["settling"])),
        "settling_max_s": float(jnp.max(d["settling"])),
        "overshoot_max_pct": float(jnp.max(d["overshoot"])),
        "u_peak": float(d["u_peak"]),
        "e_ss_over_linear_max": float(jnp.max(d["e_final"] / loop.e_lin)),
        "sims": int(sims),
        "wall_s": float(wall_s),
        "compile_s": float(compile_s),
    }
    if isinstance(char, fz.ThreeSection):
        row.update({k: float(getattr(char, k)) for k in "abcd"})
        row["K1"], row["K2"] = (
            float(char.b) / float(char.a),
            (float(char.d) - float(char.b)) / (float(char.c) - float(char.a)),
        )
    return row


def compare_three_section(loop: FuzzyPTuning, cfg: Config, progress: Callable[..., Any]):
    """Gradient (smooth surrogate, augmented Lagrangian), PSO and grid (exact J), equal budgets."""
    n_pts, budget = len(cfg.operating_points), cfg.budget
    if cfg.grid_points_per_dim**4 > budget or budget % cfg.pso_particles or budget % cfg.n_starts:
        raise ValueError("budget: must be a multiple of pso_particles and n_starts, and ≥ grid_points_per_dim**4")
    space = loop.three_section_space()
    exact = loop.problem("fuzzy_p_exact", space, lambda p: three_section_of(p, cfg.smooth_temperature, "exact"), False)
    smooth = loop.problem(
        "fuzzy_p_smooth", space, lambda p: three_section_of(p, cfg.smooth_temperature, "smooth"), True
    )
    key = jax.random.PRNGKey(cfg.seed)
    tuners = {
        "gradient": lambda _, __: tune(
            smooth,
            optimizer=optax.adam(cfg.learning_rate),
            steps=budget // cfg.n_starts,
            n_starts=cfg.n_starts,
            key=key,
            init_spread=cfg.init_spread,
            constraint_method="augmented_lagrangian",
            sims_per_eval=n_pts,
            mode="forward",
        ),
        "pso": lambda pb, _: pso(
            pb, n_particles=cfg.pso_particles, n_iters=budget // cfg.pso_particles, key=key, sims_per_eval=n_pts
        ),
        "grid": lambda pb, _: grid_search(pb, points_per_dim=cfg.grid_points_per_dim, sims_per_eval=n_pts),
    }
    cmp = stages.tune_and_compare(
        exact,
        budget * n_pts,
        tuners,
        progress=progress,
        figure="tuning_comparison",
        loss_label="J (gradient: smooth surrogate), s²",
        title="fuzzy P (a, b, c, d): J vs budget (simulations = evaluations × points)",
    )
    cmp.notes = [f"budget {budget} loss evaluations per method, each simulating {n_pts} operating points"]
    rows = [
        report(
            loop,
            three_section_of(cmp.designs[name], cfg.smooth_temperature, "exact"),
            name,
            r.n_sims,
            r.wall_s,
            getattr(r, "compile_s", 0.0),
        )
        for name, r in cmp.comparison.results.items()
    ]
    rows.append(report(loop, fz.three_section(*cfg.paper_fc), "paper"))
    rows.append(report(loop, fz.linear(loop.k_mds), "linear K_mds"))
    return rows, cmp


def run_fis(loop: FuzzyPTuning, cfg: Config, kind: str):
    """Tune the breakpoints of a 7-term Mamdani or Sugeno P controller by gradient on the same J."""
    u_range = 1.6 * cfg.u_max
    decl = dict(
        e=Sorted(lo=0.02, hi=2.0, init=(0.375, 0.75, 1.2), min_gap=0.02),
        u=Sorted(lo=0.0, hi=2.0, init=(0.15, 0.3, 1.0)),
    )
    if kind == "mamdani":
        decl["width"] = Sorted(lo=0.0, hi=1.0, init=(0.1,), origin=0.01)  # one value > 0.01

    def build(p):
        if kind == "mamdani":
            return fz.odd_mamdani(p["e"], p["u"], p["width"][0], u_range=u_range, n_grid=cfg.fis_grid)
        return fz.odd_sugeno(p["e"], p["u"])

    problem = loop.problem(f"fuzzy_p_{kind}", ParamSpace(**decl), build, True)
    res = tune(
        problem,
        optimizer=optax.adam(cfg.fis_learning_rate),
        steps=cfg.fis_steps,
        constraint_method="augmented_lagrangian",
        sims_per_eval=len(cfg.operating_points),
        mode="forward",
    )
    fis0, fis = build(problem.space.init), build(res.params)
    row = report(loop, fis, f"{kind} (gradient)", res.n_sims, res.wall_s, res.compile_s)
    row0, e, char = (
        report(loop, fis0, f"{kind} (initial)"),
        jnp.linspace(-2.5, 2.5, 251),
        jax.jit(fz.static_characteristic),
    )
    u0, u = np.asarray(char(fis0, e)), np.asarray(char(fis, e))
    fit = fz.fit_three_section(e, u)
    row.update({f"fit_{k}": v for k, v in zip("abcd", fit.abcd)})
    row.update(
        fit_rms=fit.rms,
        breakpoints_e=[round(float(v), 4) for v in res.params["e"]],
        levels_u=[round(float(v), 4) for v in res.params["u"]],
    )
    return row, row0, (np.asarray(e), u0, u, fit)


SHORT = {
    "gradient": "gradient",
    "pso": "pso",
    "grid": "grid",
    "paper": "paper",
    "linear K_mds": "linear",
    "mamdani (gradient)": "mamdani",
    "sugeno (gradient)": "sugeno",
}  # method → metric suffix


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    loop = FuzzyPTuning(cfg)
    start = time.perf_counter()
    rows, cmp = compare_three_section(loop, cfg, progress)
    fis_rows, fis_curves = [], {}
    for kind in progress(["mamdani", "sugeno"], desc="fuzzy_pid_tuning (fuzzy systems)", unit="system"):
        row, row0, fis_curves[kind] = run_fis(loop, cfg, kind)
        fis_rows += [row0, row]
    by = {r["method"]: r for r in rows + fis_rows}
    metrics = {**cmp.metrics, **{f"tuned_loss_{SHORT[n]}": by[n]["loss_J"] for n in SHORT}}
    metrics.update({f"{k}_{n}": by[n][k] for n in ("gradient", "pso", "grid") for k in ("sims", "wall_s")})
    metrics.update({f"initial_loss_{k}": by[f"{k} (initial)"]["loss_J"] for k in ("mamdani", "sugeno")})
    metrics["initial_loss_sugeno_vs_paper_rel_diff"] = abs(metrics["initial_loss_sugeno"] / by["paper"]["loss_J"] - 1)
    metrics.update(
        k_mds=loop.k_mds,
        budget_evals=cfg.budget,
        operating_points=len(cfg.operating_points),
        fis_steps=cfg.fis_steps,
        dt=cfg.dt,
        t_final=cfg.t_final,
        total_wall_s=time.perf_counter() - start,
    )
    for name, key in SHORT.items():
        metrics[f"settling_max_{key}"] = by[name]["settling_max_s"]
        metrics[f"overshoot_max_{key}"] = by[name]["overshoot_max_pct"]
        metrics[f"feasible_{key}"] = float(by[name]["feasible"])
    figures = {
        **cmp.figures,
        "tuned_characteristics": _plot_characteristics(rows, fis_curves, loop.k_mds),
        "tuned_transients": _plot_transients(loop, rows),
    }
    return StudyResult(
        metrics=metrics,
        tables={"three_section": rows, "fuzzy_systems": fis_rows, "tuners": cmp.tables["comparison"]},
        figures=figures,
        notes=[
            *cmp.notes,
            "J is re-evaluated with the exact characteristic and exact overshoot for "
            "every method (the gradient run's own curve is the smooth surrogate it optimised)",
            "wall_s: optimisation time without compilation (compile_s separately)",
        ],
    )


def _plot_characteristics(rows: list[dict], fis_curves: dict, k_mds: float):
    """Static characteristics u(e): the tuned three-section ones; the Mamdani/Sugeno ones with their fits."""
    e = np.linspace(0, 2.5, 251)
    three = {
        f"{r['method']}: J = {r['loss_J']:.4g}": (e, fz.ThreeSection(r["a"], r["b"], r["c"], r["d"])(e))
        if "a" in r
        else (e, k_mds * e, ":")
        for r in rows
    }
    fis = {}
    for i, (kind, (ee, u0, u, fit)) in enumerate(fis_curves.items()):
        fis[f"{kind}: initial"] = (ee, u0, f"C{i}:")
        fis[f"{kind}: tuned"] = (ee, u, f"C{i}-")
        fit_label = f"{kind} fit (a, b, c, d) = " + ", ".join(f"{v:.3f}" for v in fit.abcd)
        fis[fit_label] = (ee, np.asarray(fit.params(jnp.asarray(ee))), f"C{i}--")
    axes = dict(x_label="e (error units)", y_label="u (control units)", xlim=(0, 2.5))
    return figures.line_panels(
        [
            dict(lines=three, title="tuned three-section characteristics (u ≥ 0 half)", **axes),
            dict(lines=fis, title="tuned Mamdani and Sugeno controllers: static characteristics", **axes),
        ]
    )


def _plot_transients(loop: FuzzyPTuning, rows: list[dict]):
    """Output at every operating point for the three-section designs and the linear reference."""
    chars = {r["method"]: fz.ThreeSection(r["a"], r["b"], r["c"], r["d"]) for r in rows if "a" in r}
    chars["linear K_mds"] = fz.linear(loop.k_mds)
    runs = {name: loop.rollouts_jit(char) for name, char in chars.items()}
    panels = [
        dict(
            lines={name: (t[i], y[i]) for name, (t, y, _) in runs.items()},
            title=f"g = {g}, f = {f}",
            x_label="t, s",
            y_label="y (output units)",
            xlim=(0, 2.5),
        )
        for i, (g, f) in enumerate(loop.setup.operating_points)
    ]
    return figures.line_panels(panels, size=(4.2, 3.8))


STUDY = Study(
    name="fuzzy_pid_tuning",
    description="Fuzzy-PID paper: tune (a, b, c, d) by gradient vs PSO vs grid on ITAE with e_ss/overshoot/|u| "
    "constraints; tune Mamdani and Sugeno breakpoints",
    config=Config,
    presets={
        "quick": dict(
            budget=81, pso_particles=9, grid_points_per_dim=3, n_starts=3, fis_steps=15, t_final=4.0, dt=4e-3
        ),
        "tiny": dict(budget=16, pso_particles=4, grid_points_per_dim=2, n_starts=2, fis_steps=2, t_final=2.0, dt=0.01),
    },
    claims=CLAIMS,
    assumptions=ASSUMPTIONS,
    run=run,
)
