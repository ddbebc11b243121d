"""The radar-tracking problem of the ``vessel_tracking`` study (seed 003): one run, the trackers, the
per-run statistics and the selector-tuning problem.

A 2-D radar (scan ``scan_period``) sees a vessel that sails straight, turns on ``turn_radius`` and
sails straight again (:mod:`jaxsim.plants.vessel_target`, :mod:`jaxsim.plants.radar`).  Trackers on
the same plots: growing-memory α–β filters over fixed windows 3, 5, 10, the paper's Sugeno window
selector over the bank of windows 2…``max_window`` (:mod:`jaxsim.estimation.window_selector`), a CV
Kalman filter and a CV + coordinated-turn IMM (:mod:`jaxsim.estimation.plot_trackers`).  A track is
lost at the first checked scan whose plot falls outside the circular gate around the tracker's
one-scan prediction (:mod:`jaxsim.estimation.track_loss`).

:func:`selector_problem` is the tuning problem of the selector's per-input memberships: the mean
soft probability of loss over a fixed training batch (smooth selector, soft gate).
Units: m, s, m/s.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Callable, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.estimation.plot_trackers import Track, imm_cv_ct_track, kalman_cv_track
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
from jaxsim.montecarlo.distributions import uniform
from jaxsim.plants.radar import cartesian_covariance, measure, radar, scan_times
from jaxsim.plants.vessel_target import VesselManoeuvre, vessel_state
from jaxsim.problem.problem import Problem
from jaxsim.problem.reparam import Positive
from jaxsim.problem.space import Param, ParamSpace

FIXED_WINDOWS = (3, 5, 10)
BASE_TRACKERS = tuple(f"window{w}" for w in FIXED_WINDOWS) + ("fuzzy", "kalman_cv", "imm")


@dataclass(frozen=True)
class TrackingSetup:
    """Scenario, radar, trackers and evaluation (the paper's values where it gives them)."""

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
    # smooth surrogate of the track-loss probability (tuning)
    smooth_temperature: float = 0.25  # window units (soft max and soft rounding)
    gate_temperature: float = 2.0  # m (soft gate)


class RadarRun(NamedTuple):
    """Plots ``z (T, 2)``, truth ``position (T, 2)``, scan ``times (T,)``, turn interval, plot covariance."""

    z: jax.Array
    position: jax.Array
    times: np.ndarray
    turn_start: jax.Array
    turn_end: jax.Array
    R: jax.Array


def check_setup(cfg: TrackingSetup) -> None:
    """``ValueError`` unless the scan period and every gate width are > 0 and ``gate`` is one of ``gates``."""
    if cfg.scan_period <= 0:
        raise ValueError(f"scan_period: must be > 0 s, got {cfg.scan_period!r}")
    if cfg.gate <= 0 or cfg.gate not in cfg.gates:
        raise ValueError(f"gate: must be > 0 m and one of gates {cfg.gates}, got {cfg.gate!r}")
    if not all(np.isfinite(g) and g > 0 for g in cfg.gates):
        raise ValueError(f"gates: every gate width must be > 0 m, got {cfg.gates!r}")


def nominal_params(cfg: TrackingSetup) -> dict[str, float]:
    """Every parameter a sweep may set (``python -m experiments sweep vessel_tracking --param …``)."""
    return {
        "gate": cfg.gate,
        "speed": cfg.speeds[0],
        "turn_radius": cfg.turn_radius,
        "turn_start": cfg.turn_start,
        "turn_angle_deg": cfg.turn_angle_deg,
        "range_std": cfg.range_std,
        "cross_range_std": cfg.cross_range_std,
    }


def simulate(cfg: TrackingSetup, key: jax.Array, p: dict[str, Any]) -> RadarRun:
    """The vessel and the radar plots of one run (parameters ``p`` as in :func:`nominal_params`)."""
    sensor = radar(p["range_std"], p["cross_range_std"] / cfg.target_range, period=cfg.scan_period)
    times = scan_times(sensor, cfg.t_final)
    f = lambda v: jnp.asarray(v, float)  # noqa: E731  (no value checks: the MC engine traces with zeros)
    m = VesselManoeuvre(
        f(p["speed"]),
        f(p["turn_radius"]),
        f(p["turn_start"]),
        jnp.deg2rad(f(p["turn_angle_deg"])),
        f(0.0),
        f((-600.0, cfg.target_range)),
    )
    truth = vessel_state(m, times)
    z = measure(sensor, key, truth.position)
    R = cartesian_covariance(sensor, truth.position[0])
    return RadarRun(z, truth.position, times, m.turn_start, m.turn_end, R)


def window_tracks(
    cfg: TrackingSetup, sc: RadarRun, selectors: dict[str, WindowSelector], *, smooth: bool = False
) -> tuple[dict[str, Track], dict[str, Any]]:
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


def all_tracks(cfg: TrackingSetup, sc: RadarRun, selectors: dict[str, WindowSelector]) -> tuple[dict[str, Track], dict]:
    """:func:`window_tracks` plus the CV Kalman filter and the IMM (both from a one-plot start)."""
    tracks, selections = window_tracks(cfg, sc, selectors)
    tracks["kalman_cv"] = kalman_cv_track(sc.z, sc.R, cfg.scan_period, cfg.kalman_q, cfg.velocity_prior_std)
    tracks["imm"] = imm_cv_ct_track(
        sc.z,
        sc.R,
        cfg.scan_period,
        q_cv=cfg.imm_q_cv,
        q_ct=cfg.imm_q_ct,
        q_turn_rate=cfg.imm_q_turn_rate,
        switch_prob=cfg.imm_switch_prob,
        velocity_prior_std=cfg.velocity_prior_std,
        turn_rate_prior_std=cfg.turn_rate_prior_std,
    )
    return tracks, selections


def phases(cfg: TrackingSetup, sc: RadarRun) -> tuple[jax.Array, jax.Array, jax.Array]:
    """Masks ``(T,)``: checked scans (``t ≥ warm_up``), straight legs and the turn phase (turn + recovery)."""
    t = jnp.asarray(sc.times)
    checked = t >= cfg.warm_up
    turn = (t >= sc.turn_start) & (t <= sc.turn_end + cfg.recovery)
    return checked, checked & ~turn, turn


def paper_selector(cfg: TrackingSetup) -> WindowSelector:
    return window_selector(cfg.max_window, cfg.slope, cfg.centre, kappa=cfg.kappa, tnorm=cfg.tnorm)


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


def envelope_metric(cfg: TrackingSetup) -> Callable[[jax.Array, dict[str, Any]], dict[str, Any]]:
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


def single_runs(cfg: TrackingSetup, key: jax.Array) -> list[tuple[RadarRun, dict[str, Any]]]:
    """One run per speed of ``cfg.speeds`` with the same ``key``: the run and its
    :func:`envelope_metric` statistics (NumPy)."""
    one = jax.jit(envelope_metric(cfg))
    return [
        (simulate(cfg, key, p), jax.tree_util.tree_map(np.asarray, one(key, p)))
        for p in ({**nominal_params(cfg), "speed": v} for v in cfg.speeds)
    ]


def envelope_means(cfg: TrackingSetup, key: jax.Array, runs: int) -> list[dict[str, float]]:
    """Per speed of ``cfg.speeds``, means over ``runs`` runs (keys split from ``key``) of the fuzzy
    tracker's final σ̂ (m), median turn window (scans) and error peaks in the turn and on the straight legs (m)."""
    metric = jax.jit(jax.vmap(envelope_metric(cfg), in_axes=(0, None)))
    out = []
    for speed in cfg.speeds:
        stats = metric(jax.random.split(key, runs), {**nominal_params(cfg), "speed": speed})
        out.append(
            {
                "sigma_final_m": float(jnp.mean(stats["sigma_final"])),
                "window_turn_median": float(jnp.mean(stats["window_turn_median"])),
                "max_turn_m": float(jnp.mean(stats["max_turn"]["fuzzy"])),
                "max_straight_m": float(jnp.mean(stats["max_straight"]["fuzzy"])),
            }
        )
    return out


def loss_metric(cfg: TrackingSetup, selectors: dict[str, WindowSelector], gates: Any = None) -> Callable:
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


def loss_run(cfg: TrackingSetup) -> tuple[Callable, dict[str, float], dict[str, Any]]:
    """One track-loss run of the paper's selector, for a parameter sweep: ``(metric, nominal
    parameters, the drawn ones)`` — speed and turn start drawn as in :func:`loss_space`."""
    space = loss_space(cfg)
    return (
        loss_metric(cfg, {"fuzzy": paper_selector(cfg)}),
        nominal_params(cfg),
        {k: space[k] for k in ("speed", "turn_start")},
    )


def loss_space(cfg: TrackingSetup) -> dict[str, Any]:
    """The track-loss population: speed uniform in ``speed_range``, turn start uniform within a scan."""
    lo, hi = cfg.speed_range
    return {
        **nominal_params(cfg),
        "speed": uniform(lo, hi),
        "turn_start": uniform(cfg.turn_start, cfg.turn_start + cfg.scan_period),
    }


def training_batch(cfg: TrackingSetup, key: jax.Array, n: int) -> tuple[Any, RadarRun, jax.Array]:
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


def surrogate_loss(
    cfg: TrackingSetup,
    sel: WindowSelector,
    banks: Any,
    z: jax.Array,
    checked: jax.Array,
    gate: Any,
    *,
    smooth: bool = True,
) -> jax.Array:
    """Mean soft probability of loss over a batch (smooth selector and soft gate); with
    ``smooth=False`` the exact selector (still the soft gate)."""

    def one(bank, z_, mask):
        s = select_windows(sel, bank, smooth=smooth, temperature=cfg.smooth_temperature)
        d = miss_distances(z_, predicted_plots(select_estimates(bank, s.weights)))
        return soft_track_loss(d, gate, cfg.gate_temperature, mask)

    return jnp.mean(jax.vmap(one)(banks, z, checked))


def exact_batch_loss(
    cfg: TrackingSetup, sel: WindowSelector, banks: Any, z: jax.Array, checked: jax.Array, gate: Any
) -> jax.Array:
    """Fraction of the batch's runs lost (exact selector, exact gate)."""

    def one(bank, z_, mask):
        s = select_windows(sel, bank)
        return track_lost(miss_distances(z_, predicted_plots(select_estimates(bank, s.weights))), gate, mask)

    return jnp.mean(jax.vmap(one)(banks, z, checked).astype(float))


def selector_problem(cfg: TrackingSetup, key: jax.Array, runs: int) -> tuple[Problem, Callable]:
    """The selector's per-input ``slopes`` (> 0, softplus) and ``centres`` (in ``(0, clip)``) from the
    paper's, scored by :func:`surrogate_loss` at ``cfg.gate`` on ``runs`` training runs of their own;
    also ``exact(selector)``, the fraction of that batch lost (exact selector, exact gate)."""
    banks, sc, checked = training_batch(cfg, key, runs)
    sel0 = paper_selector(cfg)

    def loss(p, draw, k):
        return surrogate_loss(cfg, with_memberships(sel0, p), banks, sc.z, checked, cfg.gate)

    clip = float(sel0.clip)
    space = ParamSpace(
        slopes=Param(lo=1e-6, hi=1e3, init=sel0.slopes, reparam=Positive()),
        centres=Param(lo=0.0, hi=clip, init=sel0.centres),
    )
    exact = jax.jit(lambda s: exact_batch_loss(cfg, s, banks, sc.z, checked, cfg.gate))
    return Problem.from_loss("window_selector", space, loss), exact


def with_memberships(sel: WindowSelector, p: dict[str, Any]) -> WindowSelector:
    """``sel`` with the ``slopes`` and ``centres`` of ``p``."""
    return dataclasses.replace(sel, slopes=p["slopes"], centres=p["centres"])
