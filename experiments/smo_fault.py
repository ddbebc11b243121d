"""Study ``smo_fault``: sliding-mode identification of a friction fault in a servo drive (seed 000, paper 2).

The loop, observer and error statistics are :mod:`jaxsim.problem.servo_fault` (paper gains
``k1 = 1e7, k2 = 1, k3 = 1e4``; the fault from ``t = 3 s``).  The study reports:

1. the identification error against the paper's claim (≤ 0.35 % of ``M̃``), with exact switching
   (implicit set-valued step) at the sample period, an exact-switching reference at a smaller step,
   the smooth semi-implicit surrogate, and an explicit RK4 run that fails;
2. the sliding-existence check of the gains (and a pair of gains it rejects);
3. Monte Carlo over measurement noise and plant-parameter spread (the observer keeps the nominal model);
4. gains ``(k1, k3)`` and an equivalent-injection filter tuned by gradient through the smooth
   surrogate under noise, then evaluated with exact switching on fresh noise.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np
import optax

from experiments import figures, stages
from experiments.runner import Claim, Study, StudyResult, paper_facts
from jaxsim.core.integrators import RK4
from jaxsim.estimation import reduced_order_smo as smo
from jaxsim.plants import servo_drive as sd
from jaxsim.problem.servo_fault import (
    SPREAD_FIELDS,
    FaultSetup,
    error_stats,
    gain_tuning_problem,
    observer,
    perturbed,
    run_once,
)

QUANTITIES = ("median", "p99", "max", "max_excl_switching")  # relative identification errors reported
PAPER_CLAIM = 0.0035  # seed 000 paper 2, line 1931: "does not exceed 0.35 % of the identified value"
MC_CASES = {  # name -> (noise level index or None, with the parameter spread)
    "noise level 1": (0, False),
    "noise level 2": (1, False),
    "parameter spread": (None, True),
    "noise level 1 + spread": (0, True),
}


@dataclass(frozen=True)
class Config(FaultSetup):  # + the observer gains, switching and error statistics of FaultSetup
    t_final: float = 8.0  # s; the fault starts at 3 s
    sample_period: float = 1e-5  # s: plant RK4 step, controller and observer period
    reference_step_ratio: int = 10  # exact-switching reference runs at sample_period / this
    reference_t_final: float = 5.0  # s
    mc_cases: tuple = tuple(MC_CASES)  # Monte-Carlo cases (names of MC_CASES), in this order
    mc_samples: int = 8  # per Monte-Carlo case
    angle_noise: tuple[float, ...] = (1e-9, 1e-8)  # rad, std per noise level
    current_noise: tuple[float, ...] = (1e-4, 1e-3)  # A, std per noise level
    parameter_spread: float = 0.01  # relative std of the drive constants in the plant
    tune_steps: int = 25
    tune_learning_rate: float = 0.15  # Adam, on log-gains
    tune_window: float = 1.8  # s after the fault used by the tuning loss
    tune_noise_level: int = 1  # index into angle_noise/current_noise
    tune_keys: int = 2
    seed: int = 0


PRESETS = {
    "quick": dict(
        t_final=4.0,
        sample_period=5e-5,
        reference_step_ratio=5,
        reference_t_final=3.6,
        mc_cases=("noise level 2", "parameter spread"),
        mc_samples=3,
        tune_steps=3,
        tune_window=0.9,
    ),
    "tiny": dict(  # 0.3 s after the fault at 1e-4 s: every stage once (the test's preset)
        t_final=3.3,
        sample_period=1e-4,
        reference_step_ratio=2,
        reference_t_final=3.2,
        mc_cases=("noise level 2", "parameter spread"),
        mc_samples=2,
        tune_steps=1,
        tune_window=0.3,
        tune_keys=1,
    ),
}
SOURCE = "seed 000 paper 2, line 1931 (spec §2.4): max identification error after the fault ≤ 0.35 % of M̃"
CLAIMS = [
    *(
        Claim(m, paper=PAPER_CLAIM, band=(0.0, PAPER_CLAIM), source=SOURCE, note=n)
        for m, n in (
            ("ident_err_rel_median", ""),
            ("ident_err_rel_p99", ""),
            ("ident_err_rel_max_after_3s_excl_switching", "away from the speed reversals, where M̃ jumps by 0.02 N·m"),
            ("ident_err_rel_max_after_3s", "may differ: no continuous observer follows M̃'s jump at a speed reversal"),
        )
    ),
    Claim(
        "ident_bias_theory",
        paper=1 / 1001,
        rel_tol=1e-12,
        source="sliding-mode bias 1/(1 + k1/k3) with the paper's k1 = 1e7, k3 = 1e4 (spec §2.3)",
    ),
]

_, ASSUMPTIONS = paper_facts("smo_fault")


# one jitted run for every call with the same (cfg, ts, t_final): gains, plant, noise and key are
# arguments, so the paper/tuned evaluation runs reuse one program instead of compiling one each
_run_once = jax.jit(run_once, static_argnums=(0, 5, 6))


def stats_row(
    cfg: Config, par: smo.SMOParams, plant: sd.ServoParams, noise: Any, key: jax.Array, ts: float, t_final: float
) -> tuple[dict[str, float], dict[str, np.ndarray]]:
    """``ident_err_rel_*`` of one run, and its series."""
    s = _run_once(cfg, par, plant, jnp.asarray(noise, float), key, float(ts), float(t_final))
    s = {k: np.asarray(v) for k, v in s.items()}
    st = {k: float(v) for k, v in error_stats(cfg, s, ts).items()}
    return {f"ident_err_rel_{k}": v for k, v in st.items() if k != "scale"} | {"scale": st["scale"]}, s


# --- Monte Carlo --------------------------------------------------------------------------------


def monte_carlo(cfg: Config, par: smo.SMOParams, progress: Callable[..., Any]) -> list[dict[str, Any]]:
    """``mc_samples`` runs of each case of ``mc_cases``; case ``i`` draws from ``fold_in(key, i)``."""
    ts, n = cfg.sample_period, cfg.mc_samples

    def one(scales, noise, key):
        return error_stats(cfg, run_once(cfg, par, perturbed(scales), noise, key, ts, cfg.t_final), ts)

    batched = jax.jit(jax.vmap(one))
    rows = []
    key = jax.random.PRNGKey(cfg.seed + 1)
    for ci, name in enumerate(progress(cfg.mc_cases, desc="Monte Carlo", unit="case")):
        level, spread_on = MC_CASES[name]
        noise = (0.0, 0.0) if level is None else (cfg.angle_noise[level], cfg.current_noise[level])
        spread = cfg.parameter_spread if spread_on else 0.0
        k_scale, k_noise = jax.random.split(jax.random.fold_in(key, ci))
        scales = 1.0 + spread * jax.random.normal(k_scale, (n, len(SPREAD_FIELDS)))
        out = batched(scales, jnp.broadcast_to(jnp.asarray(noise), (n, 2)), jax.random.split(k_noise, n))
        rows += [
            {
                "case": name,
                "angle_noise_rad": noise[0],
                "current_noise_A": noise[1],
                "parameter_spread": spread,
                "sample": i,
                **{f"ident_err_rel_{k}": float(v[i]) for k, v in out.items() if k != "scale"},
            }
            for i in range(n)
        ]
    return rows


# --- the study ----------------------------------------------------------------------------------


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    ts, t_final = cfg.sample_period, cfg.t_final
    nominal, zero, key = sd.ServoParams(), (0.0, 0.0), jax.random.PRNGKey(cfg.seed)
    exact = observer(cfg)
    margins = smo.sliding_existence(
        exact.model, exact.gains, exact.P, 2 * jnp.eye(1), sd.sliding_bounds(nominal, cfg.fault_bound)
    )
    try:
        observer(cfg, gains=smo.SMOGains(k1=1.0, k2=1.0, k3=1.0))
        rejected = 0.0
    except ValueError:
        rejected = 1.0

    ts_ref = ts / cfg.reference_step_ratio
    runs = [
        ("exact switching (implicit), sample period", exact, ts, t_final),
        ("smooth surrogate, semi-implicit Euler", observer(cfg, scheme="smooth"), ts, t_final),
        ("exact switching reference, step/10", exact, ts_ref, cfg.reference_t_final),
    ]
    integ = []
    for name, par, step, horizon in progress(runs, desc="nominal runs", unit="run"):
        st, s = stats_row(cfg, par, nominal, zero, key, step, horizon)
        if not integ:
            series, scale = s, st["scale"]  # the main run: figure, and the RK4 run's error scale
        integ.append(
            {
                "integration": name,
                "step_s": step,
                "horizon_s": float(s["t"][-1] + step),
                **{k: v for k, v in st.items() if k != "scale"},
            }
        )
    rk4_err = _rk4_failure(cfg, observer(cfg, scheme="smooth", solver=RK4), key, scale)
    integ.append(
        {"integration": "smooth surrogate, explicit RK4", "step_s": ts, "horizon_s": 3.3, "ident_err_rel_max": rk4_err}
    )
    mc_rows = monte_carlo(cfg, exact, progress)

    level = cfg.tune_noise_level
    problem = gain_tuning_problem(
        cfg,
        ts,
        jnp.array([cfg.angle_noise[level], cfg.current_noise[level]]),
        jax.random.split(jax.random.PRNGKey(cfg.seed + 7), cfg.tune_keys),
        cfg.tune_window,
    )
    tuning = stages.gradient_tuning(
        problem,
        steps=cfg.tune_steps,
        mode="forward",
        optimizer=optax.adam(cfg.tune_learning_rate),
        progress=progress,
        loss_label="mean-square relative error (smooth surrogate, noisy)",
    )
    k1, k3, tau = (float(v) for v in tuning.result.params["theta"])
    noise = (cfg.angle_noise[cfg.tune_noise_level], cfg.current_noise[cfg.tune_noise_level])
    evaluation = []
    for label, par in (("paper gains", exact), ("tuned", observer(cfg, smo.SMOGains(k1, cfg.k2, k3), filter_tau=tau))):
        stats = [
            stats_row(cfg, par, nominal, noise, jax.random.PRNGKey(cfg.seed + 100 + i), ts, t_final)[0]
            for i in range(2)
        ]  # fresh noise, not seen by the tuner
        evaluation.append(
            {
                "gains": label,
                "k1": float(par.gains.k1),
                "k3": float(par.gains.k3),
                "filter_tau": float(par.filter_tau),
                **{
                    f"ident_err_rel_{q}": float(np.mean([st[f"ident_err_rel_{q}"] for st in stats])) for q in QUANTITIES
                },
            }
        )

    main, rho = integ[0], cfg.k1 / cfg.k3
    metrics = {
        f"{k}_after_3s" if k in ("ident_err_rel_max", "ident_err_rel_max_excl_switching") else k: v
        for k, v in main.items()
        if k.startswith("ident_err_rel_")
    }
    metrics["ident_err_rel_max_after_3s_excl_switching"] = metrics.pop("ident_err_rel_max_excl_switching_after_3s")
    metrics |= {
        "ident_bias_theory": 1.0 / (1.0 + rho),
        "paper_claim_rel": PAPER_CLAIM,
        "within_claim_p99": float(main["ident_err_rel_p99"] <= PAPER_CLAIM),
        "within_claim_max": float(main["ident_err_rel_max"] <= PAPER_CLAIM),
        **{
            f"{tag}_ident_err_rel_{q}": integ[i][f"ident_err_rel_{q}"]
            for i, tag in ((2, "reference"), (1, "smooth"))
            for q in ("median", "p99")
        },
        "explicit_rk4_ident_err_rel_max": rk4_err,
        "sliding_delta": margins.delta,
        "sliding_k3_min": margins.k3_min,
        "unreachable_gains_rejected": rejected,
        "tuned_k1": k1,
        "tuned_k3": k3,
        "tuned_filter_tau": tau,
        **{
            f"noisy_{tag}_ident_err_rel_{q}": ev[f"ident_err_rel_{q}"]
            for q in ("median", "p99")
            for tag, ev in zip(("paper_gains", "tuned"), evaluation)
        },
    }
    for name in cfg.mc_cases:
        tag = name.replace(" + ", "_").replace(" ", "_")
        for q in ("median", "p99"):
            metrics[f"mc_{tag}_{q}"] = float(np.median([r[f"ident_err_rel_{q}"] for r in mc_rows if r["case"] == name]))
    notes = [
        f"noise-free, paper gains, exact switching at {ts:g} s: median {main['ident_err_rel_median']:.3%}, "
        f"p99 {main['ident_err_rel_p99']:.3%}, max {main['ident_err_rel_max']:.2%} (max away from speed "
        f"reversals {main['ident_err_rel_max_excl_switching']:.3%}); paper: ≤ 0.35 %",
        f"the bias floor 1/(1 + k1/k3) = {1 / (1 + rho):.3%} is structural: in the sliding mode e2 obeys "
        "ė2 = −(1 + k1/k3) e2 + M̃/(J_t i_r), and d̂ = (k1/k3) e2",
        "the max is set by the speed reversals: M̃ jumps by 2·0.5·M_dry = 0.02 N·m (≈ 7.7 % of max|M̃|) and the "
        "nominal-friction sign of the estimated speed flips ~1 ms late; no continuous observer can follow a jump, "
        "so the paper's 0.35 % holds for the median and p99 but not for the max at those instants",
        "explicit RK4 on the smooth surrogate: eigenvalue ≈ −k3/ε = −1e7 s⁻¹, far outside its stability region",
        "at a speed reversal the rotor sticks for ~2 ms (dry friction): the plant's exact sign(x2) chatters there "
        "under RK4 (its Filippov average is what the observer follows), see the zoom in identification.png",
        "angle noise is differentiated twice by the observer: d̂ noise ∝ (k1/k3)·σ/dt, so 1e-8 rad already "
        "costs percent-level errors without the equivalent-injection filter",
    ]
    groups = {c: [r["ident_err_rel_median"] for r in mc_rows if r["case"] == c] for c in cfg.mc_cases}
    mc_fig = figures.box_by_group(
        groups,
        y_label="median relative identification error",
        log=True,
        reference=PAPER_CLAIM,
        reference_label="paper: 0.35 %",
    )
    own = stages.Stage(
        tables={"integration": integ, "monte_carlo": mc_rows, "tuned_vs_paper_under_noise": evaluation},
        figures={"identification": _plot_identification(series, ts), "monte_carlo": mc_fig},
    )
    return stages.merge(own, tuning, metrics=metrics, notes=notes)


def _rk4_failure(cfg: Config, rk4: smo.SMOParams, key: jax.Array, scale: float) -> float:
    """Max error (relative to ``scale``) of the smooth surrogate under explicit RK4 on [0.5, 3.3] s."""
    ts = cfg.sample_period
    s = _run_once(cfg, rk4, sd.ServoParams(), jnp.zeros(2), key, float(ts), 3.3)
    err = np.abs(np.asarray(s["M_hat"]) - np.asarray(s["M"]))[int(0.5 / ts) :]
    return float(np.nanmax(err) / scale) if np.all(np.isfinite(err)) else float("inf")


def _plot_identification(s: dict[str, np.ndarray], ts: float):
    """Fault torque and estimate, the relative error against the claim, a zoom on a speed reversal."""
    plt = figures._plt()
    t, M, Mh = s["t"], s["M"], s["M_hat"]
    after = t >= 3.0
    fig, axes = plt.subplots(3, 1, figsize=(10, 9))
    axes[0].plot(t, M, lw=1.5, label="M̃(t) (true)")
    axes[0].plot(t, Mh, "--", lw=1.0, label="observer estimate")
    axes[0].set(
        ylabel="M̃, N·m",
        ylim=(-0.35, 0.35),
        xlabel="t, s",
        title="fault torque and its sliding-mode estimate (exact switching, paper gains)",
    )
    rel = np.abs(Mh - M) / np.max(np.abs(M[after]))
    axes[1].semilogy(t[after], np.maximum(rel[after], 1e-8), lw=0.6, label="|M̃̂ − M̃| / max|M̃|")
    axes[1].axhline(PAPER_CLAIM, color="r", ls="--", label="paper: 0.35 %")
    axes[1].set(ylabel="relative error", xlabel="t, s")
    flips = np.nonzero((np.diff(np.sign(s["x2"])) != 0) & (t[1:] > 3.1))[0]
    c = flips[0] if len(flips) else len(t) // 2
    z = slice(max(0, c - int(0.02 / ts)), c + int(0.02 / ts))
    axes[2].plot(t[z], M[z], label="M̃")
    axes[2].plot(t[z], Mh[z], "--", label="estimate")
    axes[2].set(title="zoom on a speed reversal (M̃ jumps by 0.02 N·m)", xlabel="t, s", ylabel="M̃, N·m")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


STUDY = Study(
    name="smo_fault",
    description="Paper 2: reduced-order sliding-mode observer identifying a friction fault in a servo drive",
    config=Config,
    presets=PRESETS,
    claims=CLAIMS,
    assumptions=ASSUMPTIONS,
    run=run,
)
