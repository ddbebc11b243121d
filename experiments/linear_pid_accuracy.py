"""Study ``linear_pid_accuracy``: the fuzzy-PID paper's Tables 1–2 for linear P, PI and PD control.

Seed 000, paper 1 (spec ``seed000_fuzzy_pid_smo_predictor.md`` §1.1–1.3).  For the static plant
``2/((0.1s+1)(0.5s+1))`` and the astatic plant ``2/(s(0.1s+1))``:

1. design P, PI and PD (with derivative filter) for maximum stability degree — the P gains must come
   out as the paper's 0.4 and 1.25;
2. for every controller and every input component (constant / ramp reference, constant / ramp
   disturbance at the plant input) compute the steady-state error three ways: the paper's table
   formula, the final-value theorem on the loop's polynomials, and a closed-loop simulation (one
   vmapped rollout per plant);
3. detect the "∞" cells as simulations whose error keeps drifting.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np

from experiments import stages
from experiments.runner import Study, StudyResult, paper_facts
from jaxsim.control.pid import PIDParams, pid, pid_transfer_function
from jaxsim.control.stability_degree import (
    characteristic_polynomial,
    max_stability_degree,
    stability_degree,
)
from jaxsim.control.steady_state import final_value_error, paper_table_error
from jaxsim.core.metrics import steady_state
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

STRUCTURES = ("P", "PI", "PD")
INPUTS = (  # (label, source, order)
    ("g = const", "reference", 0),
    ("g = Kg·t", "reference", 1),
    ("f = const", "disturbance", 0),
    ("f = Kf·t", "disturbance", 1),
)


@dataclass(frozen=True)
class Config:
    K_static: float = 2.0  # paper lines 468–470
    T1: float = 0.1
    T2: float = 0.5
    K_astatic: float = 2.0  # paper line 609
    T_astatic: float = 0.1
    g_const: float = 1.0  # "single step reference g = 1"
    g_slope: float = 0.5  # assumed (Tables are symbolic)
    f_const: float = 0.3  # the paper's Fig. 4b disturbance
    f_slope: float = 0.2  # assumed (Tables are symbolic)
    derivative_filter: float = 0.05  # s, assumed: PD needs a filter for a finite optimum
    dt: float = 1e-3  # s, plant step and controller period
    t_final: float = 20.0  # s
    drift_window: float = 1.0  # s, window over which a steady state must not drift
    drift_rtol: float = 1e-6


PRESETS = {"quick": dict(t_final=10.0)}
CLAIMS, ASSUMPTIONS = paper_facts("linear_pid_accuracy")


def _plants(cfg: Config) -> dict[str, dict[str, Any]]:
    sp = StaticParams(K=cfg.K_static, T1=cfg.T1, T2=cfg.T2)
    ap = AstaticParams(K=cfg.K_astatic, T=cfg.T_astatic)
    return {
        "static": {"plant": static_plant(sp), "tf": static_transfer_function(sp), "K": cfg.K_static},
        "astatic": {"plant": astatic_plant(ap), "tf": astatic_transfer_function(ap), "K": cfg.K_astatic},
    }


def design_all(cfg: Config) -> dict[tuple[str, str], Any]:
    """Maximum-stability-degree designs for every (plant, structure)."""
    designs = {}
    for pname, info in _plants(cfg).items():
        num, den = (np.asarray(v) for v in info["tf"])
        for s in STRUCTURES:
            tf = cfg.derivative_filter if s == "PD" else 0.0
            designs[(pname, s)] = max_stability_degree(num, den, s, tf=tf)
    return designs


def _cell_params(cfg: Config, designs, pname: str):
    """Stacked PID params and input signals for the 12 cells of one plant."""
    rows, kps, kis, kds, tfs, sig = [], [], [], [], [], []
    for s in STRUCTURES:
        g = designs[(pname, s)].gains
        for label, source, order in INPUTS:
            rows.append((s, label, source, order))
            kps.append(g.get("kp", 0.0))
            kis.append(g.get("ki", 0.0))
            kds.append(g.get("kd", 0.0))
            tfs.append(cfg.derivative_filter if s == "PD" else 0.0)
            amp = {
                ("reference", 0): cfg.g_const,
                ("reference", 1): cfg.g_slope,
                ("disturbance", 0): cfg.f_const,
                ("disturbance", 1): cfg.f_slope,
            }[(source, order)]
            v = np.zeros(4)
            v[[("reference", 0), ("reference", 1), ("disturbance", 0), ("disturbance", 1)].index((source, order))] = amp
            sig.append(v)
    sig = np.array(sig)
    n = len(rows)
    params = PIDParams(
        kp=jnp.array(kps),
        ki=jnp.array(kis),
        kd=jnp.array(kds),
        tf=jnp.array(tfs),
        u_min=jnp.full(n, -jnp.inf),
        u_max=jnp.full(n, jnp.inf),
        anti_windup="none",
    )
    t0 = jnp.zeros(n)
    refs = Sum((Step(jnp.array(sig[:, 0]), t0), Ramp(jnp.array(sig[:, 1]), t0)))
    dists = Sum((Step(jnp.array(sig[:, 2]), t0), Ramp(jnp.array(sig[:, 3]), t0)))
    return rows, params, refs, dists


def simulate_cells(cfg: Config, plant, params, refs, dists, timing: Timing):
    """One vmapped rollout over the cells; returns (t, e) with e of shape (cells, N)."""
    template = pid(kp=1.0, anti_windup="none")

    def one(p, r, d):
        loop = ClosedLoop(plant, dataclasses.replace(template, params=p), reference=r, disturbance=d)
        tr = simulate(loop, jnp.zeros(plant.n_states), timing)
        return tr.t, tr.r[:, 0] - tr.y[:, 0]

    t, e = jax.jit(jax.vmap(one))(params, refs, dists)
    return np.asarray(t[0]), np.asarray(e)


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    t_final = cfg.t_final
    save_every = 10
    timing = Timing(t_final=t_final, dt=cfg.dt, controller_period=cfg.dt, save_every=save_every)
    tail = max(2, int(round(cfg.drift_window / (cfg.dt * save_every))))
    designs = design_all(cfg)
    plants = _plants(cfg)
    table, traces = [], {}
    for pname in progress(list(plants), desc="linear_pid_accuracy", unit="plant"):
        info = plants[pname]
        num, den = (np.asarray(v) for v in info["tf"])
        rows, params, refs, dists = _cell_params(cfg, designs, pname)
        t, e = simulate_cells(cfg, info["plant"], params, refs, dists, timing)
        traces[pname] = (t, e, rows)
        for i, (s, label, source, order) in enumerate(rows):
            g = designs[(pname, s)].gains
            tf = cfg.derivative_filter if s == "PD" else 0.0
            nc, dc = pid_transfer_function(g.get("kp", 0.0), g.get("ki", 0.0), g.get("kd", 0.0), tf)
            mag = {
                ("reference", 0): cfg.g_const,
                ("reference", 1): cfg.g_slope,
                ("disturbance", 0): cfg.f_const,
                ("disturbance", 1): cfg.f_slope,
            }[(source, order)]
            fvt = final_value_error(num, den, nc, dc, source, order, mag)
            paper = paper_table_error(pname, s, source, order, info["K"], g.get("kp", 0.0), g.get("ki", 0.0), mag)
            ss = steady_state(jnp.asarray(e[i]), tail, rtol=cfg.drift_rtol)
            sim_value = float(ss.value) if bool(ss.converged) else float(np.sign(ss.drift) * np.inf)
            finite = np.isfinite(paper)
            err = abs(sim_value - paper) / max(abs(paper), abs(mag)) if finite and np.isfinite(sim_value) else np.nan
            table.append(
                {
                    "plant": pname,
                    "controller": s,
                    "input": label,
                    "magnitude": mag,
                    "kp": g.get("kp", 0.0),
                    "ki": g.get("ki", 0.0),
                    "kd": g.get("kd", 0.0),
                    "analytic_table": paper,
                    "analytic_final_value": fvt,
                    "simulated": sim_value,
                    "status": "finite" if bool(ss.converged) else "diverges (∞)",
                    "normalised_error": err,
                }
            )
    finite_rows = [r for r in table if np.isfinite(r["analytic_table"])]
    inf_rows = [r for r in table if not np.isfinite(r["analytic_table"])]
    fvt_vs_table = max(
        abs(r["analytic_final_value"] - r["analytic_table"]) / max(abs(r["analytic_table"]), abs(r["magnitude"]))
        for r in finite_rows
    )
    inf_agree = all(not np.isfinite(r["analytic_final_value"]) for r in inf_rows)
    designs_rows = [
        {
            "plant": p,
            "controller": s,
            **d.gains,
            "stability_degree": d.degree,
            "poles": " ".join(f"{z.real:.4f}{z.imag:+.4f}j" for z in d.poles),
            "method": d.method,
            "independent_search_degree": d.search_degree,
        }
        for (p, s), d in designs.items()
    ]
    metrics = {
        "kp_mds_static": designs[("static", "P")].gains["kp"],
        "kp_mds_astatic": designs[("astatic", "P")].gains["kp"],
        "stability_degree_static_p": designs[("static", "P")].degree,
        "stability_degree_astatic_p": designs[("astatic", "P")].degree,
        "pi_mds_astatic_kp": designs[("astatic", "PI")].gains["kp"],
        "pi_mds_astatic_ki": designs[("astatic", "PI")].gains["ki"],
        "stability_degree_astatic_pi": designs[("astatic", "PI")].degree,
        "max_normalised_error_sim_vs_table": max(r["normalised_error"] for r in finite_rows),
        "max_normalised_error_final_value_vs_table": fvt_vs_table,
        "n_cells_finite": len(finite_rows),
        "n_cells_infinite": len(inf_rows),
        "n_infinite_detected_by_simulation": sum(r["status"] != "finite" for r in inf_rows),
        "n_finite_confirmed_by_simulation": sum(r["status"] == "finite" for r in finite_rows),
        "infinite_cells_agree_with_final_value_theorem": float(inf_agree),
    }
    figures = {f"transients_{p}": _plot_transients(p, *traces[p], table) for p in traces}
    figures["stability_degree_vs_kp"] = _plot_degree_curves(cfg, plants, designs)
    return stages.merge(
        stages.Stage(tables={"steady_state_errors": table, "designs": designs_rows}, figures=figures),
        metrics=metrics,
        notes=[
            f"simulation: RK4, dt = controller period = {cfg.dt} s, horizon {t_final} s; "
            f"steady state = last saved sample, ∞ = drift over the last {cfg.drift_window} s "
            f"above rtol {cfg.drift_rtol}"
        ],
    )


def _plot_transients(pname, t, e, rows, table):
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(STRUCTURES), len(INPUTS), figsize=(14, 8), sharex=True)
    for i, (s, label, _, _) in enumerate(rows):
        ax = axes[STRUCTURES.index(s), [x[0] for x in INPUTS].index(label)]
        ax.plot(t, e[i], lw=1.2, label="simulated e(t)")
        ref = next(r for r in table if r["plant"] == pname and r["controller"] == s and r["input"] == label)
        if np.isfinite(ref["analytic_table"]):
            ax.axhline(ref["analytic_table"], color="k", ls="--", lw=0.8, label="table value")
        ax.set_title(f"{s}, {label}", fontsize=9)
        ax.grid(alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("t, s")
    axes[0, 0].legend(fontsize=8)
    fig.suptitle(f"{pname} plant: error components (dashed: Table {1 if pname == 'static' else 2})")
    fig.tight_layout()
    return fig


def _plot_degree_curves(cfg, plants, designs):
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    for pname, info in plants.items():
        num, den = (np.asarray(v) for v in info["tf"])
        kps = np.linspace(0.01, 3.0, 600)
        eta = [stability_degree(characteristic_polynomial(num, den, "P", [k])) for k in kps]
        ax.plot(kps, eta, label=f"{pname} plant")
        d = designs[(pname, "P")]
        ax.plot(d.gains["kp"], d.degree, "o", color="k")
        ax.annotate(
            f"Kp={d.gains['kp']:.3g}, η={d.degree:.3g}",
            (d.gains["kp"], d.degree),
            textcoords="offset points",
            xytext=(5, 5),
            fontsize=8,
        )
    ax.set_xlabel("Kp")
    ax.set_ylabel("stability degree η = −max Re λ, 1/s")
    ax.set_title("P control: maximum stability degree")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    return fig


STUDY = Study(
    name="linear_pid_accuracy",
    description="Tables 1–2 of the fuzzy-PID paper: linear P/PI/PD steady-state errors, analytic vs simulated",
    config=Config,
    presets=PRESETS,
    claims=CLAIMS,
    assumptions=ASSUMPTIONS,
    run=run,
)
