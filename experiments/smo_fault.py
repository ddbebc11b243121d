"""Study ``smo_fault``: sliding-mode identification of a friction fault in a servo drive (seed 000, paper 2).

The loaded drive of joint 2 of a PUMA-type arm (:mod:`jaxsim.plants.servo_drive`, paper constants)
tracks ``q2* = sin t`` under the paper's PID (10, 0.5, 1); from ``t = 3 s`` viscous and dry friction
grow by 50 %.  The reduced-order sliding-mode observer
(:mod:`jaxsim.estimation.reduced_order_smo`, gains ``k1 = 1e7, k2 = 1, k3 = 1e4``) identifies the
fault torque ``M̃(t)`` from the angle and the current.  The study reports:

1. the identification error over time against the paper's claim (≤ 0.35 % of ``M̃``), with exact
   switching (implicit set-valued step) at the sample period, an exact-switching reference at a
   10× smaller step, the smooth semi-implicit surrogate, and an explicit RK4 run that fails;
2. the sliding-existence check of the gains (and a pair of gains it rejects);
3. Monte Carlo over measurement noise and plant-parameter spread (the observer keeps the nominal model);
4. gains ``(k1, k3)`` and an equivalent-injection filter tuned by gradient through the smooth
   surrogate under noise, then evaluated with exact switching on fresh noise.

Relative errors are ``|M̃̂ − M̃| / max|M̃|`` over ``t ≥ t_fault + settle`` (the paper gives no
normalisation; ``M̃`` itself jumps through ±0.01 N·m at every speed reversal, so a pointwise ratio
is ill-defined there).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np
import optax

from experiments.study import Study, StudyResult, assumption
from jaxsim.control.pid import PIDParams, pid_init, pid_step
from jaxsim.core.integrators import RK4
from jaxsim.core.rollout import ClosedLoop, Timing, simulate
from jaxsim.core.signals import Sine
from jaxsim.core.system import Controller, Sensor
from jaxsim.estimation import reduced_order_smo as smo
from jaxsim.plants import servo_drive as sd

PAPER_CLAIM = 0.0035
SPREAD_FIELDS = ("R_m", "L_m", "k_w", "k_m", "J", "k_y")


@dataclass(frozen=True)
class Config:
    quick: bool = False
    t_final: float = 8.0  # s (quick: 4 s); the fault starts at 3 s
    sample_period: float = 1e-5  # s: plant RK4 step, controller and observer period (quick: 5e-5)
    reference_step_ratio: int = 10  # exact-switching reference runs at sample_period / this (quick: 5)
    reference_t_final: float = 5.0  # s (quick: 3.6 s)
    k1: float = 1e7  # paper
    k2: float = 1.0  # paper
    k3: float = 1e4  # paper
    Q: float = -1.0  # paper
    width: float = 1e-3  # rad, boundary layer ε of the smooth switch e/(|e| + ε)
    pid_derivative_filter: float = 1e-3  # s
    fault_bound: float = 0.5  # N·m, |M̃| ≤ this for the existence check
    settle: float = 0.05  # s after the fault onset before errors are counted
    switching_window: float = 5e-3  # s either side of a speed reversal (for the "excluding" metric)
    mc_samples: int = 8  # per Monte-Carlo case (quick: 3, and only noise level 2 and the spread)
    angle_noise: tuple[float, ...] = (1e-9, 1e-8)  # rad, std per noise level
    current_noise: tuple[float, ...] = (1e-4, 1e-3)  # A, std per noise level
    parameter_spread: float = 0.01  # relative std of the drive constants in the plant
    tune_steps: int = 25  # quick: 3
    tune_learning_rate: float = 0.15  # Adam, on log-gains
    tune_window: float = 1.8  # s after the fault used by the tuning loss (quick: 0.9)
    tune_noise_level: int = 1  # index into angle_noise/current_noise
    tune_keys: int = 2
    seed: int = 0


ASSUMPTIONS = {
    "drive_equations": assumption(
        "eq. (4.1) rebuilt as in spec §2.2 (standard drive model of the authors' group)",
        "the display equation is lost in the extraction; the companion paper (Zuev et al., Sensors 2022, "
        "22(1), 317) was searched for but its body text was not available, only its abstract"),
    "arm_coupling": assumption(
        "H* = M22(q3), h* = Ḣ*, M* = M23 q̈3 + ∂M23/∂q3 q̇3² − ½∂M11/∂q2 q̇1² + ∂V/∂q2 of an RRR arm",
        "the coupling equations of ref. [22] are lost; derived from the Lagrangian with the paper's link "
        "parameters (tested against an independent forward-kinematics Lagrangian)"),
    "sensors": assumption("angle x1 and current x3", "the only set consistent with k = 2, N* = 0, M* = 2"),
    "reduced_model": assumption("x*2 = x2/i_r + φ(t) x3, φ = −a L_m/(i_r k_ω)", "spec §2.3 [ours]"),
    "self_tuning_device": assumption("none", "not described in the paper"),
    "pid": assumption("U = kp e + ki ∫e + kd D, D = s/(1e-3 s + 1) e, no voltage limit",
                      "the paper gives only the gains (10, 0.5, 1); a 1 ms derivative filter tames noise"),
    "initial_state": assumption("at rest at q2 = 0 with the holding current; observer ẑ2(0) = 0", "not stated"),
    "sample_period": assumption(1e-5, "integration step and ε are not given; 100 kHz sampling"),
    "width": assumption(1e-3, "ε of v_eq = e1/(|e1| + ε) is not given"),
    "fault_bound": assumption(0.5, "β for the existence check: about twice the largest |M̃| of the scenario"),
    "error_normalisation": assumption("max |M̃| after the fault", "the paper does not define its 0.35 %"),
    "settle": assumption(0.05, "seconds after the onset before errors count (observer time constant ≈ 1 ms)"),
    "noise_levels": assumption("angle 1e-9 / 1e-8 rad, current 1e-4 / 1e-3 A",
                               "the paper is noise-free; these levels show where the identification breaks"),
    "parameter_spread": assumption(0.01, "relative std of R_m, L_m, k_ω, k_m, J, k_y in the plant; observer nominal"),
}


# --- the closed loop ----------------------------------------------------------------------------

def _pid_init(p, r0, y0):
    return pid_init(p, r0, y0[:1])


def _pid_step(p, s, r, y, ts, t):
    return pid_step(p, s, r, y[:1], ts, t)


def position_loop(cfg: Config, plant_params: sd.ServoParams, noise: jax.Array) -> ClosedLoop:
    """PID on the measured angle, reference ``sin t``, Gaussian sensor of std ``noise`` (2,)."""
    ctrl = Controller(PIDParams(kp=10.0, ki=0.5, kd=1.0, tf=cfg.pid_derivative_filter, anti_windup="none"),
                      _pid_init, _pid_step, name="position_pid")
    return ClosedLoop(sd.servo_drive_plant(plant_params), ctrl, reference=Sine(1.0, 1.0 / (2 * np.pi)),
                      sensor=Sensor(params=noise, name="gaussian"))  # gaussian_sensor() is not traceable


def observer(cfg: Config, gains: smo.SMOGains | None = None, scheme: str = "implicit_sign",
             filter_tau: float = 0.0, solver=None, check: bool = True) -> smo.SMOParams:
    gains = smo.SMOGains(cfg.k1, cfg.k2, cfg.k3) if gains is None else gains
    nominal = sd.ServoParams()
    bounds = sd.sliding_bounds(nominal, cfg.fault_bound) if check else None
    kw = {} if solver is None else {"solver": solver}
    return smo.reduced_order_smo(sd.reduced_model(sd.ObserverModelParams(Q=cfg.Q)), gains, bounds=bounds,
                                 width=cfg.width, filter_tau=filter_tau, scheme=scheme, **kw)


def run_once(cfg: Config, par: smo.SMOParams, plant_params: sd.ServoParams, noise: jax.Array, key: jax.Array,
             ts: float, t_final: float) -> dict[str, jax.Array]:
    """Simulate loop + observer; returns the time series ``t, M, M_hat, x2``."""
    loop = position_loop(cfg, plant_params, noise)
    tr = simulate(loop, sd.initial_state(plant_params, 0.0), Timing(t_final, ts), key=key)
    run = smo.smo_filter(par, tr.t, tr.y_meas, tr.u)
    nominal = sd.ServoParams()
    m_true = jax.vmap(sd.fault_torque, (None, 0, 0))(plant_params, tr.x, tr.t)
    m_hat = jax.vmap(sd.fault_torque_from_estimate, (None, 0, 0))(nominal, tr.t, run.d_hat)
    return {"t": tr.t, "M": m_true, "M_hat": m_hat, "x2": tr.x[:, 1], "v": run.v}


def error_stats(cfg: Config, t, M, M_hat, x2) -> dict[str, jax.Array]:
    """Relative identification errors (jittable): median, p99, max, max away from speed reversals."""
    onset = sd.FaultParams().onset
    after = t >= onset
    scale = jnp.max(jnp.where(after, jnp.abs(M), 0.0))
    rel = jnp.abs(M_hat - M) / scale
    win = t >= onset + cfg.settle
    flip = jnp.concatenate([jnp.zeros(1, bool), jnp.sign(x2[1:]) != jnp.sign(x2[:-1])])
    k = int(round(cfg.switching_window / float(cfg.sample_period)))
    near = jnp.convolve(flip.astype(float), jnp.ones(2 * max(k, 1) + 1), mode="same") > 0
    masked = jnp.where(win, rel, jnp.nan)
    pre = (t >= 0.5) & (t < onset)
    return {
        "median": jnp.nanmedian(masked),
        "p99": jnp.nanpercentile(masked, 99.0),
        "max": jnp.nanmax(masked),
        "max_excl_switching": jnp.nanmax(jnp.where(near, jnp.nan, masked)),
        "pre_fault_max": jnp.max(jnp.where(pre, jnp.abs(M_hat), 0.0)) / scale,
        "scale": scale,
    }


def _stats_np(cfg: Config, series: dict, ts: float) -> dict[str, float]:
    c = dataclasses.replace(cfg, sample_period=ts)
    out = error_stats(c, series["t"], series["M"], series["M_hat"], series["x2"])
    return {k: float(v) for k, v in out.items()}


# --- Monte Carlo --------------------------------------------------------------------------------

def perturbed(scales: jax.Array) -> sd.ServoParams:
    base = sd.ServoParams()
    drive = dataclasses.replace(base.drive, **{f: getattr(base.drive, f) * s for f, s in zip(SPREAD_FIELDS, scales)})
    return dataclasses.replace(base, drive=drive)


def monte_carlo(cfg: Config, par, ts, t_final, cases, n, progress):
    def one(scales, noise, key):
        s = run_once(cfg, par, perturbed(scales), noise, key, ts, t_final)
        return error_stats(dataclasses.replace(cfg, sample_period=ts), s["t"], s["M"], s["M_hat"], s["x2"])

    batched = jax.jit(jax.vmap(one))
    rows = []
    key = jax.random.PRNGKey(cfg.seed + 1)
    for ci, (name, noise, spread) in enumerate(progress(cases, desc="Monte Carlo", unit="case")):
        k_scale, k_noise = jax.random.split(jax.random.fold_in(key, ci))
        scales = 1.0 + spread * jax.random.normal(k_scale, (n, len(SPREAD_FIELDS)))
        out = batched(scales, jnp.broadcast_to(jnp.asarray(noise), (n, 2)), jax.random.split(k_noise, n))
        for i in range(n):
            rows.append({"case": name, "angle_noise_rad": noise[0], "current_noise_A": noise[1],
                         "parameter_spread": spread, "sample": i,
                         **{f"ident_err_rel_{k}": float(v[i]) for k, v in out.items() if k != "scale"}})
    return rows


# --- tuning -------------------------------------------------------------------------------------

def tune(cfg: Config, ts: float, progress) -> tuple[dict, list[dict]]:
    """Adam on (log k1, log k3, log τ) through the smooth surrogate on a noisy segment around the fault."""
    onset = sd.FaultParams().onset
    t_end = onset + (0.9 if cfg.quick else cfg.tune_window)
    noise = jnp.array([cfg.angle_noise[cfg.tune_noise_level], cfg.current_noise[cfg.tune_noise_level]])
    keys = jax.random.split(jax.random.PRNGKey(cfg.seed + 7), cfg.tune_keys)
    loop = position_loop(cfg, sd.ServoParams(), noise)
    timing = Timing(round(t_end / ts) * ts, ts)
    trs = jax.jit(jax.vmap(lambda k: simulate(loop, sd.initial_state(sd.ServoParams(), 0.0), timing, key=k)))(keys)
    start = int(round((onset - 0.1) / ts))
    seg = jax.tree_util.tree_map(lambda a: a[:, start:], (trs.t, trs.y_meas, trs.u, trs.x))
    m_true = jax.vmap(jax.vmap(sd.fault_torque, (None, 0, 0)), (None, 0, 0))(sd.ServoParams(), seg[3], seg[0])
    template = observer(cfg, scheme="smooth", filter_tau=1e-4, check=False)
    window = seg[0][0] >= onset + cfg.settle
    scale = jnp.max(jnp.abs(m_true))

    def loss(theta):
        k1, k3, tau = jnp.exp(theta)
        par = dataclasses.replace(template, gains=smo.SMOGains(k1, cfg.k2, k3), filter_tau=tau)

        def one(t, y, u, m):
            run = smo.smo_filter(par, t, y, u)
            m_hat = jax.vmap(sd.fault_torque_from_estimate, (None, 0, 0))(sd.ServoParams(), t, run.d_hat)
            return jnp.sum(jnp.where(window, ((m_hat - m) / scale) ** 2, 0.0)) / jnp.sum(window)

        return jnp.mean(jax.vmap(one)(seg[0], seg[1], seg[2], m_true))

    value_and_grad = jax.jit(lambda th: (loss(th), jax.jacfwd(loss)(th)))
    theta = jnp.log(jnp.array([cfg.k1, cfg.k3, 1e-4]))
    opt = optax.adam(cfg.tune_learning_rate)
    state = opt.init(theta)
    history, best = [], (np.inf, theta)
    steps = 3 if cfg.quick else cfg.tune_steps
    for i in progress(range(steps), desc="tuning (smooth surrogate)", unit="step"):
        val, grad = value_and_grad(theta)
        history.append({"step": i, "loss_rms_rel": float(jnp.sqrt(val)), "k1": float(jnp.exp(theta[0])),
                        "k3": float(jnp.exp(theta[1])), "filter_tau": float(jnp.exp(theta[2]))})
        if float(val) < best[0]:
            best = (float(val), theta)
        upd, state = opt.update(grad, state)
        theta = theta + upd
    k1, k3, tau = (float(v) for v in jnp.exp(best[1]))
    return {"k1": k1, "k3": k3, "filter_tau": tau, "loss_rms_rel": float(np.sqrt(best[0]))}, history


# --- the study ----------------------------------------------------------------------------------

def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    ts = 5e-5 if cfg.quick else cfg.sample_period
    t_final = 4.0 if cfg.quick else cfg.t_final
    ts_ref = ts / (5 if cfg.quick else cfg.reference_step_ratio)
    t_ref = 3.6 if cfg.quick else cfg.reference_t_final
    n_mc = 3 if cfg.quick else cfg.mc_samples
    nominal = sd.ServoParams()
    zero = jnp.zeros(2)
    key = jax.random.PRNGKey(cfg.seed)

    exact = observer(cfg)
    margins = smo.sliding_existence(exact.model, exact.gains, exact.P, 2 * jnp.eye(1),
                                    sd.sliding_bounds(nominal, cfg.fault_bound))
    try:
        observer(cfg, gains=smo.SMOGains(k1=1.0, k2=1.0, k3=1.0))
        rejected = 0.0
    except ValueError:
        rejected = 1.0

    runs = {}
    steps = [("exact switching (implicit), sample period", exact, ts, t_final),
             ("smooth surrogate, semi-implicit Euler", observer(cfg, scheme="smooth"), ts, t_final),
             ("exact switching reference, step/10", exact, ts_ref, t_ref)]
    for name, par, step, horizon in progress(steps, desc="nominal runs", unit="run"):
        s = jax.jit(lambda p, k: run_once(cfg, p, nominal, zero, k, step, horizon))(par, key)
        runs[name] = ({k: np.asarray(v) for k, v in s.items()}, step)
    rk4 = observer(cfg, scheme="smooth", solver=RK4)
    integ_rows = []
    for name, (s, step) in runs.items():
        st = _stats_np(cfg, s, step)
        integ_rows.append({"integration": name, "step_s": step, "horizon_s": float(s["t"][-1] + step),
                           **{f"ident_err_rel_{k}": v for k, v in st.items() if k != "scale"}})
    rk4_err = _rk4_failure(cfg, rk4, ts, key, scale=_stats_np(cfg, runs[steps[0][0]][0], ts)["scale"])
    integ_rows.append({"integration": "smooth surrogate, explicit RK4", "step_s": ts, "horizon_s": 3.3,
                       "ident_err_rel_max": rk4_err})

    main = integ_rows[0]
    cases = [("noise level 2", (cfg.angle_noise[1], cfg.current_noise[1]), 0.0),
             ("parameter spread", (0.0, 0.0), cfg.parameter_spread)]
    if not cfg.quick:
        cases[:0] = [("noise level 1", (cfg.angle_noise[0], cfg.current_noise[0]), 0.0)]
        cases.append(("noise level 1 + spread", (cfg.angle_noise[0], cfg.current_noise[0]), cfg.parameter_spread))
    mc_rows = monte_carlo(cfg, exact, ts, t_final, cases, n_mc, progress)

    tuned, history = tune(cfg, ts, progress)
    noise_t = jnp.array([cfg.angle_noise[cfg.tune_noise_level], cfg.current_noise[cfg.tune_noise_level]])
    evaluation = []
    for label, par in (("paper gains", exact),
                       ("tuned", observer(cfg, smo.SMOGains(tuned["k1"], cfg.k2, tuned["k3"]),
                                          filter_tau=tuned["filter_tau"]))):
        stats = []
        for i in range(2):
            k = jax.random.PRNGKey(cfg.seed + 100 + i)  # fresh noise, not seen by the tuner
            s = jax.jit(lambda p, kk: run_once(cfg, p, nominal, noise_t, kk, ts, t_final))(par, k)
            stats.append(_stats_np(cfg, {kk: np.asarray(v) for kk, v in s.items()}, ts))
        evaluation.append({"gains": label, "k1": float(par.gains.k1), "k3": float(par.gains.k3),
                           "filter_tau": float(par.filter_tau),
                           **{f"ident_err_rel_{k}": float(np.mean([st[k] for st in stats]))
                              for k in ("median", "p99", "max", "max_excl_switching")}})

    rho = cfg.k1 / cfg.k3
    metrics = {
        "ident_err_rel_median": main["ident_err_rel_median"],
        "ident_err_rel_p99": main["ident_err_rel_p99"],
        "ident_err_rel_max_after_3s": main["ident_err_rel_max"],
        "ident_err_rel_max_after_3s_excl_switching": main["ident_err_rel_max_excl_switching"],
        "ident_err_rel_pre_fault_max": main["ident_err_rel_pre_fault_max"],
        "ident_bias_theory": 1.0 / (1.0 + rho),
        "paper_claim_rel": PAPER_CLAIM,
        "within_claim_p99": float(main["ident_err_rel_p99"] <= PAPER_CLAIM),
        "within_claim_max": float(main["ident_err_rel_max"] <= PAPER_CLAIM),
        "reference_ident_err_rel_median": integ_rows[2]["ident_err_rel_median"],
        "reference_ident_err_rel_p99": integ_rows[2]["ident_err_rel_p99"],
        "smooth_ident_err_rel_median": integ_rows[1]["ident_err_rel_median"],
        "smooth_ident_err_rel_p99": integ_rows[1]["ident_err_rel_p99"],
        "explicit_rk4_ident_err_rel_max": rk4_err,
        "sliding_delta": margins.delta,
        "sliding_k3_min": margins.k3_min,
        "unreachable_gains_rejected": rejected,
        "tuned_k1": tuned["k1"],
        "tuned_k3": tuned["k3"],
        "tuned_filter_tau": tuned["filter_tau"],
        "noisy_paper_gains_ident_err_rel_median": evaluation[0]["ident_err_rel_median"],
        "noisy_tuned_ident_err_rel_median": evaluation[1]["ident_err_rel_median"],
        "noisy_paper_gains_ident_err_rel_p99": evaluation[0]["ident_err_rel_p99"],
        "noisy_tuned_ident_err_rel_p99": evaluation[1]["ident_err_rel_p99"],
    }
    for name, _, _ in cases:
        rows = [r for r in mc_rows if r["case"] == name]
        tag = name.replace(" + ", "_").replace(" ", "_")
        metrics[f"mc_{tag}_median"] = float(np.median([r["ident_err_rel_median"] for r in rows]))
        metrics[f"mc_{tag}_p99"] = float(np.median([r["ident_err_rel_p99"] for r in rows]))
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
    figs = {"identification": _plot_identification(runs[steps[0][0]][0], ts),
            "monte_carlo": _plot_mc(mc_rows), "tuning": _plot_tuning(history)}
    return StudyResult(metrics=metrics,
                       tables={"integration": integ_rows, "monte_carlo": mc_rows, "tuning_history": history,
                               "tuned_vs_paper_under_noise": evaluation},
                       assumptions=ASSUMPTIONS, figures=figs, notes=notes)


def _rk4_failure(cfg: Config, rk4: smo.SMOParams, ts: float, key, scale: float) -> float:
    """Max error (relative to ``scale``) of the smooth surrogate under explicit RK4 on [0.5, 3.3] s."""
    s = jax.jit(lambda p, k: run_once(cfg, p, sd.ServoParams(), jnp.zeros(2), k, ts, 3.3))(rk4, key)
    err = np.abs(np.asarray(s["M_hat"]) - np.asarray(s["M"]))[int(0.5 / ts):]
    return float(np.nanmax(err) / scale) if np.all(np.isfinite(err)) else float("inf")


def _plot_identification(s, ts):
    import matplotlib.pyplot as plt

    t, M, Mh = s["t"], s["M"], s["M_hat"]
    scale = np.max(np.abs(M[t >= 3.0]))
    fig, axes = plt.subplots(3, 1, figsize=(10, 9))
    axes[0].plot(t, M, lw=1.5, label="M̃(t) (true)")
    axes[0].plot(t, Mh, "--", lw=1.0, label="observer estimate")
    axes[0].set_ylabel("N·m")
    axes[0].set_ylim(-0.35, 0.35)
    axes[0].legend()
    axes[0].set_title("fault torque and its sliding-mode estimate (exact switching, paper gains)")
    rel = np.abs(Mh - M) / scale
    axes[1].semilogy(t[t >= 3.0], np.maximum(rel[t >= 3.0], 1e-8), lw=0.6)
    axes[1].axhline(PAPER_CLAIM, color="r", ls="--", label="paper: 0.35 %")
    axes[1].set_ylabel("|M̃̂ − M̃| / max|M̃|")
    axes[1].legend()
    flips = np.nonzero((np.diff(np.sign(s["x2"])) != 0) & (t[1:] > 3.1))[0]
    c = flips[0] if len(flips) else len(t) // 2
    z = slice(max(0, c - int(0.02 / ts)), c + int(0.02 / ts))
    axes[2].plot(t[z], M[z], label="M̃")
    axes[2].plot(t[z], Mh[z], "--", label="estimate")
    axes[2].set_title("zoom on a speed reversal (M̃ jumps by 0.02 N·m)")
    axes[2].set_xlabel("t, s")
    axes[2].legend()
    for ax in axes:
        ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def _plot_mc(rows):
    import matplotlib.pyplot as plt

    cases = list(dict.fromkeys(r["case"] for r in rows))
    fig, ax = plt.subplots(figsize=(8, 4))
    data = [[r["ident_err_rel_median"] for r in rows if r["case"] == c] for c in cases]
    ax.boxplot(data)
    ax.set_xticks(range(1, len(cases) + 1), cases, rotation=15)
    ax.set_yscale("log")
    ax.axhline(PAPER_CLAIM, color="r", ls="--", label="paper: 0.35 %")
    ax.set_ylabel("median relative identification error")
    ax.legend()
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def _plot_tuning(history):
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    ax.semilogy([h["step"] for h in history], [h["loss_rms_rel"] for h in history], "o-")
    ax.set_xlabel("Adam step")
    ax.set_ylabel("RMS relative error (smooth surrogate, noisy)")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


STUDY = Study(
    name="smo_fault",
    description="Paper 2: reduced-order sliding-mode observer identifying a friction fault in a servo drive",
    config_cls=Config,
    run=run,
)
