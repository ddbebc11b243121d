"""Study ``gravity_anomaly``: gravity-anomaly estimation at sea with GNSS-based rejection of manoeuvre
epochs (Nosov & Motorin, seed 004 part 4 §B1).

Models (:mod:`jaxsim.plants.marine_gravimetry`): the Jordan third-order anomaly model and the
third-order heave model, the 6-state gravimeter model, the GNSS constant-acceleration model.  The study:

1. verifies the model identities numerically: the Jordan filter's stationary variance σ² (continuous
   Lyapunov solver of :mod:`jaxsim.control`), the spectrum ↔ covariance Fourier pair (Gauss–Legendre
   quadrature after ``ω = β tan θ``), the state-space covariance ``H e^{Aτ} P Hᵀ`` against ``K(τ)``, the
   heave filter's unit-variance gain ``C = σ_v √(2a3(a1a2 − a3)/a1)``, and the χ²(4) 0.99 quantile;
2. simulates survey lines (anomaly shared by two passes, independent heave, noise and manoeuvres),
   flags GNSS epochs whose NIS exceeds the χ²(4) quantile, and runs the gravimeter Kalman filter + RTS
   smoother without and with the rejection (and with the true manoeuvre mask as an oracle);
3. Monte-Carlo detection and false-alarm rates with Wilson intervals, RMS and crossover errors;
4. the hyperparameters (β, σ) by gradient maximum likelihood through the filter's log-likelihood.

The paper's crossover numbers (3.38 → 0.78 mGal on one line, 1.48 → 0.81 mGal on 22 lines) are on
real data that are not available; the synthetic analogue is reported beside them.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np
import optax

from experiments import figures, stages
from experiments.runner import Study, StudyResult, paper_facts
from jaxsim.control.lyapunov import solve_continuous_lyapunov, solve_discrete_lyapunov
from jaxsim.core.discretize import van_loan
from jaxsim.core.matrix_exp import expm
from jaxsim.estimation.gating import chi2_threshold
from jaxsim.estimation.lgssm import kalman_filter, lgssm
from jaxsim.estimation.smoothers import rts_smoother
from jaxsim.montecarlo.events import wilson_interval
from jaxsim.plants import marine_gravimetry as mg

CLAIMS, ASSUMPTIONS = paper_facts("gravity_anomaly")


@dataclass(frozen=True)
class Config:
    dt: float = 1.0  # s, gravimeter and GNSS sampling [assumed]
    speed: float = 5.0  # m/s [assumed, spec §B1: ~10 kn]
    sigma_g: float = 20.0  # mGal, anomaly rms [assumed]
    sigma_gradient: float = 2.0e-3  # mGal/m (2 mGal/km), rms horizontal gradient [assumed]
    sigma_v: float = 1.0  # m, heave rms [assumed]
    omega0: float = 0.6  # rad/s, dominant heave frequency [assumed]
    alpha_w: float = 0.06  # 1/s, wave irregularity (0.1·ω0) [assumed]
    kappa: float = 1.0  # [assumed]
    sigma_gr: float = 1.0  # mGal, gravimeter white noise [assumed]
    gnss_sigma_pos: float = 2.0  # m [assumed]
    gnss_sigma_vel: float = 0.05  # m/s [assumed]
    gnss_q_jerk: float = 1.0e-8  # m²/s⁵, jerk intensity of the CA model (and of the true motion) [assumed]
    chi2_prob: float = 0.99  # spec §B1: threshold 13.28 = χ²(4) 0.99 quantile
    guard: int = 10  # s: clusters of flags are widened by this many epochs on each side
    cluster: int = 5  # s: two flags within ±cluster epochs form a cluster (a manoeuvre, not a false alarm)
    line_steps: int = 3600  # samples per survey line (1 h, 18 km)
    n_lines: int = 22  # the paper's survey size
    manoeuvres_per_line: int = 2
    manoeuvre_duration: int = 120  # s, an S-turn (turn rate +ω_t, then −ω_t)
    turn_rate: float = 0.02  # rad/s → lateral acceleration V·ω_t = 0.1 m/s²
    manoeuvre_bias: float = 300.0  # mGal per m/s² of horizontal acceleration [assumed]
    quadrature_nodes: int = 4000
    ml_lines: int = 8
    ml_steps: int = 60
    ml_learning_rate: float = 0.05  # Adam on (log β, log σ)
    ml_start: tuple[float, float] = (2.0, 0.5)  # start at (2β, σ/2)
    seed: int = 0


PRESETS = {
    "quick": dict(line_steps=1800, n_lines=8, ml_lines=4, ml_steps=40),
    "tiny": dict(
        line_steps=1200,
        n_lines=2,
        manoeuvres_per_line=1,
        ml_lines=1,
        ml_steps=3,
    ),
}


def beta_of(cfg: Config) -> float:
    return float(mg.jordan_beta(cfg.speed, cfg.sigma_g, cfg.sigma_gradient))


# --- the gravimeter model (normalised states, integrating sensor) ----------------------------------


def gravimeter_ssm(cfg: Config, beta: Any, sigma: Any):
    """``(F, Q, H, Hg, P0, scale)`` of the 7-state discrete gravimeter model in normalised states.

    States 1–6: the anomaly and heave shaping filters, each scaled to unit stationary variance
    (``scale = 1/√diag P∞`` from the continuous Lyapunov equation); state 7: the heave velocity one
    sample earlier.  The sample is the mean acceleration over the interval (an integrating sensor)::

        y_k = g_k + 10⁵ (x5_k − x5_{k−1})/dt + v_gr

    ``H`` maps the state to ``y`` (mGal), ``Hg`` to the anomaly ``g``."""
    A, G, H6 = mg.gravimeter_model(beta, sigma, cfg.sigma_v, cfg.omega0, cfg.alpha_w, cfg.kappa)
    P = solve_continuous_lyapunov(A, -G @ G.T)
    d = 1.0 / jnp.sqrt(jnp.diag(P))
    Az = d[:, None] * A / d[None, :]
    F6, Q6 = van_loan(Az, jnp.eye(2), cfg.dt, d[:, None] * G)
    F = jnp.zeros((7, 7)).at[:6, :6].set(F6).at[6, 4].set(1.0)
    Q = jnp.zeros((7, 7)).at[:6, :6].set(Q6)
    Hg = jnp.concatenate([mg.anomaly_output(beta) / d[None, :], jnp.zeros((1, 1))], axis=1)
    k = mg.MGAL_PER_MS2 / (cfg.dt * d[4])
    H = Hg.at[0, 4].set(k).at[0, 6].set(-k)
    P0 = solve_discrete_lyapunov(F, Q)
    return F, Q, H, Hg, 0.5 * (P0 + P0.T), d


def gnss_model(cfg: Config):
    F, Qu, H = mg.gnss_ca_model(cfg.dt)
    R = np.diag([cfg.gnss_sigma_pos**2] * 2 + [cfg.gnss_sigma_vel**2] * 2)
    return F, cfg.gnss_q_jerk * Qu, H, R


# --- synthetic survey -----------------------------------------------------------------------------


def manoeuvre_profile(cfg: Config, starts: jax.Array, n: int) -> tuple[jax.Array, jax.Array]:
    """Turn rate ``(n,)`` (S-turns of ``manoeuvre_duration`` from each start) and the manoeuvre mask."""
    t = jnp.arange(n)
    rel = t[None, :] - starts[:, None]
    half = cfg.manoeuvre_duration // 2
    rate = jnp.where((rel >= 0) & (rel < half), cfg.turn_rate, 0.0) - jnp.where(
        (rel >= half) & (rel < 2 * half), cfg.turn_rate, 0.0
    )
    return rate.sum(0), ((rel >= 0) & (rel < 2 * half)).any(0)


def gnss_pass(cfg: Config, turn_rate: jax.Array, key: jax.Array) -> jax.Array:
    """NIS ``(n,)`` of the GNSS CA-model Kalman filter on a pass with the given turn-rate profile."""
    F, Q, H, R = gnss_model(cfg)
    n = turn_rate.shape[0]
    heading = jnp.cumsum(turn_rate) * cfg.dt
    vel = cfg.speed * jnp.stack([jnp.cos(heading), jnp.sin(heading)], axis=1)
    pos = jnp.cumsum(vel, axis=0) * cfg.dt
    k1, k2 = jax.random.split(key)
    chol_q = jnp.linalg.cholesky(jnp.asarray(Q) + 1e-30 * jnp.eye(6))
    w = jax.random.normal(k1, (n, 6)) @ chol_q.T

    def drift(x, wk):
        x = jnp.asarray(F) @ x + wk
        return x, x

    _, dx = jax.lax.scan(drift, jnp.zeros(6), w)  # the CA model's own random motion
    truth = jnp.stack([pos[:, 0] + dx[:, 0], pos[:, 1] + dx[:, 3], vel[:, 0] + dx[:, 1], vel[:, 1] + dx[:, 4]], 1)
    z = truth + jax.random.normal(k2, (n, 4)) * jnp.sqrt(jnp.diag(jnp.asarray(R)))
    m0 = jnp.array([0.0, cfg.speed, 0.0, 0.0, 0.0, 0.0])
    P0 = jnp.diag(jnp.array([4.0, 0.01, 1e-4, 4.0, 0.01, 1e-4]))
    model = lgssm(F, Q, H, R, m0, P0)
    return kalman_filter(model, z).nis


def dilate(flags: jax.Array, guard: int) -> jax.Array:
    """``flags`` widened by ``guard`` epochs on each side."""
    kernel = jnp.ones(2 * guard + 1)
    return jnp.convolve(flags.astype(float), kernel, mode="same") > 0.5


def rejection_mask(flags: jax.Array, guard: int, cluster: int) -> jax.Array:
    """Epochs to reject: ``guard`` epochs either side of every flag that belongs to a *cluster* (≥ 2 flags
    within ``±cluster`` epochs).  Isolated flags (false alarms: 1 % of normal epochs) are kept: every
    skipped gravimeter epoch breaks the integrated heave-velocity chain (see the notes)."""
    count = jnp.convolve(flags.astype(float), jnp.ones(2 * cluster + 1), mode="same")
    return dilate(flags & (count > 1.5), guard)


@functools.partial(jax.jit, static_argnums=0)
def survey_line(cfg: Config, key: jax.Array) -> dict[str, jax.Array]:
    """Two passes over one anomaly profile: per pass the flags, the masks and the smoothed anomalies."""
    beta = beta_of(cfg)
    F, Q, H, Hg, P0, _ = gravimeter_ssm(cfg, beta, cfg.sigma_g)
    n = cfg.line_steps
    thr = chi2_threshold(4, cfg.chi2_prob)
    k_anom, k_a, k_b = jax.random.split(key, 3)
    chol = jnp.linalg.cholesky(P0[:6, :6] + 1e-12 * jnp.eye(6))
    chol_q = jnp.linalg.cholesky(Q[:6, :6] + 1e-14 * jnp.eye(6))

    def states(k):
        k0, k1 = jax.random.split(k)
        x0 = chol @ jax.random.normal(k0, (6,))
        w = jax.random.normal(k1, (n + 1, 6)) @ chol_q.T

        def step(x, wk):
            x = F[:6, :6] @ x + wk
            return x, x

        _, xs = jax.lax.scan(step, x0, w)
        return xs  # (n + 1, 6)

    anomaly = states(k_anom)[:, :3]
    model = lgssm(F, Q, H, jnp.eye(1) * cfg.sigma_gr**2, jnp.zeros(7), P0)

    def one_pass(k):
        kh, kv, km, kg = jax.random.split(k, 4)
        heave = states(kh)[:, 3:]
        x6 = jnp.concatenate([anomaly, heave], axis=1)
        x = jnp.concatenate([x6[1:], x6[:-1, 4:5]], axis=1)  # (n, 7): state 7 = previous heave velocity
        g = x @ Hg[0]
        slots = n // max(cfg.manoeuvres_per_line, 1)
        starts = jnp.arange(cfg.manoeuvres_per_line) * slots + jax.random.randint(
            km, (cfg.manoeuvres_per_line,), 0, max(slots - cfg.manoeuvre_duration, 1)
        )
        rate, man = manoeuvre_profile(cfg, starts, n)
        bias = cfg.manoeuvre_bias * cfg.speed * jnp.abs(rate)  # |a| = V |ω|
        y = x @ H[0] + bias + cfg.sigma_gr * jax.random.normal(kv, (n,))
        # the pass itself and a straight pass (for the false-alarm rate) through one traced GNSS filter
        nis_both = jax.vmap(lambda r, k: gnss_pass(cfg, r, k))(jnp.stack([rate, jnp.zeros(n)]), jax.random.split(kg))
        nis = nis_both[0]
        flags = nis > thr
        reject = rejection_mask(flags, cfg.guard, cfg.cluster)
        out = {"g": g, "y": y, "manoeuvre": man, "flags": flags, "reject": reject, "nis": nis}
        out["clean_flags"] = nis_both[1] > thr
        masks = jnp.stack([jnp.ones(n, bool), ~reject, ~man])  # ungated, gated, oracle

        def smooth(mask):
            sm = rts_smoother(model, y[:, None], mask=mask)
            return sm.means @ Hg[0], jnp.sqrt(jnp.einsum("i,tij,j->t", Hg[0], sm.covs, Hg[0]))

        means, sds = jax.vmap(smooth)(masks)
        for i, name in enumerate(("ungated", "gated", "oracle")):
            out[f"g_{name}"], out[f"sd_{name}"] = means[i], sds[i]
        return out

    both = jax.vmap(one_pass)(jnp.stack([k_a, k_b]))
    return {f"{k}_{p}": v[i] for k, v in both.items() for i, p in enumerate("ab")}


# --- identities -----------------------------------------------------------------------------------


def covariance_by_quadrature(cfg: Config, tau: jax.Array, beta: float, sigma: float) -> jax.Array:
    """``K(τ) = (1/π)∫₀^∞ S(ω) cos ωτ dω`` by composite 8-point Gauss–Legendre (``quadrature_nodes``
    nodes in all) on ``ω = β tan θ``, ``θ ∈ [0, π/2)``."""
    x, w = np.polynomial.legendre.leggauss(8)
    panels = max(cfg.quadrature_nodes // 8, 1)
    h = 0.5 * np.pi / panels
    left = np.arange(panels)[:, None] * h
    theta = jnp.asarray((left + 0.5 * h * (x[None, :] + 1.0)).ravel())
    wt = jnp.asarray(np.broadcast_to(0.5 * h * w, (panels, 8)).ravel())
    om = beta * jnp.tan(theta)
    jac = beta / jnp.cos(theta) ** 2
    integrand = mg.jordan_spectrum(om, beta, sigma) * jac
    return jnp.sum(wt * integrand * jnp.cos(om[None, :] * tau[:, None]), axis=1) / jnp.pi


def identities(cfg: Config) -> tuple[dict[str, float], list[dict[str, Any]]]:
    beta, sigma = beta_of(cfg), cfg.sigma_g
    jf = mg.jordan_filter(beta, sigma)
    P = solve_continuous_lyapunov(jf.A, -jf.G @ jf.G.T)
    var_g = float((jf.H @ P @ jf.H.T)[0, 0])
    taus = jnp.asarray(np.array([0.0, 0.25, 0.5, 1.0, 2.0, 3.0, 5.0, 8.0]) / beta)
    k_closed = mg.jordan_covariance(taus, beta, sigma)
    k_quad = covariance_by_quadrature(cfg, taus, beta, sigma)
    k_ss = jax.jit(jax.vmap(lambda t: (jf.H @ expm(jf.A * t) @ P @ jf.H.T)[0, 0]))(taus)
    oms = jnp.asarray(np.array([0.0, 0.3, 1.0, 3.0, 10.0]) * beta)
    hjw = jax.jit(jax.vmap(lambda w: (jf.H @ jnp.linalg.solve(1j * w * jnp.eye(3) - jf.A, jf.G))[0, 0]))(oms)
    s_filter = jnp.abs(hjw) ** 2
    s_closed = mg.jordan_spectrum(oms, beta, sigma)
    hv = mg.heave_filter(cfg.sigma_v, cfg.omega0, cfg.alpha_w, cfg.kappa)
    Ph = solve_continuous_lyapunov(hv.A, -hv.G @ hv.G.T)
    rows = [
        {
            "tau_s": float(t),
            "beta_tau": float(t * beta),
            "K_closed_mgal2": float(a),
            "K_quadrature_mgal2": float(b),
            "K_state_space_mgal2": float(c),
        }
        for t, a, b, c in zip(taus, k_closed, k_quad, k_ss)
    ]
    scale = sigma**2
    metrics = {
        "beta_per_s": beta,
        "jordan_q2_over_10beta3sigma2": float(jf.G[2, 0] ** 2 / (10 * beta**3 * sigma**2)),
        "jordan_variance_ratio": var_g / sigma**2,
        "fourier_pair_max_abs_err_rel": float(jnp.max(jnp.abs(k_quad - k_closed)) / scale),
        "state_space_cov_max_abs_err_rel": float(jnp.max(jnp.abs(k_ss - k_closed)) / scale),
        "shaping_spectrum_max_rel_err": float(jnp.max(jnp.abs(s_filter / s_closed - 1.0))),
        "heave_variance_ratio": float(Ph[0, 0] / cfg.sigma_v**2),
        "heave_accel_rms_mgal": float(jnp.sqrt(Ph[2, 2]) * mg.MGAL_PER_MS2),
        "chi2_threshold": chi2_threshold(4, cfg.chi2_prob),
    }
    return metrics, rows


# --- maximum likelihood ---------------------------------------------------------------------------


def negative_loglik(cfg: Config, log_theta: jax.Array, ys: jax.Array, masks: jax.Array) -> jax.Array:
    """``−Σ log p(y)`` over lines ``ys (L, n)`` (rejected epochs masked) at ``(β, σ) = exp(log_theta)``."""
    beta, sigma = jnp.exp(log_theta[0]), jnp.exp(log_theta[1])
    F, Q, H, _, P0, _ = gravimeter_ssm(cfg, beta, sigma)
    model = lgssm(F, Q, H, jnp.eye(1) * cfg.sigma_gr**2, jnp.zeros(7), P0)
    ll = jax.vmap(lambda y, m: kalman_filter(model, y[:, None], mask=m).log_likelihood)(ys, masks)
    return -jnp.sum(ll)


# --- the study ------------------------------------------------------------------------------------


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


def _mean_ci(x: np.ndarray) -> tuple[float, float, float]:
    m = float(np.mean(x))
    h = 1.96 * float(np.std(x, ddof=1)) / math.sqrt(len(x)) if len(x) > 1 else float("nan")
    return m, m - h, m + h


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    metrics, id_rows = identities(cfg)

    # survey lines
    keys = jax.random.split(jax.random.PRNGKey(cfg.seed), cfg.n_lines)
    lines = [
        {k: np.asarray(v) for k, v in survey_line(cfg, k).items()}
        for k in progress(list(keys), desc="survey lines", unit="line")
    ]
    line_rows = []
    for i, ln in enumerate(lines):
        row: dict[str, Any] = {"line": i}
        for p in ("a", "b"):
            man, flags, rej = ln[f"manoeuvre_{p}"], ln[f"flags_{p}"], ln[f"reject_{p}"]
            row[f"detected_epochs_{p}"] = int(np.sum(flags & man))
            row[f"manoeuvre_epochs_{p}"] = int(np.sum(man))
            row[f"rejected_epochs_{p}"] = int(np.sum(rej))
            row[f"rejected_outside_{p}"] = int(np.sum(rej & ~man))
            for v in ("ungated", "gated", "oracle"):
                row[f"rms_{v}_{p}"] = _rms(ln[f"g_{v}_{p}"] - ln[f"g_{p}"])
        for v in ("ungated", "gated", "oracle"):
            row[f"crossover_rms_{v}"] = _rms(ln[f"g_{v}_a"] - ln[f"g_{v}_b"]) / math.sqrt(2.0)
        line_rows.append(row)

    def pooled(key: str) -> float:
        return float(np.sqrt(np.mean([r[key] ** 2 for r in line_rows])))

    for v in ("ungated", "gated", "oracle"):
        metrics[f"crossover_rms_{v}"] = pooled(f"crossover_rms_{v}")
        metrics[f"rms_error_{v}"] = float(np.sqrt(np.mean([r[f"rms_{v}_{p}"] ** 2 for r in line_rows for p in "ab"])))
        metrics[f"crossover_rms_{v}_line0"] = line_rows[0][f"crossover_rms_{v}"]
    metrics["crossover_improvement"] = metrics["crossover_rms_ungated"] / metrics["crossover_rms_gated"]

    # detection: per epoch inside manoeuvres, and per manoeuvre event
    det = sum(r[f"detected_epochs_{p}"] for r in line_rows for p in "ab")
    man_epochs = sum(r[f"manoeuvre_epochs_{p}"] for r in line_rows for p in "ab")
    lo, hi = wilson_interval(det, man_epochs)
    metrics |= {
        "detection_rate_epochs": det / man_epochs,
        "detection_ci_low": float(lo),
        "detection_ci_high": float(hi),
    }
    events = hits = 0
    for ln in lines:
        for p in "ab":
            man, rej = ln[f"manoeuvre_{p}"], ln[f"reject_{p}"]
            edges = np.flatnonzero(np.diff(np.concatenate([[0], man.astype(int), [0]])))
            for s, e in zip(edges[::2], edges[1::2]):
                events += 1
                hits += int(np.all(rej[s:e]))
    lo, hi = wilson_interval(hits, events)
    metrics |= {
        "manoeuvres_fully_rejected": hits / events,
        "manoeuvres_fully_rejected_ci_low": float(lo),
        "manoeuvres_fully_rejected_ci_high": float(hi),
    }

    # false alarms on straight passes (one per survey pass, independent GNSS noise and motion)
    flags = np.stack([ln[f"clean_flags_{p}"] for ln in lines for p in "ab"])[:, 30:]  # after the start-up
    fa, nfa = int(flags.sum()), flags.size
    lo, hi = wilson_interval(fa, nfa)
    metrics |= {"false_alarm_rate": fa / nfa, "false_alarm_ci_low": float(lo), "false_alarm_ci_high": float(hi)}
    per_line = flags.mean(axis=1)
    metrics["false_alarm_line_spread"] = float(np.std(per_line, ddof=1)) if len(per_line) > 1 else math.nan

    # consistency of the gated smoother (its σ across the gaps)
    z = np.concatenate([(ln[f"g_gated_{p}"] - ln[f"g_{p}"]) / ln[f"sd_gated_{p}"] for ln in lines for p in "ab"])
    gap = np.concatenate([ln[f"reject_{p}"] for ln in lines for p in "ab"])
    metrics["gated_normalised_error_ms"] = float(np.mean(z**2))
    sd = np.concatenate([ln[f"sd_gated_{p}"] for ln in lines for p in "ab"])
    metrics["gated_sd_in_gaps_over_elsewhere"] = float(np.mean(sd[gap]) / np.mean(sd[~gap])) if gap.any() else math.nan

    # maximum likelihood of (β, σ) on the first ml_lines lines (pass a, rejected epochs masked)
    n_ml = min(cfg.ml_lines, cfg.n_lines)
    beta = beta_of(cfg)
    ml_rows, ml_metrics = _max_likelihood(cfg, lines[:n_ml], progress)
    metrics |= ml_metrics

    notes = [
        f"β = V σ_Γ/(√2 σ_g) = {beta:.3e} 1/s (ρ = {cfg.speed / beta / 1e3:.1f} km); q² = 10β³σ² and "
        "the Lyapunov variance of g equal σ² (identities table)",
        f"heave acceleration rms {metrics['heave_accel_rms_mgal']:.0f} mGal: point samples of it alias the heave's "
        "1/ω² tail into the anomaly band, so the gravimeter is modelled as an integrating sensor (mean acceleration "
        "over the sample: a 7th state, the previous heave velocity); every skipped epoch breaks that velocity chain, "
        "so isolated χ² flags are not rejected, only clusters (≥ 2 flags within ±cluster epochs, widened by ±guard)",
        f"χ²(4) 0.99 quantile = {metrics['chi2_threshold']:.4f} (paper 13.28)",
        "the paper's crossover errors (3.38 → 0.78 mGal on one line, 1.48 → 0.81 mGal on 22 lines) are on real data "
        "that are not available: not reproducible; the synthetic analogue (two passes per line, crossover RMS = "
        "RMS(ĝ_a − ĝ_b)/√2) depends on the assumed manoeuvre bias",
        f"synthetic crossover RMS: ungated {metrics['crossover_rms_ungated']:.2f} → gated "
        f"{metrics['crossover_rms_gated']:.2f} mGal (oracle mask {metrics['crossover_rms_oracle']:.2f})",
    ]
    ln = lines[0]
    t = np.arange(cfg.line_steps) * cfg.dt
    fig = figures.line_panels(
        [
            figures.panel(
                {
                    "true g": (t, ln["g_a"], "k-"),
                    "smoother, ungated": (t, ln["g_ungated_a"], "r-"),
                    "smoother, gated": (t, ln["g_gated_a"], "b-"),
                },
                "t, s",
                "gravity anomaly, mGal",
                title="line 0, pass a",
            ),
            figures.panel(
                {"GNSS NIS": (t, ln["nis_a"]), "rejected (×20)": (t, 20.0 * ln["reject_a"], "r-")},
                "t, s",
                "NIS",
                hline=metrics["chi2_threshold"],
                log_y=True,
                title="χ²(4) rejection",
            ),
        ]
    )
    own = stages.Stage(
        tables={"identities": id_rows, "survey_lines": line_rows, "max_likelihood": ml_rows},
        figures={"survey_line": fig},
    )
    return stages.merge(own, metrics=metrics, notes=notes)


def _max_likelihood(cfg: Config, lines: list[dict[str, np.ndarray]], progress: Callable[..., Any]):
    beta = beta_of(cfg)
    ys = jnp.stack([jnp.asarray(ln["y_a"]) for ln in lines])
    masks = jnp.stack([~jnp.asarray(ln["reject_a"]) for ln in lines])
    vg = jax.jit(jax.value_and_grad(lambda th: negative_loglik(cfg, th, ys, masks)))
    theta = jnp.log(jnp.array([beta * cfg.ml_start[0], cfg.sigma_g * cfg.ml_start[1]]))
    opt = optax.adam(cfg.ml_learning_rate)
    state = opt.init(theta)
    rows = []
    for step in progress(range(cfg.ml_steps + 1), desc="max likelihood", unit="step"):
        val, g = vg(theta)
        rows.append(
            {
                "step": step,
                "neg_loglik": float(val),
                "beta": float(jnp.exp(theta[0])),
                "sigma_g": float(jnp.exp(theta[1])),
            }
        )
        if step == cfg.ml_steps:
            break
        upd, state = opt.update(g, state)
        theta = optax.apply_updates(theta, upd)
    true_nll = float(vg(jnp.log(jnp.array([beta, cfg.sigma_g])))[0])
    last = rows[-1]
    return rows, {
        "ml_beta_ratio": last["beta"] / beta,
        "ml_sigma_ratio": last["sigma_g"] / cfg.sigma_g,
        "ml_neg_loglik_start": rows[0]["neg_loglik"],
        "ml_neg_loglik_end": last["neg_loglik"],
        "ml_neg_loglik_true": true_nll,
    }


STUDY = Study(
    name="gravity_anomaly",
    description="Seed 004 B1: gravity anomaly at sea, Jordan + heave shaping filters, KF/RTS with χ²(4) GNSS rejection",
    config=Config,
    presets=PRESETS,
    claims=CLAIMS,
    assumptions=ASSUMPTIONS,
    run=run,
)
