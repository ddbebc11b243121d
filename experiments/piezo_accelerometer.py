"""Study ``piezo_accelerometer``: resonance by white noise (seed 004 #25) and the KD45 calibration
bench's high-pass corner (#26); spec seed004_part2 §2.9 and §2.8.

* **Bench (#26).** ``τ = C_d·(Z_n ∥ R_y)`` and ``f_c = 1/(2πτ)`` from the paper's component values;
  ``|H|`` at 1 Hz, 10 Hz, ``f_c``; then the bench procedure simulated: the sensor rotated in gravity
  (``a = g₀ cos φ sin 2πft``, φ giving 1 m/s²) at a few frequencies, the output amplitude by a sine
  fit, and ``K_p``, ``τ`` recovered by linear least squares on ``1/|H|² = 1/K_p² + 1/(K_p τ ω)²``.
* **Table 1 (#25).** The paper's stepped-sine amplitudes: the table's peak, its half-power width,
  the spec's Lorentzian check, and a linear resonator fitted to all 29 distinct points by
  Levenberg–Marquardt on the log amplitude (it cannot follow the asymmetric peak: residuals shown).
* **White noise (#25).** The resonator (``f_r`` = 807.5 Hz from the paper, ``Q`` assumed) driven
  through the coil by white noise for ``record_s`` seconds, output noise added; H1 estimate by Welch,
  resonator fitted to the complex H1 near the peak (LM on autodiff Jacobians); batched over noise
  seeds to check the paper's ±0.1 Hz in < 10 s, against peak picking on the output spectrum.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np

from experiments import figures, stages
from experiments.runner import Study, StudyResult, paper_facts
from jaxsim.core.integrators import RK4, integrate
from jaxsim.estimation.resonator_fit import fit_resonator, resonator_response
from jaxsim.estimation.spectral import frf_h1
from jaxsim.lti.discretize import hold_matrices
from jaxsim.plants import piezo_accelerometer as pa

# Paper #25, Table 1 (output amplitude, V; seed lines 8190–8205): coarse, fine and refined sweeps.
# 800 Hz and 810 Hz appear in two sweeps with the same value; kept once.
TABLE1_HZ = (700, 800, 900, 1000, 1100, 1200, 1300, 1400, 1500, 750, 760, 770, 780, 790, 810, 820, 830, 840, 850)
TABLE1_HZ += (805, 806, 807, 808, 809, 811, 812, 813, 814, 815)
TABLE1_V = (0.88, 3.36, 0.96, 0.48, 0.32, 0.24, 0.16, 0.24, 0.16, 1.28, 1.44, 1.60, 2.00, 2.40, 9.60, 8.96, 5.92, 3.68)
TABLE1_V += (2.56, 9.74, 9.85, 10.31, 9.91, 9.78, 9.53, 9.42, 9.30, 9.21, 9.17)


@dataclass(frozen=True)
class Config:
    # resonator (#25): f_r from the paper, Q and gain assumed
    f_r: float = 807.5  # Hz, white-noise result of the paper (the "true" resonance of the simulation)
    q: float = 35.0  # assumed (Table 1's half-power width ≈ 22 Hz)
    gain: float = 1.0  # V/A, assumed
    fs: float = 8192.0  # Hz, sampling rate of the record (assumed)
    record_s: float = 8.0  # s (paper: < 10 s)
    nperseg: int = 8192  # Welch segment (1 Hz resolution at fs = 8192)
    band_lo: float = 700.0  # Hz, fitted band
    band_hi: float = 950.0
    noise_ratio: float = 0.05  # output noise std / output std (assumed)
    n_runs: int = 64  # noise seeds
    fit_iters: int = 60
    step_lo: float = 750.0  # Hz, stepped-sine grid (1 Hz step, as in the paper)
    step_hi: float = 850.0
    # bench (#26): KD45 values from the paper
    kp: float = 10e-3  # V/g
    c_d: float = 1.2e-9  # F
    z_n: float = 5.5e6  # Ω
    r_y: float = 6e11  # Ω
    bench_amplitude: float = 1.0  # m/s², test amplitude (paper: ~1 m/s²)
    bench_freqs: tuple[float, ...] = (1.0, 2.0, 5.0, 10.0, 20.0, 24.0, 50.0, 100.0)  # Hz
    bench_dt: float = 1e-4  # s, RK4 step
    bench_settle_s: float = 0.1  # s before the amplitude is measured (≈ 15 τ)
    seed: int = 0


def bench_stage(cfg: Config) -> stages.Stage:
    p = pa.BenchParams(kp=cfg.kp, c_d=cfg.c_d, z_n=cfg.z_n, r_y=cfg.r_y)
    tau, fc = float(pa.time_constant(p)), float(pa.corner_frequency(p))
    mag = {f: float(jnp.abs(pa.bench_response(p, f)) / cfg.kp) for f in (1.0, 10.0, fc)}
    plant = pa.bench_sensor(p)
    phi = float(np.arccos(cfg.bench_amplitude / pa.G0))  # inclination giving the test amplitude
    freqs = jnp.asarray(cfg.bench_freqs)
    n_steps = int(round((cfg.bench_settle_s + 1.0) / cfg.bench_dt))  # 1 s window: whole periods (integer Hz)

    def amplitude(f: jax.Array) -> jax.Array:
        def rhs(t: jax.Array, x: jax.Array) -> jax.Array:
            return plant.f(x, pa.rotating_input(f, t, phi)[None], t)

        ts, xs = integrate(rhs, jnp.zeros(1), 0.0, cfg.bench_dt, n_steps, RK4)
        a = pa.rotating_input(f, ts, phi)
        v = jax.vmap(lambda x, u: plant.h(x, u[None])[0])(xs, a)
        keep = ts >= cfg.bench_settle_s - 1e-12
        basis = jnp.stack([jnp.sin(2 * jnp.pi * f * ts), jnp.cos(2 * jnp.pi * f * ts), jnp.ones_like(ts)], 1)
        w = keep.astype(ts.dtype)[:, None]
        coef = jnp.linalg.lstsq(basis * w, v * w[:, 0])[0]
        return jnp.hypot(coef[0], coef[1])

    amp_v = np.asarray(jax.jit(jax.vmap(amplitude))(freqs))
    a_g = cfg.bench_amplitude / pa.G0
    h = amp_v / a_g  # V per g
    om = 2 * np.pi * np.asarray(cfg.bench_freqs)
    # 1/|H|² = 1/K_p² + (1/(K_p τ)²)·(1/ω²): linear least squares
    design = np.stack([np.ones_like(om), 1.0 / om**2], 1)
    c0, c1 = np.asarray(jnp.linalg.lstsq(jnp.asarray(design), jnp.asarray(1.0 / h**2))[0])
    kp_fit = 1.0 / np.sqrt(c0)
    tau_fit = np.sqrt(c0 / c1)
    rows = [
        {
            "f_hz": float(f),
            "simulated_mv_per_g": 1e3 * float(hh),
            "model_mv_per_g": 1e3 * float(jnp.abs(pa.bench_response(p, f))),
            "amplitude_mv_at_1mps2": 1e3 * float(a),
        }
        for f, hh, a in zip(cfg.bench_freqs, h, amp_v)
    ]
    fgrid = np.geomspace(0.5, 500, 200)
    fig = figures.line_panels(
        [
            figures.panel(
                {
                    "model K_p·sτ/(1+sτ)": (fgrid, 1e3 * np.abs(np.asarray(pa.bench_response(p, fgrid)))),
                    "simulated bench": (np.asarray(cfg.bench_freqs), 1e3 * h, "o"),
                },
                "f, Hz",
                "|V/a|, mV/g",
                log_y=True,
                hline=1e3 * cfg.kp / np.sqrt(2),
                title=f"KD45: τ = {1e3 * tau:.2f} ms, f_c = {fc:.1f} Hz",
            )
        ]
    )
    fig.axes[0].set_xscale("log")
    return stages.Stage(
        metrics={
            "bench_tau_ms": 1e3 * tau,
            "bench_fc_hz": fc,
            "bench_mag_1hz": mag[1.0],
            "bench_mag_10hz": mag[10.0],
            "bench_mag_fc": mag[fc],
            "bench_mv_per_g_1hz": 1e3 * cfg.kp * mag[1.0],
            "bench_fit_tau_ms": 1e3 * float(tau_fit),
            "bench_fit_kp_mv_per_g": 1e3 * float(kp_fit),
            "bench_phi_deg": float(np.degrees(phi)),
        },
        tables={"bench": rows},
        figures={"bench_response": fig},
        notes=[
            f"bench: τ = C_d·(Z_n∥R_y) = {1e3 * tau:.3f} ms, f_c = {fc:.2f} Hz — the KD45's −3 dB limit is "
            "above the bench's 10 Hz goal; the voltage-mode model is the spec's reconstruction (cable "
            "capacitance ignored)",
            f"bench simulated at φ = {np.degrees(phi):.1f}° (a = {cfg.bench_amplitude:g} m/s²); K_p and τ "
            f"recovered by linear LS: {1e3 * kp_fit:.4f} mV/g, {1e3 * tau_fit:.4f} ms",
        ],
    )


def table_stage(cfg: Config) -> tuple[stages.Stage, Any]:
    f = np.asarray(TABLE1_HZ, float)
    v = np.asarray(TABLE1_V, float)
    k = int(np.argmax(v))
    peak_f, peak_v = f[k], v[k]
    # half-power crossings by linear interpolation on the sorted table
    order = np.argsort(f)
    fs_, vs_ = f[order], v[order]
    half = peak_v / np.sqrt(2)
    left = fs_[fs_ < peak_f]
    lv = vs_[fs_ < peak_f]
    i = np.nonzero(lv < half)[0][-1]
    f_lo = left[i] + (half - lv[i]) * (left[i + 1] - left[i]) / (lv[i + 1] - lv[i])
    right, rv = fs_[fs_ > peak_f], vs_[fs_ > peak_f]
    j = np.nonzero(rv < half)[0][0]
    f_hi = right[j - 1] + (rv[j - 1] - half) * (right[j] - right[j - 1]) / (rv[j - 1] - rv[j])
    # the spec's check: a Lorentzian through the 807 Hz peak and the 800 Hz point, evaluated at 820 Hz
    q_l = np.sqrt((peak_v / 3.36) ** 2 - 1) / (2 * abs(800.0 - peak_f) / peak_f)
    lor_820 = peak_v / np.sqrt(1 + (2 * q_l * (820.0 - peak_f) / peak_f) ** 2)
    q0 = peak_f / (f_hi - f_lo)
    theta0 = jnp.array([peak_v / q0, peak_f, np.log(q0)])
    fit = fit_resonator(jnp.asarray(f), jnp.asarray(v), theta0, mode="magnitude", n_iter=cfg.fit_iters * 3)
    model = np.abs(np.asarray(resonator_response(fit.theta, f)))
    rms_log = float(np.sqrt(np.mean(np.log(model / v) ** 2)))
    rows = [
        {"f_hz": float(a), "paper_v": float(b), "linear_fit_v": float(c), "ratio": float(c / b)}
        for a, b, c in sorted(zip(f, v, model))
    ]
    metrics = {
        "table_peak_hz": float(peak_f),
        "table_half_power_lo_hz": float(f_lo),
        "table_half_power_hi_hz": float(f_hi),
        "table_q_half_power": float(q0),
        "table_lorentz_q": float(q_l),
        "table_lorentz_820_v": float(lor_820),
        "table_fit_f_r_hz": float(fit.f_r),
        "table_fit_q": float(fit.q),
        "table_fit_rms_log": rms_log,
        "table_fit_820_v": float(model[list(f).index(820.0)]),
    }
    note = (
        f"Table 1: peak {peak_v:g} V at {peak_f:g} Hz, half-power band {f_lo:.1f}–{f_hi:.1f} Hz (Q ≈ {q0:.0f}); "
        f"the peak is asymmetric (3.36 V at 800 Hz, 8.96 V at 820 Hz): a Lorentzian through 800/807 Hz "
        f"(Q = {q_l:.0f}) predicts {lor_820:.2f} V at 820 Hz; the best linear resonator (all points, log LS) "
        f"peaks at {float(fit.f_r):.1f} Hz, Q = {float(fit.q):.0f}, rms log error {rms_log:.2f} — the table "
        "is not a linear second-order response (a softening or sweep artefact, spec §2.9)"
    )
    return stages.Stage(metrics=metrics, tables={"table1": rows}, notes=[note]), (f, v, fit)


def white_noise_stage(cfg: Config) -> tuple[stages.Stage, Any]:
    p = pa.ResonatorParams(f_r=cfg.f_r, q=cfg.q, gain=cfg.gain)
    a, b, _ = pa.resonator_state_space(p)
    ad, g0, _ = hold_matrices(a, b, 1.0 / cfg.fs)
    n = int(round(cfg.fs * cfg.record_s))
    fbins = np.fft.rfftfreq(cfg.nperseg, 1.0 / cfg.fs)
    idx = np.nonzero((fbins >= cfg.band_lo) & (fbins <= cfg.band_hi))[0]

    def one(key: jax.Array) -> dict[str, jax.Array]:
        ku, kn = jax.random.split(key)
        u = jax.random.normal(ku, (n,))  # coil current samples (A), held between samples

        def step(x: jax.Array, uk: jax.Array) -> tuple[jax.Array, jax.Array]:
            return ad @ x + g0[:, 0] * uk, x[0]

        _, y = jax.lax.scan(step, jnp.zeros(2), u)
        y = y + cfg.noise_ratio * jnp.std(y) * jax.random.normal(kn, (n,))
        est = frf_h1(u, y, cfg.fs, cfg.nperseg)
        f, h = est.f[idx], est.h[idx]
        k = jnp.argmax(jnp.abs(h))
        q0 = 20.0
        theta0 = jnp.stack([jnp.abs(h[k]) / q0, f[k], jnp.log(q0)])
        fit = fit_resonator(f, h, theta0, hold=1.0 / cfg.fs, n_iter=cfg.fit_iters)
        kp = jnp.argmax(est.p_yy[idx])  # peak picking on the output spectrum
        return {"f_r_fit": fit.f_r, "q_fit": fit.q, "f_r_peak": f[kp], "h_abs": jnp.abs(h), "coh": est.coherence[idx]}

    keys = jax.random.split(jax.random.PRNGKey(cfg.seed), cfg.n_runs)
    out = {k: np.asarray(v) for k, v in jax.jit(jax.vmap(one))(keys).items()}
    fr, pk = out["f_r_fit"], out["f_r_peak"]
    err = np.abs(fr - cfg.f_r)
    half = 1.96 * fr.std(ddof=1) / np.sqrt(len(fr)) if len(fr) > 1 else float("nan")
    grid = np.arange(cfg.step_lo, cfg.step_hi + 0.5, 1.0)
    stepped = float(grid[int(np.argmax(np.abs(np.asarray(pa.resonator_response(p, grid)))))])
    metrics = {
        "f_n_hz": float(pa.natural_frequency(p)),
        "wn_f_r_mean_hz": float(fr.mean()),
        "wn_f_r_std_hz": float(fr.std(ddof=1)) if len(fr) > 1 else 0.0,
        "wn_f_r_ci95_lo_hz": float(fr.mean() - half),
        "wn_f_r_ci95_hi_hz": float(fr.mean() + half),
        "wn_f_r_abs_err_max_hz": float(err.max()),
        "wn_f_r_abs_err_p95_hz": float(np.quantile(err, 0.95)),
        "wn_q_mean": float(out["q_fit"].mean()),
        "wn_peak_pick_abs_err_max_hz": float(np.abs(pk - cfg.f_r).max()),
        "wn_peak_pick_std_hz": float(pk.std(ddof=1)) if len(pk) > 1 else 0.0,
        "wn_coherence_min": float(out["coh"].min()),
        "record_s": float(cfg.record_s),
        "stepped_sine_peak_hz": stepped,
    }
    rows = [
        {"seed_index": i, "f_r_fit_hz": float(a), "q_fit": float(b), "f_r_peak_pick_hz": float(c)}
        for i, (a, b, c) in enumerate(zip(fr, out["q_fit"], pk))
    ]
    note = (
        f"white noise: {cfg.n_runs} records of {cfg.record_s:g} s at {cfg.fs:g} Hz, output noise "
        f"{100 * cfg.noise_ratio:g} % of its std; H1 (Welch, {cfg.nperseg} samples) + resonator fit in "
        f"{cfg.band_lo:g}–{cfg.band_hi:g} Hz: f_r = {fr.mean():.4f} Hz (95 % CI of the mean "
        f"{fr.mean() - half:.4f}–{fr.mean() + half:.4f}), max error {err.max():.4f} Hz; peak picking on the "
        f"output spectrum (1 bin = {cfg.fs / cfg.nperseg:g} Hz) errs up to {np.abs(pk - cfg.f_r).max():g} Hz. "
        f"The true f_r is the paper's 807.5 Hz by construction: what is tested is the ±0.1 Hz accuracy in "
        f"< 10 s. Stepped sine (1 Hz grid, steady state) peaks at {stepped:g} Hz (paper: 807)"
    )
    return stages.Stage(metrics=metrics, tables={"white_noise_runs": rows}, notes=[note]), (
        fbins[idx],
        out["h_abs"][0],
        p,
    )


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    bench = bench_stage(cfg)
    table, (tf, tv, tfit) = table_stage(cfg)
    noise, (f, h_abs, p) = white_noise_stage(cfg)
    fine = np.linspace(cfg.band_lo, cfg.band_hi, 500)
    tmax = float(np.max(tv))
    fig = figures.line_panels(
        [
            figures.panel(
                {
                    "H1 estimate, seed 0": (f, h_abs),
                    "resonator (assumed Q)": (fine, np.abs(np.asarray(pa.resonator_response(p, fine)))),
                },
                "f, Hz",
                "|y/u|, V/A",
                log_y=True,
                title=f"white noise, {cfg.record_s:g} s",
            ),
            figures.panel(
                {
                    "paper Table 1": (tf, tv, "o"),
                    "linear resonator fit": (fine, np.abs(np.asarray(resonator_response(tfit.theta, fine)))),
                },
                "f, Hz",
                "amplitude, V",
                log_y=True,
                hline=tmax / np.sqrt(2),
                title="Table 1 vs a linear resonator",
            ),
        ]
    )
    return stages.merge(bench, table, noise, stages.Stage(figures={"resonance": fig}))


CLAIMS, ASSUMPTIONS = paper_facts("piezo_accelerometer")

STUDY = Study(
    name="piezo_accelerometer",
    description="Seed 004 #25/#26: piezo-accelerometer resonance by white noise (H1 + resonator fit, "
    "Monte Carlo over noise) and the KD45 calibration bench's high-pass corner",
    config=Config,
    presets={
        "quick": dict(n_runs=16),
        "tiny": dict(n_runs=2, record_s=2.0, nperseg=4096, fit_iters=30, bench_freqs=(1.0, 10.0, 24.0, 100.0)),
    },
    claims=CLAIMS,
    assumptions=ASSUMPTIONS,
    run=run,
)
