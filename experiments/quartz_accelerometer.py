"""Study ``quartz_accelerometer``: quartz-flexure pendulous accelerometer with a digital
force-rebalance loop (seed 004, Gnusarev; spec seed004_part4.md B6).  Plant
:mod:`jaxsim.plants.quartz_accelerometer`, loop :mod:`jaxsim.control.force_rebalance`.

The paper prints no numbers (transients as curves only), so every value is assumed (Q-Flex class) and
the claims are checks against independent computations:

1. the plant (with stops) integrated by the toolkit's RK4 against SciPy ``solve_ivp`` (Radau);
2. the PID gains tuned on a bandwidth/noise objective (step-tracking error plus noise in one rollout,
   smooth quantisers) by gradient and PSO on equal budgets (``stages.tune_and_compare``), the designs
   re-scored with the exact quantisers;
3. the tuned loop's −3 dB bandwidth from the linear discrete closed loop (``jaxsim.lti``) checked by a
   simulated sine at that frequency (exact quantisers, stops);
4. output noise vs ADC bits and sample rate: a vmapped Monte Carlo (95 % intervals over seeds) against
   the linear white-quantisation prediction ``(σ_n² + q²/12)‖H_n‖² + q_dac²/12 ‖H_d‖²``.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np
import scipy.integrate
import scipy.linalg

from experiments import figures, stages
from experiments.runner import Study, StudyResult, paper_facts
from jaxsim import lti
from jaxsim.control import force_rebalance as fr
from jaxsim.plants import quartz_accelerometer as qa
from jaxsim.problem import Param, ParamSpace, Problem


@dataclass(frozen=True)
class Config:
    dt: float = 5e-5  # s, base step = fastest control period (20 kHz, assumed)
    substeps: int = 2  # RK4 steps per base step
    sigma_n: float = 1e-3  # V rms pick-off noise per sample (assumed)
    adc_bits: float = 16.0  # assumed
    dac_bits: float = 16.0  # assumed
    step_g: float = 1.0  # g, tuning step input
    t_tune: float = 0.02  # s, tuning rollout
    noise_weight: float = 1.0  # weight of the noise term (noise-only rollout) in the loss
    tau: float = 0.3  # soft-quantiser temperature (gradient path only)
    gains0: tuple[float, float, float] = (2.0e-3, 0.6, 5.0e-7)  # hand PID (kp A/V, ki A/(V·s), kd A·s/V)
    budget: int = 192  # loss evaluations per tuner
    n_particles: int = 8
    n_starts: int = 1
    learning_rate: float = 0.1
    mc_bits: tuple[float, ...] = (8.0, 10.0, 12.0, 14.0, 16.0)
    mc_rates: tuple[int, ...] = (1, 2, 4)  # control period in base steps (20, 10, 5 kHz)
    mc_seeds: int = 16
    t_mc: float = 0.04  # s, Monte-Carlo rollout
    t_settle: float = 0.02  # s, discarded transient
    n_freq: int = 400
    ivp_t: float = 0.02  # s, open-loop check (30 g step into the stops)
    ivp_g: float = 30.0
    ivp_substeps: int = 8  # RK4 steps per base step in the open-loop check (the stops are stiff)
    seed: int = 0


def _conv(cfg: Config, adc_bits: Any = None) -> fr.Converters:
    return fr.Converters(adc_bits=cfg.adc_bits if adc_bits is None else adc_bits, dac_bits=cfg.dac_bits)


def _gains(d: dict[str, Any]) -> fr.Gains:
    return fr.Gains(kp=d["kp"], ki=d["ki"], kd=d["kd"])


def plant_check(cfg: Config, p: qa.Params) -> dict[str, float]:
    """Open loop, zero current, a ``ivp_g`` step (hits the stops): RK4 vs SciPy Radau."""
    n = int(round(cfg.ivp_t / cfg.dt))
    a = cfg.ivp_g * qa.G0
    h = cfg.dt / cfg.ivp_substeps

    def body(x, _):
        x = jax.lax.fori_loop(0, cfg.ivp_substeps, lambda _, y: qa.rk4_step(p, y, 0.0, a, h), x)
        return x, x

    _, xs = jax.jit(lambda: jax.lax.scan(body, jnp.zeros(2), None, length=n))()
    t = cfg.dt * np.arange(1, n + 1)
    J, k, c, ml, ts_ = (float(v) for v in (p.J, p.k, p.c, p.m_l, p.theta_stop))
    ks = float(p.k_stop_ratio) * k

    def rhs(_: float, x: np.ndarray) -> list[float]:  # NumPy restatement of the plant (independent)
        over = x[0] - min(max(x[0], -ts_), ts_)
        return [x[1], (ml * a - c * x[1] - k * x[0] - ks * over) / J]

    sol = scipy.integrate.solve_ivp(
        rhs,
        (0.0, t[-1]),
        np.zeros(2),
        method="DOP853",
        t_eval=t,
        rtol=1e-10,
        atol=1e-12,
    )
    err = np.max(np.abs(np.asarray(xs[:, 0]) - sol.y[0]))
    return {
        "plant_vs_solve_ivp_rel_err": float(err / np.max(np.abs(sol.y[0]))),
        "plant_max_theta_over_stop": float(np.max(np.abs(sol.y[0])) / float(p.theta_stop)),
    }


def problem_of(cfg: Config, p: qa.Params) -> Problem:
    kp0, ki0, kd0 = cfg.gains0
    space = ParamSpace(
        kp=Param(lo=kp0 / 10, hi=kp0 * 10, init=kp0, log=True),
        ki=Param(lo=ki0 / 30, hi=ki0 * 30, init=ki0, log=True),
        kd=Param(lo=kd0 / 30, hi=kd0 * 30, init=kd0, log=True),
    )
    n = int(round(cfg.t_tune / cfg.dt))
    step = jnp.full(n, cfg.step_g * qa.G0)
    conv = _conv(cfg)

    def loss(d: dict[str, Any], _draw: Any, key: jax.Array) -> jax.Array:
        return bandwidth_noise_loss(cfg, p, _gains(d), conv, step, key, cfg.tau)

    return Problem.from_loss("quartz_force_rebalance", space, loss, key=jax.random.PRNGKey(cfg.seed + 1))


def bandwidth_noise_loss(
    cfg: Config, p: qa.Params, g: fr.Gains, conv: fr.Converters, step: jax.Array, key: jax.Array, tau: float
) -> jax.Array:
    """Mean-square step-tracking error (g², noise-free: ∝ 1/bandwidth) + ``noise_weight`` × output
    noise variance (g², zero input, pick-off noise: ∝ bandwidth); quantisers exact when ``tau = 0``."""
    noise = cfg.sigma_n * jax.random.normal(key, step.shape)
    kw = dict(dt=cfg.dt, substeps=cfg.substeps, tau=tau)
    z = jnp.zeros_like(step)  # one vmapped scan: (step, no noise) and (no input, noise)
    out = jax.vmap(lambda a, n: fr.simulate(p, g, conv, a, n, **kw).output_g)(
        jnp.stack([step, z]), jnp.stack([z, noise])
    )
    track = jnp.mean((out[0] - cfg.step_g) ** 2)
    quiet = out[1]
    half = step.shape[0] // 2
    return (track + cfg.noise_weight * jnp.mean(quiet[half:] ** 2)) * 1e4  # (×1e4: in (0.01 g)²


def linear_loop(p: qa.Params, g: fr.Gains, ts: float) -> tuple[np.ndarray, ...]:
    return fr.closed_loop_matrices(p, g, ts)


@functools.cache
def _magnitude(ts: float) -> Callable[..., jax.Array]:
    """Jitted ``|G(e^{jωT_s})|`` of a discrete ``(A, B, C, D)`` by :func:`jaxsim.lti.frequency_response`."""
    return jax.jit(lambda a, b, c, d, w: lti.frequency_response(lti.ss(a, b, c, d, ts), w).magnitude)


def bandwidth_hz(cfg: Config, p: qa.Params, g: fr.Gains, ts: float) -> tuple[float, np.ndarray, np.ndarray]:
    """−3 dB frequency of a (g) → output (g) of the linear discrete closed loop (jaxsim.lti)."""
    A, B, C, D = linear_loop(p, g, ts)
    sf = float(qa.scale_factor(p))
    f = np.logspace(0, np.log10(0.5 / ts) - 1e-3, cfg.n_freq)
    mag = np.asarray(_magnitude(ts)(A, B[:, :1] * qa.G0, C / sf, D[:, :1] * qa.G0 / sf, 2 * np.pi * f)).ravel()
    below = np.nonzero(mag < 1 / np.sqrt(2))[0]
    if below.size == 0 or below[0] == 0:
        return float("nan"), f, mag
    i = below[0]  # log-linear interpolation of the crossing
    x0, x1 = np.log(f[i - 1]), np.log(f[i])
    y0, y1 = mag[i - 1] - 1 / np.sqrt(2), mag[i] - 1 / np.sqrt(2)
    return float(np.exp(x0 - y0 * (x1 - x0) / (y1 - y0))), f, mag


def noise_gains(p: qa.Params, g: fr.Gains, ts: float) -> tuple[float, float]:
    """‖H_n‖² (A²/V²) and ‖H_d‖² (1) of the linear loop, by SciPy's discrete Lyapunov solver."""
    A, B, C, D = linear_loop(p, g, ts)
    if np.max(np.abs(np.linalg.eigvals(A))) >= 1:
        return float("inf"), float("inf")
    out = []
    for j in (1, 2):
        b = B[:, j : j + 1]
        P = scipy.linalg.solve_discrete_lyapunov(A, b @ b.T)
        out.append(float((C @ P @ C.T)[0, 0] + D[0, j] ** 2))
    return out[0], out[1]


def sine_gain(cfg: Config, p: qa.Params, g: fr.Gains, f_hz: float) -> float:
    """Simulated amplitude ratio at ``f_hz`` (1 g sine, exact quantisers, no noise; last half fitted)."""
    periods = max(4.0, f_hz * 0.02)
    n = int(round(periods / f_hz / cfg.dt))
    t = cfg.dt * np.arange(n)
    a = np.sin(2 * np.pi * f_hz * t)
    tr = jax.jit(lambda acc: fr.simulate(p, g, _conv(cfg), acc, jnp.zeros_like(acc), cfg.dt, 1, cfg.substeps))(
        jnp.asarray(a * qa.G0)
    )
    half = n // 2
    basis = np.stack([np.sin(2 * np.pi * f_hz * t[half:]), np.cos(2 * np.pi * f_hz * t[half:])], 1)
    coef, *_ = np.linalg.lstsq(basis, np.asarray(tr.output_g)[half:], rcond=None)
    return float(np.hypot(*coef))


def noise_mc(cfg: Config, p: qa.Params, g: fr.Gains) -> tuple[list[dict[str, float]], dict[str, float]]:
    """Output noise std (g) vs ADC bits × control period: one vmapped batch, seeds per cell."""
    n = int(round(cfg.t_mc / cfg.dt))
    n0 = int(round(cfg.t_settle / cfg.dt))
    bits = np.repeat(np.array(cfg.mc_bits, float), len(cfg.mc_rates))
    rates = np.tile(np.array(cfg.mc_rates, np.int32), len(cfg.mc_bits))
    cells = bits.size
    keys = jax.random.split(jax.random.PRNGKey(cfg.seed + 2), cells * cfg.mc_seeds).reshape(cells, cfg.mc_seeds, 2)

    def one(b, m, key):
        noise = cfg.sigma_n * jax.random.normal(key, (n,))
        tr = fr.simulate(p, g, _conv(cfg, b), jnp.zeros(n), noise, cfg.dt, m, cfg.substeps)
        return jnp.std(tr.output_g[n0:])

    std = np.asarray(
        jax.jit(jax.vmap(jax.vmap(one, (None, None, 0)), (0, 0, 0)))(jnp.asarray(bits), jnp.asarray(rates), keys)
    )
    sf = float(qa.scale_factor(p))
    rows, metrics = [], {}
    for c in range(cells):
        ts = int(rates[c]) * cfg.dt
        conv = _conv(cfg, bits[c])
        hn, hd = noise_gains(p, g, ts)
        pred = np.sqrt((cfg.sigma_n**2 + float(conv.q_adc) ** 2 / 12) * hn + float(conv.q_dac) ** 2 / 12 * hd) / sf
        s = std[c]
        half = 1.96 * s.std(ddof=1) / np.sqrt(s.size) if s.size > 1 else float("nan")
        rows.append(
            {
                "adc_bits": float(bits[c]),
                "rate_hz": 1.0 / ts,
                "noise_mg_mean": 1e3 * float(s.mean()),
                "noise_mg_ci_lo": 1e3 * float(s.mean() - half),
                "noise_mg_ci_hi": 1e3 * float(s.mean() + half),
                "linear_prediction_mg": 1e3 * float(pred),
                "ratio_mc_over_linear": float(s.mean() / pred),
                "ratio_ci_halfwidth": float(half / pred),
            }
        )
    top = [r for r in rows if r["adc_bits"] == max(cfg.mc_bits) and r["rate_hz"] == 1.0 / cfg.dt][0]
    low = [r for r in rows if r["adc_bits"] == min(cfg.mc_bits) and r["rate_hz"] == 1.0 / cfg.dt][0]
    metrics["noise_mc_over_linear_top"] = top["ratio_mc_over_linear"]
    metrics["noise_mc_over_linear_top_ci"] = top["ratio_ci_halfwidth"]
    metrics["noise_mg_top"] = top["noise_mg_mean"]
    metrics["noise_mg_lowest_bits"] = low["noise_mg_mean"]
    metrics["noise_lowest_over_top_bits"] = low["noise_mg_mean"] / top["noise_mg_mean"]
    return rows, metrics


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    p = qa.Params()
    qa.check_params(p)
    metrics: dict[str, float] = dict(plant_check(cfg, p))
    metrics["scale_factor_mA_per_g"] = 1e3 * float(qa.scale_factor(p))

    problem = problem_of(cfg, p)
    comp = stages.tune_and_compare(
        problem,
        cfg.budget,
        ("gradient", "pso"),
        key=jax.random.PRNGKey(cfg.seed),
        learning_rate=cfg.learning_rate,
        n_starts=cfg.n_starts,
        n_particles=cfg.n_particles,
        progress=progress,
        loss_label="bandwidth/noise loss, (0.01 g)²",
    )
    n = int(round(cfg.t_tune / cfg.dt))
    step = jnp.full(n, cfg.step_g * qa.G0)
    exact = jax.jit(lambda d: bandwidth_noise_loss(cfg, p, _gains(d), _conv(cfg), step, problem.key, 0.0))
    kp0, ki0, kd0 = cfg.gains0
    designs = {"hand": {"kp": kp0, "ki": ki0, "kd": kd0}}
    designs.update({k: {n_: float(v) for n_, v in d.items()} for k, d in comp.designs.items()})
    rows, curves = [], {}
    for name, d in designs.items():
        g = _gains({k: jnp.float64(v) for k, v in d.items()})
        bw, f, mag = bandwidth_hz(cfg, p, g, cfg.dt)
        curves[name] = (f, mag)
        rows.append(
            {
                "design": name,
                **d,
                "loss_exact": float(exact({k: jnp.float64(v) for k, v in d.items()})),
                "loss_smooth": float(comp.comparison.results[name].loss) if name != "hand" else float("nan"),
                "bandwidth_hz": bw,
            }
        )
    by = {r["design"]: r for r in rows}
    for name, r in by.items():
        metrics[f"{name}_loss_exact"] = r["loss_exact"]
        metrics[f"{name}_bandwidth_hz"] = r["bandwidth_hz"]
    metrics["gradient_over_pso_loss_exact"] = by["gradient"]["loss_exact"] / by["pso"]["loss_exact"]
    metrics["gradient_over_hand_loss_exact"] = by["gradient"]["loss_exact"] / by["hand"]["loss_exact"]
    metrics["gradient_smooth_over_exact"] = by["gradient"]["loss_smooth"] / by["gradient"]["loss_exact"]

    g_best = _gains({k: jnp.float64(v) for k, v in designs["gradient"].items()})
    bw = by["gradient"]["bandwidth_hz"]
    metrics["sim_gain_at_bandwidth_over_0707"] = sine_gain(cfg, p, g_best, bw) * np.sqrt(2)

    mc_rows, mc_metrics = noise_mc(cfg, p, g_best)
    metrics.update(mc_metrics)

    fig_bw = figures.line_panels(
        [figures.panel(curves, "f, Hz", "|a_out/a_in|", log_y=True, title="closed loop (linear, 20 kHz)")]
    )
    fig_bw.axes[0].set_xscale("log")
    noise_curves = {}
    for m in cfg.mc_rates:
        sel = [r for r in mc_rows if abs(r["rate_hz"] - 1 / (m * cfg.dt)) < 1e-6]
        noise_curves[f"MC {1e-3 / (m * cfg.dt):g} kHz"] = (
            np.array([r["adc_bits"] for r in sel]),
            np.array([r["noise_mg_mean"] for r in sel]),
        )
        noise_curves[f"linear {1e-3 / (m * cfg.dt):g} kHz"] = (
            np.array([r["adc_bits"] for r in sel]),
            np.array([r["linear_prediction_mg"] for r in sel]),
        )
    fig_noise = figures.line_panels(
        [figures.panel(noise_curves, "ADC bits", "output noise, mg rms", log_y=True, title="quantisation")]
    )
    note = (
        f"assumed Q-Flex-class pendulum (f_n = {float(p.f_n):g} Hz, ζ = {float(p.zeta):g}, scale factor "
        f"{metrics['scale_factor_mA_per_g']:.3f} mA/g); tuned gains re-scored with exact quantisers: hand "
        f"{by['hand']['loss_exact']:.4g}, gradient {by['gradient']['loss_exact']:.4g}, PSO "
        f"{by['pso']['loss_exact']:.4g}; gradient design bandwidth {bw:.1f} Hz (linear), simulated gain there "
        f"× √2 = {metrics['sim_gain_at_bandwidth_over_0707']:.3f}; noise at {max(cfg.mc_bits):g} bits, "
        f"{1e-3 / cfg.dt:g} kHz: {metrics['noise_mg_top']:.3f} mg (MC/linear "
        f"{metrics['noise_mc_over_linear_top']:.3f} ± {metrics['noise_mc_over_linear_top_ci']:.3f})"
    )
    return stages.merge(
        comp,
        stages.Stage(
            metrics=metrics,
            tables={"designs": rows, "noise_vs_bits_rate": mc_rows},
            figures={"bandwidth": fig_bw, "noise_vs_bits": fig_noise},
            notes=[note],
        ),
    )


CLAIMS, ASSUMPTIONS = paper_facts("quartz_accelerometer")

STUDY = Study(
    name="quartz_accelerometer",
    description="Seed 004 (Gnusarev): quartz pendulous accelerometer, digital force-rebalance PID with "
    "ADC/DAC quantisation; gradient vs PSO on bandwidth/noise, noise vs bits and rate (Monte Carlo)",
    config=Config,
    presets={
        "quick": dict(budget=96, mc_seeds=8),
        "tiny": dict(
            budget=8,
            n_particles=4,
            t_tune=0.01,
            mc_bits=(10.0, 16.0),
            mc_rates=(1, 2),
            mc_seeds=4,
            t_mc=0.03,
            n_freq=200,
            ivp_t=0.01,
        ),
    },
    claims=CLAIMS,
    assumptions=ASSUMPTIONS,
    run=run,
)
