"""Study ``vessel_tracking``: radar tracking of a manoeuvring vessel with a fuzzy window selector (seed 003).

Paper (seed 003, spec ``seed002_003_…`` §003): a 2-D radar (scan 3 s, resolution 6 m / 0.03°)
tracks a vessel that sails straight, turns on a 300 m radius and sails straight again, at 10 m/s
and at 20 m/s.  The tracker is a bank of growing-memory α–β filters over the last ``j = 2…10``
plots; a zero-order Sugeno system picks the window from the residual norms normalised by a running
noise-scale estimate (:mod:`jaxsim.estimation.window_selector`).  The paper shows one run per
speed (Fig. 5); its numbers are read from the figures.

What this study computes:

1. **Reproduction** (Monte Carlo over the radar noise, ``envelope_runs`` runs per speed, plus one
   seeded run drawn like Fig. 5): the position error ε on the straight legs (RMS and the per-run
   peak) and its peak in the turn, the selected window on the straight legs and in the turn, and
   the scan after which σ̂ stays within 10 % of its final value — each against the paper with a
   ±30 % band (the paper's values are single runs read from a figure).
2. **Track loss** (``runs`` ≥ 10,000 Monte-Carlo runs, speed uniform in the paper's 10–20 m/s, the
   turn's start uniform within one scan after 45 s): the track is lost at the first scan from
   ``loss_from`` on whose plot falls outside the circular gate of radius ``gate`` around the
   tracker's one-scan prediction (:mod:`jaxsim.estimation.track_loss`).  Trackers: fixed windows 3,
   5, 10, the paper's fuzzy selector, a CV Kalman filter and a CV + coordinated-turn IMM; every
   tracker sees the same plots and every gate width the same runs (common random numbers), with
   Wilson intervals.
3. **Tuning**: the selector's memberships (per input ``a_j``, ``c_j``) by gradient
   (:func:`optim.tune`) on the smooth surrogate of the loss probability at the default gate (smooth
   selector, soft gate), on a training batch of its own; the tuned selector (exact form) is then
   scored on the same Monte-Carlo runs as everything else.

``per_run`` exposes one run (all trackers but the tuned one) for ``python -m experiments sweep
vessel_tracking --param gate=20:120:6 --runs 10000``.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass
from typing import Any, Callable, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import optax

import jaxsim.montecarlo as mc
from experiments.study import PerRun, Study, StudyResult, assumption
from jaxsim.estimation.imm import imm_estimate, imm_init, imm_predict, imm_update
from jaxsim.estimation.lgssm import LinearGaussianSSM, kalman_filter
from jaxsim.estimation.motion_models import POSITION_2D, cv_ct_imm, cv_process_noise, cv_transition
from jaxsim.estimation.track_loss import miss_distances, soft_track_loss, track_lost
from jaxsim.estimation.window_selector import (
    WindowSelector,
    fixed_window,
    predicted_plots,
    select_estimates,
    select_windows,
    window_bank_filter,
    window_selector,
)
from jaxsim.plants.radar import cartesian_covariance, measure, radar, scan_times
from jaxsim.plants.vessel_target import VesselManoeuvre, vessel_state
from optim.reparam import Interval, Positive
from optim.tune import tune

FIXED_WINDOWS = (3, 5, 10)
BASE_TRACKERS = tuple(f"window{w}" for w in FIXED_WINDOWS) + ("fuzzy", "kalman_cv", "imm")
PAPER = {  # seed 003, section 4 and Fig. 5 (single runs, read from the figure)
    "err_straight_m": (10.0, 12.0),
    "err_turn_10ms_m": 22.0,
    "err_turn_20ms_m": 27.0,
    "window_straight": 10.0,
    "window_turn_10ms": (5.0, 6.0),
    "window_turn_20ms": (3.0, 4.0),
    "sigma_settle_scans": 20.0,
    "sigma_hat_m": 10.0,
}
TOLERANCE = 0.30  # the paper's numbers are single runs read from a figure


@dataclass(frozen=True)
class Config:
    quick: bool = False
    # scenario (paper: radius 300 m, 10 and 20 m/s, manoeuvre from 45 s, run 120 s)
    speeds: tuple = (10.0, 20.0)
    turn_radius: float = 300.0
    turn_start: float = 45.0
    turn_angle_deg: float = 90.0  # assumed
    t_final: float = 120.0
    target_range: float = 8000.0  # m, assumed
    # radar (paper: 3 s scan, 6 m / 0.03° resolution; noise assumed)
    scan_period: float = 3.0
    range_std: float = 7.0  # m, assumed
    cross_range_std: float = 7.0  # m at target_range (bearing std = this / target_range), assumed
    # tracker (paper: J = 10, a = 5, c = 1.5; κ and the t-norm assumed)
    max_window: int = 10
    slope: float = 5.0
    centre: float = 1.5
    kappa: float = math.sqrt(1.5 * math.pi)  # assumed: σ̂ estimates the 2-D RMS plot error
    tnorm: str = "product"  # assumed
    # evaluation
    warm_up: float = 30.0  # s: straight-leg statistics and gate checks from here (window full)
    recovery: float = 10.0  # s after the turn still counted as manoeuvre (paper: m recovers ≤ 10 s)
    gate: float = 50.0  # m, default gate (metrics p_loss_*)
    gates: tuple = (25.0, 30.0, 35.0, 40.0, 45.0, 50.0, 60.0, 70.0, 80.0, 100.0, 120.0)
    speed_range: tuple = (10.0, 20.0)  # m/s, track-loss Monte Carlo
    # baselines
    kalman_q: float = 0.25  # m²/s³, CV white-noise acceleration (assumed, see ASSUMPTIONS)
    imm_q_cv: float = 0.01
    imm_q_ct: float = 0.05
    imm_q_turn_rate: float = 1e-4  # rad²/s³
    imm_switch_prob: float = 0.05
    velocity_prior_std: float = 15.0  # m/s, Kalman/IMM initial velocity uncertainty
    turn_rate_prior_std: float = 0.1  # rad/s
    # Monte Carlo and tuning
    runs: int = 10_000  # track-loss runs per gate (quick: 1,000)
    envelope_runs: int = 2_000  # per speed (quick: 300)
    tune_runs: int = 1_000  # training batch (quick: 100)
    tune_steps: int = 150  # quick: 20
    learning_rate: float = 0.05
    smooth_temperature: float = 0.25  # window units (soft max and soft rounding)
    gate_temperature: float = 2.0  # m (soft gate)
    seed: int = 0


ASSUMPTIONS = {
    "noise": assumption(
        "range σ 7 m, cross-range σ 7 m at 8 km (bearing σ 0.050°), plus the 6 m / 0.03° resolution cells",
        "the paper gives only the resolution and says σ̂ ≈ 10 m 'reflects the RMS coordinate error': a 2-D "
        "RMS of 10 m is 7.07 m per coordinate; the extended-echo (centroid) error dominates the cells"),
    "target_range": assumption(8000.0, "a VTS radar's typical range; it sets the bearing error in metres"),
    "turn_angle_deg": assumption(90.0, "not stated; a 300 m arc flown for the paper's 45 s at 10 m/s is 86°"),
    "turn_timing": assumption(
        "turn from t = 45 s at both speeds (ends 92.1 s at 10 m/s, 68.6 s at 20 m/s); run 120 s",
        "the paper gives [45, 90] s at 10 m/s only; at 20 m/s it shows the window recovering on [65, 75] s, "
        "which fits the same start time"),
    "kappa": assumption(
        "√(3π/2) = 2.171",
        "the paper writes σ̂ = mean(Δz⁽²⁾) and says it settles at ≈ 10 m, the RMS plot error; under CV "
        "mean(Δz⁽²⁾) = √(3π/2)·(2-D RMS), so this normaliser makes σ̂ that RMS (κ = 1 gives σ̂ ≈ 22 m; "
        "table sensitivity)"),
    "tnorm": assumption("product", "not stated; min is in table sensitivity"),
    "max_with_previous": assumption(
        "max of the raw Sugeno outputs m_t, m_{t−1}",
        "with the final previous value the maximum could never fall, contradicting Fig. 5"),
    "warm_up": assumption(30.0, "statistics and gate checks start when the 10-plot window is full"),
    "recovery": assumption(10.0, "the paper says the window changes within 10 s; the turn phase includes "
                                 "10 s after the turn ends"),
    "track_loss": assumption(
        "first scan ≥ warm_up whose plot is farther than the gate radius from the one-scan prediction",
        "the paper uses the filtered error ε as a proxy for the gate width; a gate sees the prediction"),
    "loss_population": assumption(
        "speed U(10, 20) m/s, turn start U(45, 48) s, 90° turn, radar noise as above",
        "the paper's two speeds and everything between; the turn need not start at a scan"),
    "gate": assumption(50.0, "default gate: the paper's 30 m strobe loses most tracks once one-scan "
                              "prediction errors are counted (table track_loss); at 50 m the trackers differ most"),
    "kalman_q": assumption(0.25, "CV Kalman white-noise acceleration (m²/s³): σ_a ≈ 0.5 m/s² per 3 s scan, "
                                  "between the 0.33 and 1.33 m/s² of the two turns"),
    "imm": assumption("CV q 0.01, CT q 0.05 m²/s³, turn-rate q 1e-4 rad²/s³, switch 0.05 per scan",
                      "textbook CV/CT IMM settings (Bar-Shalom et al. §11.7) for a 3 s scan"),
    "tuning": assumption("per-input slopes and centres; Adam 0.05; soft gate T = 2 m; soft selector T = 0.25",
                         "the paper's (a, c) = (5, 1.5) are an expert's choice; the temperatures keep the "
                         "surrogate within a few % of the exact loss (table tuning)"),
}


# -----------------------------------------------------------------------------------------------
# one run


class Scenario(NamedTuple):
    """Plots ``z (T, 2)``, truth ``position (T, 2)``, scan ``times (T,)``, turn interval, plot covariance."""

    z: jax.Array
    position: jax.Array
    times: np.ndarray
    turn_start: jax.Array
    turn_end: jax.Array
    R: jax.Array


def nominal_params(cfg: Config) -> dict[str, float]:
    """Every parameter a sweep may set (``python -m experiments sweep vessel_tracking --param …``)."""
    return {"gate": cfg.gate, "speed": cfg.speeds[0], "turn_radius": cfg.turn_radius,
            "turn_start": cfg.turn_start, "turn_angle_deg": cfg.turn_angle_deg, "range_std": cfg.range_std,
            "cross_range_std": cfg.cross_range_std}


def simulate(cfg: Config, key: jax.Array, p: dict[str, Any]) -> Scenario:
    """The vessel and the radar plots of one run (parameters ``p`` as in :func:`nominal_params`)."""
    sensor = radar(p["range_std"], p["cross_range_std"] / cfg.target_range, period=cfg.scan_period)
    times = scan_times(sensor, cfg.t_final)
    f = lambda v: jnp.asarray(v, float)  # noqa: E731  (no value checks: the MC engine traces with zeros)
    m = VesselManoeuvre(f(p["speed"]), f(p["turn_radius"]), f(p["turn_start"]), jnp.deg2rad(f(p["turn_angle_deg"])),
                        f(0.0), f((-600.0, cfg.target_range)))
    truth = vessel_state(m, times)
    z = measure(sensor, key, truth.position)
    R = cartesian_covariance(sensor, truth.position[0])
    return Scenario(z, truth.position, times, m.turn_start, m.turn_end, R)


class Track(NamedTuple):
    """One tracker's ``positions (T, 2)`` and the ``predicted (T, 2)`` plot each scan is gated against."""

    positions: jax.Array
    predicted: jax.Array


def _one_plot_start(sc: Scenario, velocity_prior_std: float, extra_std: tuple[float, ...] = ()) -> tuple:
    """The belief after the first plot: position ``z_0`` with covariance ``R``, zero velocity (and any
    ``extra_std`` states) with the given prior spreads.  The filters then run on ``z[1:]`` from its
    one-scan prediction, so ``z_0`` is used exactly once."""
    stds = jnp.asarray([velocity_prior_std, velocity_prior_std, *extra_std], float)
    m0 = jnp.concatenate([sc.z[0], jnp.zeros(stds.shape[0])])
    P0 = jax.scipy.linalg.block_diag(sc.R, jnp.diag(stds**2))
    return m0, P0


def _prepend_first_plot(sc: Scenario, positions: jax.Array, predicted: jax.Array) -> Track:
    """Scan 0 of a one-plot start: estimate = plot, and the plot is its own "prediction" (miss 0)."""
    return Track(jnp.concatenate([sc.z[:1], positions]), jnp.concatenate([sc.z[:1], predicted]))


def kalman_track(cfg: Config, sc: Scenario) -> Track:
    """CV Kalman filter (Joseph form) from a one-plot start (velocity prior ``velocity_prior_std``)."""
    dt = cfg.scan_period
    F, Q = jnp.asarray(cv_transition(dt)), jnp.asarray(cv_process_noise(dt, cfg.kalman_q))
    m0, P0 = _one_plot_start(sc, cfg.velocity_prior_std)
    m1, P1 = F @ m0, F @ P0 @ F.T + Q
    res = kalman_filter(LinearGaussianSSM(F, Q, jnp.asarray(POSITION_2D), sc.R, m1, P1), sc.z[1:])
    return _prepend_first_plot(sc, res.means[:, :2], res.predicted_means[:, :2])


def imm_track(cfg: Config, sc: Scenario) -> Track:
    """CV + coordinated-turn IMM from a one-plot start; the prediction is the mixture's."""
    model = cv_ct_imm(cfg.scan_period, cfg.imm_q_cv, cfg.imm_q_ct, cfg.imm_q_turn_rate, sc.R, cfg.imm_switch_prob)
    m0, P0 = _one_plot_start(sc, cfg.velocity_prior_std, (cfg.turn_rate_prior_std,))
    prior = imm_predict(model, imm_init(jnp.stack([m0, m0]), jnp.stack([P0, P0]), jnp.array([0.5, 0.5])))

    def step(state, y):
        post, _ = imm_update(model, state, y)
        return imm_predict(model, post), (imm_estimate(post).mean[:2], imm_estimate(state).mean[:2])

    _, (pos, pred) = jax.lax.scan(step, prior, sc.z[1:])
    return _prepend_first_plot(sc, pos, pred)


def window_tracks(cfg: Config, sc: Scenario, selectors: dict[str, WindowSelector], *,
                  smooth: bool = False) -> tuple[dict[str, Track], dict[str, Any]]:
    """Fixed-window trackers and the fuzzy selectors on one bank; also each selector's :class:`Selection`."""
    bank = window_bank_filter(sc.z, cfg.max_window, cfg.scan_period)
    tracks, selections = {}, {}
    for w in FIXED_WINDOWS:
        est = select_estimates(bank, fixed_window(bank, w))
        tracks[f"window{w}"] = Track(est.positions, predicted_plots(est))
    for name, sel in selectors.items():
        s = select_windows(sel, bank, smooth=smooth, temperature=cfg.smooth_temperature)
        est = select_estimates(bank, s.weights)
        tracks[name], selections[name] = Track(est.positions, predicted_plots(est)), s
    return tracks, selections


def all_tracks(cfg: Config, sc: Scenario, selectors: dict[str, WindowSelector]) -> tuple[dict[str, Track], dict]:
    tracks, selections = window_tracks(cfg, sc, selectors)
    tracks["kalman_cv"] = kalman_track(cfg, sc)
    tracks["imm"] = imm_track(cfg, sc)
    return tracks, selections


def phases(cfg: Config, sc: Scenario) -> tuple[jax.Array, jax.Array, jax.Array]:
    """Masks ``(T,)``: checked scans (``t ≥ warm_up``), straight legs and the turn phase (turn + recovery)."""
    t = jnp.asarray(sc.times)
    checked = t >= cfg.warm_up
    turn = (t >= sc.turn_start) & (t <= sc.turn_end + cfg.recovery)
    return checked, checked & ~turn, turn


def paper_selector(cfg: Config) -> WindowSelector:
    return window_selector(cfg.max_window, cfg.slope, cfg.centre, kappa=cfg.kappa, tnorm=cfg.tnorm)


# -----------------------------------------------------------------------------------------------
# per-run metrics


def _masked_max(x: jax.Array, mask: jax.Array) -> jax.Array:
    return jnp.max(jnp.where(mask, x, -jnp.inf))


def _masked_rms(x: jax.Array, mask: jax.Array) -> jax.Array:
    return jnp.sqrt(jnp.sum(jnp.where(mask, x * x, 0.0)) / jnp.maximum(jnp.sum(mask), 1))


def _masked_median(x: jax.Array, mask: jax.Array) -> jax.Array:
    return jnp.nanmedian(jnp.where(mask, x, jnp.nan))


def settle_scan(sigma: jax.Array, valid: jax.Array, rel: float = 0.10) -> jax.Array:
    """Index of the first scan from which ``σ̂`` stays within ``rel`` of its final value."""
    outside = valid & (jnp.abs(sigma - sigma[-1]) > rel * sigma[-1])
    last_out = jnp.max(jnp.where(outside, jnp.arange(sigma.shape[0]), -1))
    return (last_out + 1).astype(float)


def envelope_metric(cfg: Config) -> Callable[[jax.Array, dict[str, Any]], dict[str, Any]]:
    """One run at a fixed speed: the reproduction's statistics for every tracker (fuzzy in detail)."""
    sel = paper_selector(cfg)

    def metric(key: jax.Array, p: dict[str, Any]) -> dict[str, Any]:
        sc = simulate(cfg, key, p)
        tracks, selections = all_tracks(cfg, sc, {"fuzzy": sel})
        _, straight, turn = phases(cfg, sc)
        on_arc = (jnp.asarray(sc.times) >= sc.turn_start) & (jnp.asarray(sc.times) <= sc.turn_end)
        out: dict[str, Any] = {"err": {}, "rms_straight": {}, "max_straight": {}, "max_turn": {}}
        for name, tr in tracks.items():
            err = jnp.linalg.norm(tr.positions - sc.position, axis=-1)
            out["err"][name] = err
            out["rms_straight"][name] = _masked_rms(err, straight)
            out["max_straight"][name] = _masked_max(err, straight)
            out["max_turn"][name] = _masked_max(err, turn)
        s = selections["fuzzy"]
        out["window"] = s.m
        out["sigma_hat"] = s.sigma_hat
        out["window_turn_median"] = _masked_median(s.m, on_arc)
        out["window_straight_median"] = _masked_median(s.m, straight)
        out["sigma_settle_scan"] = settle_scan(s.sigma_hat, jnp.arange(s.sigma_hat.shape[0]) >= 2)
        out["sigma_final"] = s.sigma_hat[-1]
        return out

    return metric


def loss_metric(cfg: Config, selectors: dict[str, WindowSelector], gates: Any = None) -> Callable:
    """One run: ``lost/<tracker>`` events at ``params["gate"]`` (or at every one of ``gates``, shape
    ``(G,)``) and ``max_miss/<tracker>``, the largest miss distance over the checked scans."""

    def metric(key: jax.Array, p: dict[str, Any]) -> dict[str, Any]:
        sc = simulate(cfg, key, p)
        tracks, _ = all_tracks(cfg, sc, selectors)
        checked, _, _ = phases(cfg, sc)
        gate = p["gate"] if gates is None else jnp.asarray(gates)
        out: dict[str, Any] = {"lost": {}, "max_miss": {}}
        for name, tr in tracks.items():
            d = miss_distances(sc.z, tr.predicted)
            out["lost"][name] = track_lost(d, gate, checked)
            out["max_miss"][name] = _masked_max(d, checked)
        return out

    return metric


def per_run(cfg: Config) -> PerRun:
    """One track-loss run (speed and turn start drawn as in the study) for ``experiments sweep``."""
    nominal = nominal_params(cfg)
    lo, hi = cfg.speed_range
    uncertain = {"speed": mc.uniform(lo, hi),
                 "turn_start": mc.uniform(cfg.turn_start, cfg.turn_start + cfg.scan_period)}
    return PerRun(loss_metric(cfg, {"fuzzy": paper_selector(cfg)}), nominal, uncertain)


# -----------------------------------------------------------------------------------------------
# tuning


def training_batch(cfg: Config, key: jax.Array, n: int) -> tuple[Any, Scenario, jax.Array]:
    """Banks, scenarios and checked-scan masks of ``n`` runs drawn like the track-loss Monte Carlo."""
    k_speed, k_start, k_noise = jax.random.split(key, 3)
    lo, hi = cfg.speed_range
    speeds = jax.random.uniform(k_speed, (n,), minval=lo, maxval=hi)
    starts = cfg.turn_start + cfg.scan_period * jax.random.uniform(k_start, (n,))
    base = nominal_params(cfg)

    def one(k, v, t0):
        sc = simulate(cfg, k, {**base, "speed": v, "turn_start": t0})
        return window_bank_filter(sc.z, cfg.max_window, cfg.scan_period), sc, phases(cfg, sc)[0]

    return jax.jit(jax.vmap(one))(jax.random.split(k_noise, n), speeds, starts)


def surrogate_loss(cfg: Config, sel: WindowSelector, banks: Any, z: jax.Array, checked: jax.Array, gate: Any, *,
                   smooth: bool = True) -> jax.Array:
    """Mean soft probability of loss over a batch (smooth selector and soft gate); with
    ``smooth=False`` the exact selector (still the soft gate)."""

    def one(bank, z_, mask):
        s = select_windows(sel, bank, smooth=smooth, temperature=cfg.smooth_temperature)
        d = miss_distances(z_, predicted_plots(select_estimates(bank, s.weights)))
        return soft_track_loss(d, gate, cfg.gate_temperature, mask)

    return jnp.mean(jax.vmap(one)(banks, z, checked))


def exact_batch_loss(cfg: Config, sel: WindowSelector, banks: Any, z: jax.Array, checked: jax.Array, gate: Any) -> jax.Array:
    """Fraction of the batch's runs lost (exact selector, exact gate)."""

    def one(bank, z_, mask):
        s = select_windows(sel, bank)
        return track_lost(miss_distances(z_, predicted_plots(select_estimates(bank, s.weights))), gate, mask)

    return jnp.mean(jax.vmap(one)(banks, z, checked).astype(float))


def tune_selector(cfg: Config, key: jax.Array) -> tuple[WindowSelector, dict[str, Any], Any]:
    """Gradient-tune per-input slopes and centres at ``cfg.gate``; returns the tuned selector, a
    summary row and the :class:`optim.tune.TuneResult`."""
    runs = 100 if cfg.quick else cfg.tune_runs
    steps = 20 if cfg.quick else cfg.tune_steps
    banks, sc, checked = training_batch(cfg, key, runs)
    sel0 = paper_selector(cfg)

    def with_params(p):
        return dataclasses.replace(sel0, slopes=p["slopes"], centres=p["centres"])

    loss = lambda p: surrogate_loss(cfg, with_params(p), banks, sc.z, checked, cfg.gate)  # noqa: E731
    params0 = {"slopes": sel0.slopes, "centres": sel0.centres}
    reparam = {"slopes": Positive(), "centres": Interval(0.0, float(sel0.clip))}
    res = tune(loss, params0, optimizer=optax.adam(cfg.learning_rate), steps=steps, reparam=reparam,
               sims_per_eval=runs, mode="reverse")  # one gradient ≈ 3 losses; forward mode needs 18
    tuned = with_params(res.params)
    exact = jax.jit(lambda s: exact_batch_loss(cfg, s, banks, sc.z, checked, cfg.gate))
    row = {"training_runs": runs, "steps": res.n_steps, "surrogate_initial": float(res.history.loss[0]),
           "surrogate_tuned": res.loss, "exact_initial_train": float(exact(sel0)),
           "exact_tuned_train": float(exact(tuned)), "wall_s": res.wall_s, "compile_s": res.compile_s,
           "slopes": [round(float(v), 3) for v in tuned.slopes], "centres": [round(float(v), 3) for v in tuned.centres]}
    return tuned, row, res


# -----------------------------------------------------------------------------------------------
# the study


def _block(n: int) -> int:
    return min(1000, n)


def envelope_sweep(cfg: Config, runs: int, progress: Callable[..., Any]) -> Any:
    """Monte Carlo of the reproduction metrics at each of ``cfg.speeds`` (common random numbers)."""
    design = mc.points(["speed"], np.asarray(cfg.speeds, float)[:, None])
    return mc.sweep(envelope_metric(cfg), nominal_params(cfg), design, runs, cfg.seed, block_size=_block(runs),
                    progress=progress, name="vessel_tracking.envelope")


def loss_space(cfg: Config) -> dict[str, Any]:
    """The track-loss population: speed uniform in ``speed_range``, turn start uniform within a scan."""
    lo, hi = cfg.speed_range
    return {**nominal_params(cfg), "speed": mc.uniform(lo, hi),
            "turn_start": mc.uniform(cfg.turn_start, cfg.turn_start + cfg.scan_period)}


def loss_monte_carlo(cfg: Config, selectors: dict[str, WindowSelector], runs: int,
                     progress: Callable[..., Any] | None = None, keep_runs: int = 0) -> Any:
    """``lost/<tracker>`` events ``(G,)`` over ``cfg.gates`` and ``max_miss/<tracker>`` for ``runs`` runs."""
    for g in cfg.gates:
        if not (np.isfinite(g) and g > 0):
            raise ValueError(f"gates: every gate width must be > 0 m, got {cfg.gates!r}")
    return mc.monte_carlo(loss_metric(cfg, selectors, cfg.gates), loss_space(cfg), runs, cfg.seed + 1,
                          block_size=_block(runs), keep_runs=keep_runs, progress=progress,
                          name="vessel_tracking.loss")


def _within(value: float, target: Any) -> bool:
    lo, hi = (target, target) if np.isscalar(target) else target
    return bool((1 - TOLERANCE) * lo <= value <= (1 + TOLERANCE) * hi)


def _target_str(target: Any) -> str:
    return f"{target:g}" if np.isscalar(target) else f"{target[0]:g}–{target[1]:g}"


def envelope_rows(cfg: Config, env: Any) -> list[dict[str, Any]]:
    """The reproduction against the paper: Monte-Carlo mean, 5–95 % of single runs, ±30 % check."""
    rows = []

    def add(quantity: str, target: Any, stats: Any, speed: float) -> None:
        mean = float(stats.mean)
        rows.append({"quantity": quantity, "speed_ms": speed, "paper": _target_str(target), "mc_mean": mean,
                     "single_run_p05": float(stats.quantile(0.05)), "single_run_p95": float(stats.quantile(0.95)),
                     "within_30pct": _within(mean, target)})

    for speed, res in zip(cfg.speeds, env.points):
        tag = f"{int(speed)}ms"
        add("error on straight legs, peak (m)", PAPER["err_straight_m"], res["max_straight/fuzzy"], speed)
        add("error on straight legs, RMS (m)", PAPER["err_straight_m"], res["rms_straight/fuzzy"], speed)
        add("error in the turn, peak (m)", PAPER.get(f"err_turn_{tag}_m", np.nan), res["max_turn/fuzzy"], speed)
        add("window on straight legs (median)", PAPER["window_straight"], res["window_straight_median"], speed)
        add("window in the turn (median)", PAPER.get(f"window_turn_{tag}", np.nan), res["window_turn_median"], speed)
        add("σ̂ settles (scans, within 10 %)", PAPER["sigma_settle_scans"], res["sigma_settle_scan"], speed)
        add("σ̂ final (m)", PAPER["sigma_hat_m"], res["sigma_final"], speed)
    return rows


def tracker_rows(cfg: Config, env: Any, loss: Any, names: tuple[str, ...]) -> list[dict[str, Any]]:
    """Comparison table: per tracker, loss probability at the default gate (Wilson 95 %) and errors."""
    gi = list(cfg.gates).index(cfg.gate)
    rows = []
    for name in names:
        ev = loss[f"lost/{name}"]
        lo, hi = ev.interval(0.95)
        row = {"tracker": name, "gate_m": cfg.gate, "p_loss": float(ev.probability[gi]),
               "wilson_low": float(lo[gi]), "wilson_high": float(hi[gi]),
               "max_miss_mean_m": float(loss[f"max_miss/{name}"].mean),
               "max_miss_p95_m": float(loss[f"max_miss/{name}"].quantile(0.95))}
        for speed, res in zip(cfg.speeds, env.points):
            if f"rms_straight/{name}" in res.by_name:
                row[f"rms_straight_{int(speed)}ms_m"] = float(res[f"rms_straight/{name}"].mean)
                row[f"max_turn_{int(speed)}ms_m"] = float(res[f"max_turn/{name}"].mean)
        rows.append(row)
    return rows


def loss_curve_rows(cfg: Config, loss: Any, names: tuple[str, ...]) -> list[dict[str, Any]]:
    rows = []
    for name in names:
        ev = loss[f"lost/{name}"]
        lo, hi = ev.interval(0.95)
        for i, g in enumerate(cfg.gates):
            rows.append({"tracker": name, "gate_m": g, "p_loss": float(ev.probability[i]),
                         "wilson_low": float(lo[i]), "wilson_high": float(hi[i]), "runs": loss.runs})
    return rows


def sensitivity_rows(cfg: Config, key: jax.Array, runs: int) -> list[dict[str, Any]]:
    """Envelope under the alternatives named in ASSUMPTIONS (κ = 1, min t-norm), small batches."""
    rows = []
    for label, change in (("paper defaults (κ = 2.17, product)", {}), ("κ = 1 (σ̂ = raw mean)", {"kappa": 1.0}),
                          ("min t-norm", {"tnorm": "min"})):
        c = dataclasses.replace(cfg, **change)
        metric = jax.jit(jax.vmap(envelope_metric(c), in_axes=(0, None)))
        for speed in cfg.speeds:
            out = metric(jax.random.split(key, runs), {**nominal_params(c), "speed": speed})
            rows.append({"variant": label, "speed_ms": speed, "runs": runs,
                         "sigma_final_m": float(jnp.mean(out["sigma_final"])),
                         "window_turn_median": float(jnp.mean(out["window_turn_median"])),
                         "max_turn_m": float(jnp.mean(out["max_turn"]["fuzzy"])),
                         "max_straight_m": float(jnp.mean(out["max_straight"]["fuzzy"]))})
    return rows


def _pair(values: Any, fmt: str = ".0f") -> str:
    return " / ".join(f"{v:{fmt}}" for v in values)


def normalisation_note(kappa: float, metrics: dict[str, Any], sensitivity: list[dict[str, Any]] | None) -> str:
    """Study note on the σ̂ normalisation, every number formatted from this run's ``metrics`` and (full
    runs) the ``sensitivity`` table's κ = 1 rows; speeds 10 / 20 m/s."""
    peaks = (metrics["max_err_turn_10ms_m"], metrics["max_err_turn_20ms_m"])
    paper_peaks = (PAPER["err_turn_10ms_m"], PAPER["err_turn_20ms_m"])
    side = "below" if max(p - q for p, q in zip(peaks, paper_peaks)) < 0 else "around or above"
    note = (f"where the reproduction differs: with σ̂ normalised to the 2-D RMS (κ = {kappa:.2f}) "
            f"σ̂ = {metrics['sigma_hat_final_m']:.1f} m (paper ≈ {PAPER['sigma_hat_m']:g} m), turn windows "
            f"{_pair((metrics['window_turn_10ms'], metrics['window_turn_20ms']), '.1f')} (paper "
            f"{_target_str(PAPER['window_turn_10ms'])} / {_target_str(PAPER['window_turn_20ms'])}), "
            f"turn peaks {_pair(peaks)} m, {side} the paper's {_pair(paper_peaks)} m; ")
    raw = [r for r in sensitivity or () if r["variant"].startswith("κ = 1")]
    if len(raw) == 2:
        note += (f"κ = 1 gives peaks of {_pair(r['max_turn_m'] for r in raw)} m but σ̂ = "
                 f"{_pair((r['sigma_final_m'] for r in raw), '.1f')} m and windows "
                 f"{_pair((r['window_turn_median'] for r in raw), '.1f')} (table sensitivity): no single noise "
                 "normalisation fits every number of the single-run figure")
    else:
        note += "the κ = 1 alternative is in table sensitivity (full runs only)"
    return (note + "; the straight-leg peak at 20 m/s includes the scans just after the turn, while the "
            "10-plot window still holds turn plots")


def _figures(cfg: Config, env: Any, singles: list, loss: Any, names: tuple[str, ...], tune_res: Any,
             sel0: WindowSelector, tuned: WindowSelector) -> dict[str, Any]:
    import matplotlib.pyplot as plt

    times = scan_times(radar(period=cfg.scan_period), cfg.t_final)
    figs = {}
    fig, axes = plt.subplots(1, len(cfg.speeds), figsize=(6 * len(cfg.speeds), 4), sharey=True)
    for ax, speed, res, (sc, single) in zip(np.atleast_1d(axes), cfg.speeds, env.points, singles):
        for name in BASE_TRACKERS:
            ax.plot(times, res[f"err/{name}"].mean, label=f"{name} (MC mean)")
        ax.plot(times, single["err"]["fuzzy"], "k:", label="fuzzy, one run")
        ax.axvspan(float(sc.turn_start), float(sc.turn_end), color="0.9")
        ax.axhline(PAPER.get(f"err_turn_{int(speed)}ms_m", np.nan), color="r", ls="--", lw=0.8, label="paper's turn peak")
        ax.set(title=f"{speed:g} m/s: position error ε", xlabel="t (s)", ylabel="m")
    np.atleast_1d(axes)[0].legend(fontsize=7)
    figs["error_vs_time"] = fig

    fig, axes = plt.subplots(2, len(cfg.speeds), figsize=(6 * len(cfg.speeds), 6), sharex=True)
    axes = np.asarray(axes).reshape(2, -1)
    for i, (speed, res, (sc, single)) in enumerate(zip(cfg.speeds, env.points, singles)):
        axes[0, i].step(times, single["window"], where="post", label="one run")
        axes[0, i].plot(times, res["window"].mean, label="MC mean")
        axes[0, i].axvspan(float(sc.turn_start), float(sc.turn_end), color="0.9")
        axes[0, i].set(title=f"{speed:g} m/s: selected window m", ylabel="scans", ylim=(1.5, cfg.max_window + 0.5))
        axes[1, i].plot(times, single["sigma_hat"], label="one run")
        axes[1, i].plot(times, res["sigma_hat"].mean, label="MC mean")
        axes[1, i].axhline(PAPER["sigma_hat_m"], color="r", ls="--", lw=0.8, label="paper ≈ 10 m")
        axes[1, i].set(title="noise-scale estimate σ̂", xlabel="t (s)", ylabel="m")
    axes[0, 0].legend(fontsize=7)
    axes[1, 0].legend(fontsize=7)
    figs["window_and_sigma"] = fig

    fig, ax = plt.subplots(figsize=(7, 4.5))
    gates = np.asarray(cfg.gates)
    for name in names:
        ev = loss[f"lost/{name}"]
        lo, hi = ev.interval(0.95)
        p = ev.probability
        ax.errorbar(gates, p, yerr=[p - lo, hi - p], marker="o", ms=3, capsize=2, label=name)
    ax.axvline(cfg.gate, color="0.5", ls=":", lw=0.8)
    ax.set(yscale="log", xlabel="gate radius (m)", ylabel="P(track lost) (Wilson 95 %)",
           title=f"track loss vs gate, {loss.runs} runs per point")
    ax.legend(fontsize=7)
    figs["track_loss_vs_gate"] = fig

    fig, axes = plt.subplots(1, 2, figsize=(12, 4))
    axes[0].plot(tune_res.history.loss)
    axes[0].set(title="tuning: surrogate P(loss) at the default gate", xlabel="step", ylabel="soft P(loss)")
    u = np.linspace(0.0, float(sel0.clip), 200)
    for j in (0, (cfg.max_window - 1) // 2, cfg.max_window - 2):
        for sel, ls, lab in ((sel0, "--", "paper"), (tuned, "-", "tuned")):
            good = 1.0 / (1.0 + np.exp(float(sel.slopes[j]) * (u - float(sel.centres[j]))))
            axes[1].plot(u, good, ls, label=f"μ_good, window {j + 2} ({lab})")
    axes[1].set(title="'good' memberships", xlabel="L = Δz/σ̂")
    axes[1].legend(fontsize=7)
    figs["tuning"] = fig
    return figs


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    if cfg.scan_period <= 0:
        raise ValueError(f"scan_period: must be > 0 s, got {cfg.scan_period!r}")
    if cfg.gate <= 0 or cfg.gate not in cfg.gates:
        raise ValueError(f"gate: must be > 0 m and one of gates {cfg.gates}, got {cfg.gate!r}")
    env_runs = 300 if cfg.quick else cfg.envelope_runs
    runs = 1_000 if cfg.quick else cfg.runs
    key = jax.random.PRNGKey(cfg.seed)
    k_single, k_tune, k_sens = jax.random.split(key, 3)
    sel0 = paper_selector(cfg)

    t0 = time.perf_counter()
    env = envelope_sweep(cfg, env_runs, progress)
    one = jax.jit(envelope_metric(cfg))
    singles = []
    for speed in cfg.speeds:
        p = {**nominal_params(cfg), "speed": speed}
        singles.append((simulate(cfg, k_single, p), jax.tree_util.tree_map(np.asarray, one(k_single, p))))
    env_s = time.perf_counter() - t0

    tuned, tune_row, tune_res = tune_selector(cfg, k_tune)
    names = BASE_TRACKERS + ("fuzzy_tuned",)
    t0 = time.perf_counter()
    loss = loss_monte_carlo(cfg, {"fuzzy": sel0, "fuzzy_tuned": tuned}, runs, progress)
    loss_s = time.perf_counter() - t0

    rows = envelope_rows(cfg, env)
    comparison = tracker_rows(cfg, env, loss, names)
    by_tracker = {r["tracker"]: r for r in comparison}
    res10, res20 = env.points[0], env.points[-1]
    metrics = {
        "rmse_straight_m": float(np.mean([r["rms_straight/fuzzy"].mean for r in env.points])),
        "max_err_turn_10ms_m": float(res10["max_turn/fuzzy"].mean),
        "max_err_turn_20ms_m": float(res20["max_turn/fuzzy"].mean),
        "p_loss_fuzzy": by_tracker["fuzzy"]["p_loss"],
        "p_loss_fuzzy_tuned": by_tracker["fuzzy_tuned"]["p_loss"],
        "p_loss_imm": by_tracker["imm"]["p_loss"],
        "p_loss_window5": by_tracker["window5"]["p_loss"],
        "p_loss_window3": by_tracker["window3"]["p_loss"],
        "p_loss_window10": by_tracker["window10"]["p_loss"],
        "p_loss_kalman_cv": by_tracker["kalman_cv"]["p_loss"],
        "gate_m": cfg.gate,
        "max_err_straight_m": float(np.mean([r["max_straight/fuzzy"].mean for r in env.points])),
        "window_straight_median": float(np.mean([r["window_straight_median"].mean for r in env.points])),
        "window_turn_10ms": float(res10["window_turn_median"].mean),
        "window_turn_20ms": float(res20["window_turn_median"].mean),
        "sigma_hat_final_m": float(np.mean([r["sigma_final"].mean for r in env.points])),
        "sigma_settle_scans": float(np.mean([r["sigma_settle_scan"].mean for r in env.points])),
        "envelope_within_30pct": int(sum(r["within_30pct"] for r in rows)),
        "envelope_checks": len(rows),
        "loss_runs": runs,
        "envelope_runs_per_speed": env_runs,
        "envelope_wall_s": env_s,
        "loss_wall_s": loss_s,
        "tune_wall_s": tune_row["wall_s"] + tune_row["compile_s"],
    }
    for name in names:
        metrics[f"p_loss_{name}_wilson_low"] = by_tracker[name]["wilson_low"]
        metrics[f"p_loss_{name}_wilson_high"] = by_tracker[name]["wilson_high"]
    tables = {
        "envelope": rows,
        "comparison": comparison,
        "track_loss": loss_curve_rows(cfg, loss, names),
        "tuning": [tune_row],
        "single_run": [{"t_s": float(t), **{f"err_{n}_{int(v)}ms": float(s["err"][n][i])
                                            for v, (_, s) in zip(cfg.speeds, singles) for n in BASE_TRACKERS},
                        **{f"window_{int(v)}ms": float(s["window"][i]) for v, (_, s) in zip(cfg.speeds, singles)},
                        **{f"sigma_hat_{int(v)}ms": float(s["sigma_hat"][i]) for v, (_, s) in zip(cfg.speeds, singles)}}
                       for i, t in enumerate(singles[0][0].times)],
    }
    if not cfg.quick:  # three more compilations: full runs only
        tables["sensitivity"] = sensitivity_rows(cfg, k_sens, 300)
    notes = [
        f"reproduction: {env_runs} Monte-Carlo runs per speed plus one seeded run (figures); the paper's "
        "values are single runs read from Fig. 5, compared with a ±30 % band",
        f"track loss: {runs} runs per gate width (common random numbers over gates and trackers), loss "
        f"checked from t = {cfg.warm_up:g} s; Wilson 95 % intervals",
        f"tuning: {tune_row['training_runs']} training runs of their own, surrogate "
        f"{tune_row['surrogate_initial']:.3f} → {tune_row['surrogate_tuned']:.3f}; exact loss on the "
        f"training batch {tune_row['exact_initial_train']:.3f} → {tune_row['exact_tuned_train']:.3f}",
        normalisation_note(cfg.kappa, metrics, tables.get("sensitivity")),
        f"at the {cfg.gate:g} m gate: P(loss) fuzzy {metrics['p_loss_fuzzy']:.4f}, tuned "
        f"{metrics['p_loss_fuzzy_tuned']:.4f}, IMM {metrics['p_loss_imm']:.4f}, window 5 {metrics['p_loss_window5']:.4f}",
    ]
    return StudyResult(metrics=metrics, tables=tables, assumptions=ASSUMPTIONS,
                       figures=_figures(cfg, env, singles, loss, names, tune_res, sel0, tuned), notes=notes)


STUDY = Study(
    name="vessel_tracking",
    description="Radar tracking of a turning vessel: α–β window bank with a Sugeno window selector "
                "(seed 003), track-loss Monte Carlo vs Kalman/IMM, gradient-tuned selector",
    config_cls=Config,
    run=run,
    per_run=per_run,
)
