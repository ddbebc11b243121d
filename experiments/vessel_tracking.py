"""Study ``vessel_tracking``: radar tracking of a manoeuvring vessel with a fuzzy window selector (seed 003).

The problem (scenario, trackers, per-run statistics, tuning loss): :mod:`jaxsim.problem.vessel_tracking`.

1. **Reproduction** (``envelope_runs`` Monte-Carlo runs per speed over the radar noise, plus one seeded
   run drawn like Fig. 5): error ε on the straight legs (RMS, peak) and its turn peak, the selected
   window, the scan after which σ̂ settles — claims with a ±30 % band (the paper: one run, a figure).
2. **Track loss** (``runs`` runs, speed U(10, 20) m/s, turn start within a scan after 45 s) at every
   gate of ``gates``: windows 3, 5, 10, the fuzzy selector, a CV Kalman filter and a CV + CT IMM on the
   same plots (common random numbers), Wilson intervals.
3. **Tuning**: the selector's memberships by gradient on the smooth surrogate of the loss
   probability (a training batch of its own), then scored (exact form) on the same Monte-Carlo runs.

``per_run``: one run for ``python -m experiments sweep vessel_tracking --param gate=20:120:6``.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from typing import Any, Callable

import jax
import numpy as np
import optax

import jaxsim.montecarlo as mc
from experiments import figures, stages
from experiments.runner import PerRun, Study, StudyResult, paper_facts
from jaxsim.problem.vessel_tracking import (
    BASE_TRACKERS,
    TrackingSetup,
    check_setup,
    envelope_means,
    envelope_metric,
    loss_metric,
    loss_run,
    loss_space,
    nominal_params,
    paper_selector,
    selector_problem,
    single_runs,
    with_memberships,
)


@dataclass(frozen=True)
class Config(TrackingSetup):
    runs: int = 10_000  # track-loss runs per gate
    envelope_runs: int = 2_000  # per speed
    tune_runs: int = 1_000  # training batch
    tune_steps: int = 150
    learning_rate: float = 0.05
    sensitivity_runs: int = 300  # per variant and speed; 0: no sensitivity table (three more compilations)
    seed: int = 0


PRESETS = {"quick": dict(runs=1_000, envelope_runs=300, tune_runs=100, tune_steps=20, sensitivity_runs=0)}
SOURCE = "seed 003, §4, Fig. 5 (spec 003.4): one run per speed read from the figure; ±30 % band"
ENVELOPE = [  # (metric stem, quantity, Monte-Carlo statistic, paper value or range per speed (m/s))
    ("max_straight", "error on straight legs, peak (m)", "max_straight/fuzzy", {10: (10.0, 12.0), 20: (10.0, 12.0)}),
    ("rms_straight", "error on straight legs, RMS (m)", "rms_straight/fuzzy", {10: (10.0, 12.0), 20: (10.0, 12.0)}),
    ("max_turn", "error in the turn, peak (m)", "max_turn/fuzzy", {10: 22.0, 20: 27.0}),
    ("window_straight", "window on straight legs (median)", "window_straight_median", {10: 10.0, 20: 10.0}),
    ("window_turn", "window in the turn (median)", "window_turn_median", {10: (5.0, 6.0), 20: (3.0, 4.0)}),
    ("sigma_settle", "σ̂ settles (scans, within 10 %)", "sigma_settle_scan", {10: 20.0, 20: 20.0}),
    ("sigma_final", "σ̂ final (m)", "sigma_final", {10: 10.0, 20: 10.0}),
]


def envelope_name(stem: str, speed: float) -> str:
    """Metric name of an envelope quantity at one speed (the turn's two keep their historic names)."""
    tag = f"{int(speed)}ms"
    return {"max_turn": f"max_err_turn_{tag}_m", "window_turn": f"window_turn_{tag}"}.get(stem, f"env_{stem}_{tag}")


PAPER = {stem: paper for stem, _, _, paper in ENVELOPE}
CLAIMS = stages.band_claims(
    {envelope_name(stem, v): paper[v] for stem, _, _, paper in ENVELOPE for v in (10, 20)}, 0.3, SOURCE
)
CLAIM = {c.metric: c for c in CLAIMS}
_, ASSUMPTIONS = paper_facts("vessel_tracking")


def per_run(cfg: Config) -> PerRun:
    """One track-loss run (speed and turn start drawn as in the study) for ``experiments sweep``."""
    return PerRun(*loss_run(cfg))


def envelope(cfg: Config, env: Any) -> tuple[dict[str, float], list[dict[str, Any]]]:
    """Per-speed envelope metrics and the table against the paper (MC mean, 5–95 % of single runs)."""
    metrics, rows = {}, []
    for speed, res in zip(cfg.speeds, env.points):
        for stem, quantity, stat, paper in ENVELOPE:
            s = res[stat]
            name = envelope_name(stem, speed)
            metrics[name] = float(s.mean)
            target = paper.get(int(speed), np.nan)
            rows.append(
                {
                    "quantity": quantity,
                    "speed_ms": speed,
                    "metric": name,
                    "paper": _target_str(target),
                    "mc_mean": metrics[name],
                    "single_run_p05": float(s.quantile(0.05)),
                    "single_run_p95": float(s.quantile(0.95)),
                    "within_30pct": name in CLAIM and CLAIM[name].verdict(metrics[name]) == "reproduced",
                }
            )
    return metrics, rows


def _target_str(target: Any) -> str:
    return f"{target:g}" if np.isscalar(target) else f"{target[0]:g}–{target[1]:g}"


def loss_tables(cfg: Config, env: Any, loss: Any, names: tuple[str, ...]) -> tuple[list, list]:
    """Per tracker: the comparison row (loss probability at the default gate with its Wilson 95 %
    interval, miss distances, errors) and the loss-vs-gate rows."""
    events = {name: f"lost/{name}" for name in names}
    curve = stages.event_rows(loss, events, cfg.gates, x_name="gate_m", label="tracker", p_name="p_loss")
    comparison = []
    for name in names:
        row = next(r for r in curve if r["tracker"] == name and r["gate_m"] == cfg.gate)
        row = {k: v for k, v in row.items() if k != "runs"}
        row["max_miss_mean_m"] = float(loss[f"max_miss/{name}"].mean)
        row["max_miss_p95_m"] = float(loss[f"max_miss/{name}"].quantile(0.95))
        for speed, res in zip(cfg.speeds, env.points):
            if f"rms_straight/{name}" in res.by_name:
                row[f"rms_straight_{int(speed)}ms_m"] = float(res[f"rms_straight/{name}"].mean)
                row[f"max_turn_{int(speed)}ms_m"] = float(res[f"max_turn/{name}"].mean)
        comparison.append(row)
    return comparison, curve


def sensitivity_rows(cfg: Config, key: jax.Array, runs: int) -> list[dict[str, Any]]:
    """Envelope under the alternatives named in ASSUMPTIONS (κ = 1, min t-norm), small batches."""
    variants = {
        "paper defaults (κ = 2.17, product)": {},
        "κ = 1 (σ̂ = raw mean)": {"kappa": 1.0},
        "min t-norm": {"tnorm": "min"},
    }
    return [
        {"variant": label, "speed_ms": speed, "runs": runs, **means}
        for label, change in variants.items()
        for speed, means in zip(cfg.speeds, envelope_means(dataclasses.replace(cfg, **change), key, runs))
    ]


def _pair(values: Any, fmt: str = ".0f") -> str:
    return " / ".join(f"{v:{fmt}}" for v in values)


def normalisation_note(kappa: float, metrics: dict[str, Any], sensitivity: list[dict[str, Any]] | None) -> str:
    """Study note on the σ̂ normalisation, every number formatted from this run's ``metrics`` and (full
    runs) the ``sensitivity`` table's κ = 1 rows; speeds 10 / 20 m/s."""
    peaks = (metrics["max_err_turn_10ms_m"], metrics["max_err_turn_20ms_m"])
    paper_peaks = (PAPER["max_turn"][10], PAPER["max_turn"][20])
    side = "below" if max(p - q for p, q in zip(peaks, paper_peaks)) < 0 else "around or above"
    note = (
        f"where the reproduction differs: with σ̂ normalised to the 2-D RMS (κ = {kappa:.2f}) "
        f"σ̂ = {metrics['sigma_hat_final_m']:.1f} m (paper ≈ {PAPER['sigma_final'][10]:g} m), turn windows "
        f"{_pair((metrics['window_turn_10ms'], metrics['window_turn_20ms']), '.1f')} (paper "
        f"{_target_str(PAPER['window_turn'][10])} / {_target_str(PAPER['window_turn'][20])}), "
        f"turn peaks {_pair(peaks)} m, {side} the paper's {_pair(paper_peaks)} m; "
    )
    raw = [r for r in sensitivity or () if r["variant"].startswith("κ = 1")]
    if len(raw) == 2:
        note += (
            f"κ = 1 gives peaks of {_pair(r['max_turn_m'] for r in raw)} m but σ̂ = "
            f"{_pair((r['sigma_final_m'] for r in raw), '.1f')} m and windows "
            f"{_pair((r['window_turn_median'] for r in raw), '.1f')} (table sensitivity): no single noise "
            "normalisation fits every number of the single-run figure"
        )
    else:
        note += "the κ = 1 alternative is in table sensitivity (full runs only)"
    return (
        note + "; the straight-leg peak at 20 m/s includes the scans just after the turn, while the "
        "10-plot window still holds turn plots"
    )


def _figures(cfg: Config, env: Any, singles: list) -> dict[str, Any]:
    """Error vs time (MC means and one run) and the selected window and σ̂, per speed."""
    plt = figures._plt()
    times, n = singles[0][0].times, len(cfg.speeds)
    paper_line = {"color": "r", "ls": "--", "lw": 0.8}
    fig1, ax1 = plt.subplots(1, n, figsize=(6 * n, 4), sharey=True, squeeze=False)
    fig2, ax2 = plt.subplots(2, n, figsize=(6 * n, 6), sharex=True, squeeze=False)
    for i, (speed, res, (sc, single)) in enumerate(zip(cfg.speeds, env.points, singles)):
        for name in BASE_TRACKERS:
            ax1[0, i].plot(times, res[f"err/{name}"].mean, label=f"{name} (MC mean)")
        ax1[0, i].plot(times, single["err"]["fuzzy"], "k:", label="fuzzy, one run")
        ax1[0, i].axhline(PAPER["max_turn"].get(int(speed), np.nan), **paper_line, label="paper's turn peak")
        ax1[0, i].set(title=f"{speed:g} m/s: position error ε", xlabel="t, s", ylabel="ε, m")
        ax2[0, i].step(times, single["window"], where="post", label="one run")
        ax2[0, i].plot(times, res["window"].mean, label="MC mean")
        ax2[0, i].set(title=f"{speed:g} m/s: selected window m", ylabel="m, scans", ylim=(1.5, cfg.max_window + 0.5))
        ax2[1, i].plot(times, single["sigma_hat"], label="one run")
        ax2[1, i].plot(times, res["sigma_hat"].mean, label="MC mean")
        ax2[1, i].axhline(PAPER["sigma_final"][10], **paper_line, label="paper ≈ 10 m")
        ax2[1, i].set(title="noise-scale estimate σ̂", xlabel="t, s", ylabel="σ̂, m")
        for ax in (ax1[0, i], ax2[0, i], ax2[1, i]):
            ax.axvspan(float(sc.turn_start), float(sc.turn_end), color="0.9")
            ax.legend(fontsize=7)
    return {"error_vs_time": fig1, "window_and_sigma": fig2}


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    check_setup(cfg)
    k_single, k_tune, k_sens = jax.random.split(jax.random.PRNGKey(cfg.seed), 3)
    sel0 = paper_selector(cfg)

    t0 = time.perf_counter()  # the reproduction statistics at each speed, common random numbers
    env = mc.sweep(
        envelope_metric(cfg),
        nominal_params(cfg),
        mc.points(["speed"], np.asarray(cfg.speeds, float)[:, None]),
        cfg.envelope_runs,
        cfg.seed,
        block_size=min(1000, cfg.envelope_runs),
        progress=progress,
        name="vessel_tracking.envelope",
    )
    singles = single_runs(cfg, k_single)
    env_s = time.perf_counter() - t0

    problem, exact = selector_problem(cfg, k_tune, cfg.tune_runs)
    tuning = stages.gradient_tuning(  # reverse mode: one gradient ≈ 3 losses; forward mode needs 18
        problem,
        steps=cfg.tune_steps,
        optimizer=optax.adam(cfg.learning_rate),
        mode="reverse",
        sims_per_eval=cfg.tune_runs,
        loss_label="surrogate P(loss) at the default gate",
        progress=progress,
    )
    res = tuning.result
    tuned = with_memberships(sel0, res.params)
    tune_row = {
        "training_runs": cfg.tune_runs,
        "steps": res.n_steps,
        "surrogate_initial": float(res.history.loss[0]),
        "surrogate_tuned": res.loss,
        **{f"exact_{k}_train": float(exact(s)) for k, s in (("initial", sel0), ("tuned", tuned))},
        "wall_s": res.wall_s,
        "compile_s": res.compile_s,
        **{k: [round(float(v), 3) for v in getattr(tuned, k)] for k in ("slopes", "centres")},
    }

    names = BASE_TRACKERS + ("fuzzy_tuned",)
    t0 = time.perf_counter()  # lost/<tracker> (G,) over cfg.gates and max_miss/<tracker>, common random numbers
    loss = mc.monte_carlo(
        loss_metric(cfg, {"fuzzy": sel0, "fuzzy_tuned": tuned}, cfg.gates),
        loss_space(cfg),
        cfg.runs,
        cfg.seed + 1,
        block_size=min(1000, cfg.runs),
        progress=progress,
        name="vessel_tracking.loss",
    )
    loss_s = time.perf_counter() - t0

    env_metrics, rows = envelope(cfg, env)
    comparison, curve = loss_tables(cfg, env, loss, names)
    by = {r["tracker"]: r for r in comparison}
    mean_over = lambda stat: float(np.mean([r[stat].mean for r in env.points]))  # noqa: E731
    metrics = {
        **env_metrics,
        "rmse_straight_m": mean_over("rms_straight/fuzzy"),
        "max_err_straight_m": mean_over("max_straight/fuzzy"),
        "window_straight_median": mean_over("window_straight_median"),
        "sigma_hat_final_m": mean_over("sigma_final"),
        "sigma_settle_scans": mean_over("sigma_settle_scan"),
        **{f"p_loss_{n}": by[n]["p_loss"] for n in names},
        **{f"p_loss_{n}_{c}": by[n][c] for n in names for c in ("wilson_low", "wilson_high")},
        "gate_m": cfg.gate,
        "envelope_within_30pct": int(sum(r["within_30pct"] for r in rows)),
        "envelope_checks": len(rows),
        "loss_runs": cfg.runs,
        "envelope_runs_per_speed": cfg.envelope_runs,
        "envelope_wall_s": env_s,
        "loss_wall_s": loss_s,
        "tune_wall_s": res.wall_s + res.compile_s,
    }
    tables = {
        "envelope": rows,
        "comparison": comparison,
        "track_loss": curve,
        "tuning": [tune_row],
        "single_run": stages.series_rows(
            singles[0][0].times,
            {f"{q}_{int(v)}ms": s[q] for v, (_, s) in zip(cfg.speeds, singles) for q in ("window", "sigma_hat")}
            | {f"err_{n}_{int(v)}ms": s["err"][n] for v, (_, s) in zip(cfg.speeds, singles) for n in BASE_TRACKERS},
        ),
    }
    if cfg.sensitivity_runs:
        tables["sensitivity"] = sensitivity_rows(cfg, k_sens, cfg.sensitivity_runs)
    curves = {n: (loss[f"lost/{n}"].probability, *loss[f"lost/{n}"].interval(0.95)) for n in names}
    figs = {
        **_figures(cfg, env, singles),
        "track_loss_vs_gate": figures.probability_curves(
            np.asarray(cfg.gates),
            curves,
            x_label="gate radius, m",
            y_label="P(track lost) (Wilson 95 %)",
            title=f"track loss vs gate, {loss.runs} runs per point",
            log=True,
            mark=cfg.gate,
        ),
    }
    notes = [
        f"reproduction: {cfg.envelope_runs} Monte-Carlo runs per speed plus one seeded run (figures); the "
        "paper's values are single runs read from Fig. 5, compared with a ±30 % band",
        f"track loss: {cfg.runs} runs per gate width (common random numbers over gates and trackers), loss "
        f"checked from t = {cfg.warm_up:g} s; Wilson 95 % intervals",
        f"tuning: {tune_row['training_runs']} training runs of their own, surrogate "
        f"{tune_row['surrogate_initial']:.3f} → {tune_row['surrogate_tuned']:.3f}; exact loss on the "
        f"training batch {tune_row['exact_initial_train']:.3f} → {tune_row['exact_tuned_train']:.3f}",
        normalisation_note(cfg.kappa, metrics, tables.get("sensitivity")),
        f"at the {cfg.gate:g} m gate: P(loss) fuzzy {metrics['p_loss_fuzzy']:.4f}, tuned "
        f"{metrics['p_loss_fuzzy_tuned']:.4f}, IMM {metrics['p_loss_imm']:.4f}, "
        f"window 5 {metrics['p_loss_window5']:.4f}",
    ]
    return stages.merge(stages.Stage(tables=tables, figures=figs), tuning, metrics=metrics, notes=notes)


STUDY = Study(
    name="vessel_tracking",
    description="Radar tracking of a turning vessel: α–β window bank with a Sugeno window selector "
    "(seed 003), track-loss Monte Carlo vs Kalman/IMM, gradient-tuned selector",
    config=Config,
    presets=PRESETS,
    claims=CLAIMS,
    assumptions=ASSUMPTIONS,
    run=run,
    per_run=per_run,
)
