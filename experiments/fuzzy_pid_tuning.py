"""Study ``fuzzy_pid_tuning``: tuning the fuzzy-PID paper's fuzzy controller.

Seed 000, paper 1 (spec §1.5): the paper picks the breakpoints ``(a, b, c, d)`` of its fuzzy P
controller by hand ("from the requirement of a monotonic transient", procedure not given).  Here
they are tuned on the static plant ``2/((0.1s+1)(0.5s+1))`` over a set of operating points
``(g, f)`` (reference and disturbance steps):

    minimise   J = mean_i ITAE_i + (w/2)·Σ_k max(0, h_k)²        (the same J for every method)
    ITAE_i     = Σ t·|y_i(t) − y_i(T)|·dt                         (transient, s²)
    h          = [(e_i(T) − e_lin,i)/e_lin,i,                     e_ss no worse than the linear
                  (σ_i − σ_max)/σ_max,                           maximum-stability P controller;
                  (max_t |u| − u_max)/u_max]                     overshoot ≤ σ_max; |u| ≤ u_max

with ``e_lin`` the analytic error of the linear P controller designed for maximum stability degree
(:mod:`jaxsim.control.stability_degree`) and ``e_i(T)`` the simulated final error.

Methods, each with the same budget of loss evaluations (``budget``; every evaluation simulates all
operating points):

* gradient: :func:`optim.tune` (optax Adam, forward-mode gradients through the rollout, ``n_starts``
  starts stepping together from the paper's controller and perturbations of it, the constraints
  by augmented Lagrangian), breakpoints kept ordered by :class:`optim.reparam.SortedBreakpoints` on
  ``(a, c)`` and ``(b, d)``; on the gradient path the characteristic is the smooth (softplus) form
  and the overshoot the smooth :func:`jaxsim.core.metrics.soft_overshoot`, bounded by
  ``σ_max − 3τ`` because the surrogate reads a few temperatures low; the result is re-scored with
  the exact ``J``;
* particle swarm: :func:`optim.pso` on the box of ``(a, c − a, b, d − b)``, exact ``J``;
* grid search: :func:`optim.grid_search` on the same box, exact ``J``;
* references (not tuned): the paper's controller and the linear maximum-stability controller.

Then a full Mamdani and a zero-order Sugeno controller (:mod:`jaxsim.control.fuzzy.templates`,
seven input terms) have their membership-function breakpoints tuned directly by gradient (same
objective and constraints, augmented Lagrangian), and their static characteristics are plotted with
their three-section fits.  The zero-order Sugeno template reproduces a piecewise-linear
characteristic exactly, so its initial point *is* the paper's controller.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np
import optax

from experiments.study import Study, StudyResult, assumption
from jaxsim.control import fuzzy as fz
from jaxsim.control.fuzzy.controller import FuzzyPIDParams, fuzzy_pid_init, fuzzy_pid_step
from jaxsim.control.fuzzy_steady_state import steady_state_error
from jaxsim.control.stability_degree import max_stability_degree
from jaxsim.core.metrics import itae_integrand, soft_overshoot, step_info
from jaxsim.core.rollout import ClosedLoop, Timing, simulate
from jaxsim.core.signals import Step
from jaxsim.core.system import Controller
from jaxsim.plants.second_order import StaticParams, static_plant, static_transfer_function
from optim import SortedBreakpoints, compare, grid_search, plot_comparison, pso, tune


@dataclass(frozen=True)
class Config:
    quick: bool = False
    K: float = 2.0  # static plant, paper lines 468–470
    T1: float = 0.1
    T2: float = 0.5
    operating_points: tuple = ((1.0, 0.0), (1.0, 0.3), (0.5, 0.4), (1.5, 0.2))  # (g, f)
    paper_fc: tuple = (0.75, 0.3, 1.2, 1.0)  # paper line 488
    overshoot_max: float = 2.0  # %
    u_max: float = 1.5
    penalty_weight: float = 100.0
    dt: float = 2e-3  # s, plant step = controller period (quick: 4 ms)
    t_final: float = 6.0  # s (quick: 4 s)
    budget: int = 256  # loss evaluations per method (quick: 81)
    learning_rate: float = 0.05
    smooth_temperature: float = 0.01  # error units: softplus corners of the smooth characteristic
    overshoot_temperature: float = 0.05  # %: soft_overshoot temperature
    n_starts: int = 8  # gradient: starts stepping together (steps = budget / n_starts; quick: 3)
    init_spread: float = 1.0  # gradient: spread of the extra starts in unconstrained space
    box_lo: tuple = (0.05, 0.05, 0.02, 0.0)  # (a, c − a, b, d − b)
    box_hi: tuple = (1.5, 1.5, 1.0, 1.5)
    pso_particles: int = 16  # quick: 9 (iterations = budget / particles)
    grid_points_per_dim: int = 4  # quick: 3 (4⁴ = 256 = budget)
    fis_steps: int = 150  # gradient steps for the Mamdani and Sugeno controllers (quick: 15)
    fis_learning_rate: float = 0.02
    fis_grid: int = 101  # Mamdani output grid
    seed: int = 0


ASSUMPTIONS = {
    "operating_points": assumption(
        [[1.0, 0.0], [1.0, 0.3], [0.5, 0.4], [1.5, 0.2]],
        "the paper's two static-plant cases (g = 1, f = 0 / 0.3) plus two more that move the operating "
        "point along the small- and large-gain sections"),
    "loss": assumption(
        "mean transient ITAE Σ t|y − y(T)|dt + quadratic penalty (w = 100) on normalised violations",
        "the spec suggests ITAE with constraints e_ss ≤ linear, monotone-ish response, |u| ≤ bound; "
        "ITAE of y − y(T) measures the transient (the steady-state error is constrained separately)"),
    "overshoot_max": assumption(2.0, "the brief's bound ('overshoot ≤ 2 %') replacing the paper's "
                                     "'monotonic transient' rule"),
    "u_max": assumption(1.5, "control bound, 1.5× the paper's saturation level d = 1"),
    "box": assumption("(a, c − a, b, d − b) ∈ [0.05, 1.5] × [0.05, 1.5] × [0.02, 1] × [0, 1.5]",
                      "search domain of PSO and the grid; keeps 0 < a < c and 0 < b ≤ d"),
    "timing": assumption("RK4, dt = controller period = 2 ms, horizon 6 s",
                         "every closed-loop pole of the static loop is faster than 2 1/s, so e(6 s) "
                         "is the steady state to ~1e-5"),
    "fis_templates": assumption(
        "7 input terms (peaks 0, ±p1..3), Mamdani output triangles at 0, ±q1..3 of half-width w; "
        "Sugeno constants 0, ±q1..3; initial p = (0.375, 0.75, 1.2), q = (0.15, 0.3, 1.0)",
        "the paper gives no membership functions; these start on the paper's characteristic"),
}


# ---------------------------------------------------------------------------------------------
# The problem: closed-loop metrics of a P characteristic at every operating point


def _controller(char: Any) -> Controller:
    return Controller(FuzzyPIDParams(p=char), fuzzy_pid_init, fuzzy_pid_step, name="fuzzy_p")


class Problem:
    """Everything the losses need (plant, timing, points, linear references); no state changes."""

    def __init__(self, cfg: Config):
        self.cfg = cfg
        self.plant = static_plant(StaticParams(cfg.K, cfg.T1, cfg.T2))
        self.timing = Timing(t_final=cfg.t_final, dt=cfg.dt)
        self.points = jnp.asarray(cfg.operating_points, float)
        num, den = (np.asarray(v) for v in static_transfer_function(StaticParams(cfg.K, cfg.T1, cfg.T2)))
        self.k_mds = max_stability_degree(num, den, "P").gains["kp"]
        self.e_lin = jnp.asarray([steady_state_error("static", cfg.K, fz.linear(self.k_mds), g=g, f=f).error
                                  for g, f in cfg.operating_points])
        # exact J and metrics of a characteristic: one compiled function per characteristic type
        self.exact = jax.jit(lambda char: (self.penalised(char), self.terms(char, smooth=False)))
        self.rollouts_jit = jax.jit(self.rollouts)

    def rollouts(self, char: Any):
        """Per point: (t, y, u) of the closed loop with P characteristic ``char``."""
        def one(gf):
            loop = ClosedLoop(self.plant, _controller(char), reference=Step(gf[0]), disturbance=Step(gf[1]))
            tr = simulate(loop, jnp.zeros(2), self.timing)
            return tr.t, tr.y[:, 0], tr.u[:, 0]

        return jax.vmap(one)(self.points)

    def terms(self, char: Any, smooth: bool):
        """``(f, h, details)``: objective, normalised constraint values (feasible: h ≤ 0), metrics."""
        cfg = self.cfg
        t, y, u = self.rollouts(char)
        y_final = y[:, -1]
        itae = jnp.sum(itae_integrand(t, y - y_final[:, None]), axis=1) * cfg.dt
        e_final = self.points[:, 0] - y_final
        bound = cfg.overshoot_max
        if smooth:
            overshoot = jax.vmap(lambda yy, yf: soft_overshoot(yy, yf, cfg.overshoot_temperature))(y, y_final)
            bound = cfg.overshoot_max - 3.0 * cfg.overshoot_temperature  # the surrogate reads low
        else:
            overshoot = jax.vmap(lambda tt, yy: step_info(tt, yy).overshoot)(t, y)
        u_peak = jnp.max(jnp.abs(u))
        h = jnp.concatenate([(e_final - self.e_lin) / self.e_lin,
                             (overshoot - bound) / cfg.overshoot_max,
                             jnp.atleast_1d((u_peak - cfg.u_max) / cfg.u_max)])
        settling = jax.vmap(lambda tt, yy: step_info(tt, yy).settling_time)(t, y)
        details = dict(itae=itae, overshoot=overshoot, e_final=e_final, u_peak=u_peak, settling=settling)
        return jnp.mean(itae), h, details

    def penalised(self, char: Any, smooth: bool = False) -> jax.Array:
        f, h, _ = self.terms(char, smooth)
        return f + 0.5 * self.cfg.penalty_weight * jnp.sum(jnp.maximum(h, 0.0) ** 2)


def char_from_box(z: jax.Array) -> fz.ThreeSection:
    """``(a, c − a, b, d − b)`` → the exact characteristic."""
    return fz.ThreeSection(z[0], z[2], z[0] + z[1], z[2] + z[3], 0.01, "exact")


def char_from_sorted(params: dict, temperature: float, form: str) -> fz.ThreeSection:
    """``{"e": [a, c], "u": [b, d]}`` → the characteristic in the given form."""
    return fz.ThreeSection(params["e"][0], params["u"][0], params["e"][1], params["u"][1], temperature, form)


# ---------------------------------------------------------------------------------------------
# The runs


def report(problem: Problem, char: Any, name: str, sims: int, wall_s: float, compile_s: float) -> dict:
    """Exact J and closed-loop metrics of one tuned (or reference) characteristic."""
    J, (f, h, d) = problem.exact(char)
    row = {"method": name, "loss_J": float(J), "mean_itae": float(f),
           "max_violation": float(jnp.max(h)), "feasible": bool(jnp.all(h <= 1e-9)),
           "settling_mean_s": float(jnp.mean(d["settling"])), "settling_max_s": float(jnp.max(d["settling"])),
           "overshoot_max_pct": float(jnp.max(d["overshoot"])), "u_peak": float(d["u_peak"]),
           "e_ss_over_linear_max": float(jnp.max(d["e_final"] / problem.e_lin)),
           "sims": int(sims), "wall_s": float(wall_s), "compile_s": float(compile_s)}
    if isinstance(char, fz.ThreeSection):
        row.update({k: float(getattr(char, k)) for k in "abcd"})
        row["K1"], row["K2"] = float(char.b) / float(char.a), (float(char.d) - float(char.b)) / (float(char.c) - float(char.a))
    return row


def run_three_section(problem: Problem, cfg: Config, progress: Callable[..., Any]):
    n_pts = len(cfg.operating_points)
    budget, particles, per_dim, starts = cfg.budget, cfg.pso_particles, cfg.grid_points_per_dim, cfg.n_starts
    if per_dim ** 4 > budget or budget % particles or budget % starts:
        raise ValueError("budget: must be a multiple of pso_particles and n_starts, and ≥ grid_points_per_dim**4")
    lo, hi = jnp.asarray(cfg.box_lo), jnp.asarray(cfg.box_hi)
    exact = lambda z: problem.penalised(char_from_box(z))  # noqa: E731
    a, b, c, d = cfg.paper_fc
    params0 = {"e": jnp.asarray([a, c]), "u": jnp.asarray([b, d])}
    reparam = {"e": SortedBreakpoints(lo=0.0, min_gap=0.02), "u": SortedBreakpoints(lo=0.0)}
    smooth = lambda p: problem.terms(char_from_sorted(p, cfg.smooth_temperature, "smooth"), smooth=True)  # noqa: E731
    key = jax.random.PRNGKey(cfg.seed)
    runs = {
        "gradient": lambda: tune(lambda p: smooth(p)[0], params0, optimizer=optax.adam(cfg.learning_rate),
                                 steps=budget // starts, n_starts=starts, key=key,
                                 init_spread=cfg.init_spread, reparam=reparam,
                                 constraints=lambda p: smooth(p)[1], constraint_method="augmented_lagrangian",
                                 penalty_weight=cfg.penalty_weight, sims_per_eval=n_pts, mode="forward"),
        "pso": lambda: pso(exact, lo, hi, n_particles=particles, n_iters=budget // particles, key=key,
                           sims_per_eval=n_pts),
        "grid": lambda: grid_search(exact, lo, hi, points_per_dim=per_dim, sims_per_eval=n_pts),
    }
    bar = progress(total=len(runs), desc="fuzzy_pid_tuning (a, b, c, d)", unit="method")

    comparison = compare(runs, on_done=lambda _: bar.update(1))
    bar.close()
    rows = []
    for name, res in comparison.results.items():
        char = (char_from_sorted(res.params, cfg.smooth_temperature, "exact") if name == "gradient"
                else char_from_box(jnp.asarray(res.x)))
        rows.append(report(problem, char, name, res.n_sims, res.wall_s, getattr(res, "compile_s", 0.0)))
    rows.append(report(problem, fz.three_section(*cfg.paper_fc), "paper", 0, 0.0, 0.0))
    rows.append(report(problem, fz.linear(problem.k_mds), "linear K_mds", 0, 0.0, 0.0))
    return rows, comparison


def run_fis(problem: Problem, cfg: Config, kind: str):
    """Tune the breakpoints of a 7-term Mamdani or Sugeno P controller by gradient on the same J."""
    n_pts = len(cfg.operating_points)
    u_range = 1.6 * cfg.u_max

    def build(p):
        if kind == "mamdani":
            return fz.odd_mamdani(p["e"], p["u"], p["width"][0], u_range=u_range, n_grid=cfg.fis_grid)
        return fz.odd_sugeno(p["e"], p["u"])

    params0 = {"e": jnp.asarray([0.375, 0.75, 1.2]), "u": jnp.asarray([0.15, 0.3, 1.0])}
    reparam = {"e": SortedBreakpoints(lo=0.0, min_gap=0.02), "u": SortedBreakpoints(lo=0.0)}
    if kind == "mamdani":
        params0["width"] = jnp.asarray([0.1])
        reparam["width"] = SortedBreakpoints(lo=0.01)  # one positive value
    steps = cfg.fis_steps
    terms = lambda p: problem.terms(build(p), smooth=True)  # noqa: E731
    res = tune(lambda p: terms(p)[0], params0, optimizer=optax.adam(cfg.fis_learning_rate), steps=steps,
               reparam=reparam, constraints=lambda p: terms(p)[1], constraint_method="augmented_lagrangian",
               penalty_weight=cfg.penalty_weight, sims_per_eval=n_pts, mode="forward")
    fis0, fis = build(params0), build(res.params)
    row = report(problem, fis, f"{kind} (gradient)", res.n_sims, res.wall_s, res.compile_s)
    row0 = report(problem, fis0, f"{kind} (initial)", 0, 0.0, 0.0)
    e = jnp.linspace(-2.5, 2.5, 251)
    char = jax.jit(fz.static_characteristic)
    u0, u = np.asarray(char(fis0, e)), np.asarray(char(fis, e))
    fit = fz.fit_three_section(e, u)
    row.update({f"fit_{k}": v for k, v in zip("abcd", fit.abcd)})
    row["fit_rms"] = fit.rms
    row["breakpoints_e"] = [round(float(v), 4) for v in res.params["e"]]
    row["levels_u"] = [round(float(v), 4) for v in res.params["u"]]
    return row, row0, (np.asarray(e), u0, u, fit), res


QUICK = dict(budget=81, pso_particles=9, grid_points_per_dim=3, n_starts=3, fis_steps=15, t_final=4.0, dt=4e-3)
"""What ``--quick`` changes (CI smoke run): a smaller budget, a coarser and shorter simulation."""


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    if cfg.quick:
        cfg = dataclasses.replace(cfg, **QUICK)
    problem = Problem(cfg)
    start = time.perf_counter()
    rows, comparison = run_three_section(problem, cfg, progress)
    fis_rows, fis_curves = [], {}
    for kind in progress(["mamdani", "sugeno"], desc="fuzzy_pid_tuning (fuzzy systems)", unit="system"):
        row, row0, curve, _ = run_fis(problem, cfg, kind)
        fis_rows += [row0, row]
        fis_curves[kind] = curve
    by = {r["method"]: r for r in rows + fis_rows}
    metrics = {
        "tuned_loss_gradient": by["gradient"]["loss_J"],
        "tuned_loss_pso": by["pso"]["loss_J"],
        "tuned_loss_grid": by["grid"]["loss_J"],
        "tuned_loss_paper": by["paper"]["loss_J"],
        "tuned_loss_linear": by["linear K_mds"]["loss_J"],
        "sims_gradient": by["gradient"]["sims"],
        "sims_pso": by["pso"]["sims"],
        "sims_grid": by["grid"]["sims"],
        "wall_s_gradient": by["gradient"]["wall_s"],
        "wall_s_pso": by["pso"]["wall_s"],
        "wall_s_grid": by["grid"]["wall_s"],
        "tuned_loss_mamdani": by["mamdani (gradient)"]["loss_J"],
        "tuned_loss_sugeno": by["sugeno (gradient)"]["loss_J"],
        "initial_loss_mamdani": by["mamdani (initial)"]["loss_J"],
        "initial_loss_sugeno": by["sugeno (initial)"]["loss_J"],
        "k_mds": problem.k_mds,
        "budget_evals": cfg.budget,
        "operating_points": len(cfg.operating_points),
        "fis_steps": cfg.fis_steps,
        "dt": cfg.dt,
        "t_final": cfg.t_final,
        "total_wall_s": time.perf_counter() - start,
    }
    for name in ("gradient", "pso", "grid", "paper", "linear K_mds", "mamdani (gradient)", "sugeno (gradient)"):
        key = name.split(" ")[0]  # gradient, pso, grid, paper, linear, mamdani, sugeno
        metrics[f"settling_max_{key}"] = by[name]["settling_max_s"]
        metrics[f"overshoot_max_{key}"] = by[name]["overshoot_max_pct"]
        metrics[f"feasible_{key}"] = float(by[name]["feasible"])
    figures = {
        "tuning_comparison": plot_comparison(comparison, title="J (gradient: smooth surrogate) vs budget"),
        "tuned_characteristics": _plot_characteristics(cfg, rows, fis_curves),
        "tuned_transients": _plot_transients(problem, cfg, rows, fis_curves),
    }
    notes = [
        "J is re-evaluated with the exact characteristic and exact overshoot for every method "
        "(the gradient run's own curve is the smooth surrogate it optimised)",
        "sims: loss evaluations × operating points; wall_s: optimisation time without compilation "
        "(compile_s separately)",
    ]
    return StudyResult(metrics=metrics, tables={"three_section": rows, "fuzzy_systems": fis_rows},
                       assumptions=ASSUMPTIONS, figures=figures, notes=notes)


# ---------------------------------------------------------------------------------------------
# Plots


def _plot_characteristics(cfg, rows, fis_curves):
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(13, 4.8))
    e = np.linspace(0, 2.5, 251)
    for r in rows:
        if "a" in r:
            u = np.asarray(fz.ThreeSection(r["a"], r["b"], r["c"], r["d"])(e))
            ax1.plot(e, u, label=f"{r['method']}: J = {r['loss_J']:.4g}")
    k = next(r for r in rows if r["method"] == "linear K_mds")
    ax1.set_title("tuned three-section characteristics (u ≥ 0 half)")
    ax1.set_xlabel("e")
    ax1.set_ylabel("u")
    ax1.grid(alpha=0.3)
    ax1.legend(fontsize=8)
    ax1.text(0.02, 0.95, f"linear K_mds: J = {k['loss_J']:.4g}", transform=ax1.transAxes, fontsize=8, va="top")
    for i, (kind, (ee, u0, u, fit)) in enumerate(fis_curves.items()):
        ax2.plot(ee, u0, ":", color=f"C{i}", lw=1, label=f"{kind}: initial")
        ax2.plot(ee, u, color=f"C{i}", lw=2, label=f"{kind}: tuned")
        ax2.plot(ee, np.asarray(fit.params(jnp.asarray(ee))), "--", color=f"C{i}", lw=1,
                 label=f"{kind} fit (a, b, c, d) = " + ", ".join(f"{v:.3f}" for v in fit.abcd))
    ax2.set_xlim(0, 2.5)
    ax2.set_title("tuned Mamdani and Sugeno controllers: static characteristics")
    ax2.set_xlabel("e")
    ax2.set_ylabel("u")
    ax2.grid(alpha=0.3)
    ax2.legend(fontsize=7)
    fig.tight_layout()
    return fig


def _plot_transients(problem, cfg, rows, fis_curves):
    import matplotlib.pyplot as plt

    chars = {r["method"]: fz.ThreeSection(r["a"], r["b"], r["c"], r["d"]) for r in rows if "a" in r}
    chars["linear K_mds"] = fz.linear(problem.k_mds)
    roll = problem.rollouts_jit
    n = len(cfg.operating_points)
    fig, axes = plt.subplots(1, n, figsize=(4.2 * n, 3.8))
    for name, char in chars.items():
        t, y, _ = roll(char)
        for i, ax in enumerate(np.atleast_1d(axes)):
            ax.plot(np.asarray(t[i]), np.asarray(y[i]), lw=1.2, label=name)
    for i, ax in enumerate(np.atleast_1d(axes)):
        g, f = cfg.operating_points[i]
        ax.set_title(f"g = {g}, f = {f}")
        ax.set_xlim(0, 2.5)
        ax.set_xlabel("t, s")
        ax.grid(alpha=0.3)
    np.atleast_1d(axes)[0].set_ylabel("y")
    np.atleast_1d(axes)[0].legend(fontsize=7)
    fig.tight_layout()
    return fig


STUDY = Study(
    name="fuzzy_pid_tuning",
    description="Fuzzy-PID paper: tune (a, b, c, d) by gradient vs PSO vs grid on ITAE with e_ss/overshoot/|u| "
                "constraints; tune Mamdani and Sugeno breakpoints",
    config_cls=Config,
    run=run,
)
