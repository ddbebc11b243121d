"""Study ``gravity_map_slam``: EKF-SLAM with state augmentation, two laps of a closed track, loop closure
(seed 004 part 4 §B2).

The paper (authors lost) simulates an EKF-SLAM with 4 landmarks on a closed trajectory in two variants —
two laps in the same direction, and a second lap driven in reverse after turning around — and shows
the x-position error with its ±σ bounds: the error and σ drop sharply when the first, accurately mapped
landmark is seen again (loop closure), and further on the reverse lap.  No numbers are given (no speed,
noise, landmark layout or sample time), so every value here is assumed and named in the paper-facts
file; the claims are the paper's qualitative statements with a stated threshold.

Model: a unicycle driven by noisy odometry ``(v, ω)`` on a circle of radius ``radius`` (Euler, ``dt``),
a range–bearing sensor seeing the landmarks within ``max_range`` (known association), the kernel
:mod:`jaxsim.estimation.ekf_slam` (static shapes: the map slots are filled by state augmentation).
Monte Carlo over ``n_runs`` seeds (``vmap`` over a ``scan``; one compiled program for both variants:
the command sequence is an input).  Reported: the σ drop at loop closure, σ and actual error per lap,
the pose NEES averaged over runs against its χ² band (the known slow inconsistency of EKF-SLAM shows as
an NEES above the band late in the run), the landmark-map σ at the end.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np

from experiments import figures, stages
from experiments.runner import Study, StudyResult, paper_facts
from jaxsim.estimation import ekf_slam as slam
from jaxsim.estimation.gating import chi2_bounds

VARIANTS = ("same direction", "reverse")


@dataclass(frozen=True)
class Config:
    radius: float = 10.0  # m, the circular track (assumed; spec suggests ~10 m)
    speed: float = 1.0  # m/s (assumed)
    dt: float = 0.1  # s, odometry and scan period (assumed)
    start_deg: float = 30.0  # track angle of the start: landmark 0 is in view there (assumed)
    turn_s: float = 5.0  # s between the laps: a U-turn in place (reverse) or a stop (same direction)
    n_landmarks: int = 4  # spec §B2: 4 landmarks
    landmark_radius: float = 14.0  # m: a square of landmarks at 45° + k·90° on this circle (assumed)
    max_range: float = 7.0  # m: each landmark in view over ±28° of track around it (assumed)
    sigma_v: float = 0.05  # m/s, odometry speed noise (assumed)
    sigma_w_deg: float = 1.0  # °/s, odometry yaw-rate noise (assumed)
    sigma_range: float = 0.1  # m (spec suggestion)
    sigma_bearing_deg: float = 1.0  # ° (spec suggestion)
    sigma0_pos: float = 0.01  # m, initial pose σ per axis (the map frame is the start pose)
    sigma0_heading_deg: float = 0.1  # °
    n_runs: int = 200  # Monte-Carlo runs per variant
    closure_drop_max: float = 0.7  # "drops sharply": σ after / before the re-observation at most this
    seed: int = 0


PRESETS = {"quick": dict(n_runs=50), "tiny": dict(n_runs=8, dt=0.25)}
CLAIMS, ASSUMPTIONS = paper_facts("gravity_map_slam")


def landmarks(cfg: Config) -> np.ndarray:
    """True landmark positions ``(N, 2)`` (m): equally spaced on a circle, the first at 45°."""
    a = np.radians(45.0) + 2.0 * np.pi * np.arange(cfg.n_landmarks) / cfg.n_landmarks
    return cfg.landmark_radius * np.stack([np.cos(a), np.sin(a)], 1)


def commands(cfg: Config, variant: str) -> np.ndarray:
    """True ``(v, ω)`` per step ``(T, 2)``: lap 1 counter-clockwise, ``turn_s`` of turning in place by
    180° (reverse) or standing (same direction), lap 2 clockwise (reverse) or counter-clockwise."""
    if variant not in VARIANTS:
        raise ValueError(f"variant: expected one of {VARIANTS}, got {variant!r}")
    n_lap = int(round(2.0 * np.pi * cfg.radius / cfg.speed / cfg.dt))
    n_turn = int(round(cfg.turn_s / cfg.dt))
    w = cfg.speed / cfg.radius
    lap1 = np.tile([cfg.speed, w], (n_lap, 1))
    turn = np.tile([0.0, np.pi / (n_turn * cfg.dt) if variant == "reverse" else 0.0], (n_turn, 1))
    lap2 = np.tile([cfg.speed, -w if variant == "reverse" else w], (n_lap, 1))
    return np.concatenate([lap1, turn, lap2])


def start_pose(cfg: Config) -> np.ndarray:
    a = np.radians(cfg.start_deg)
    return np.array([cfg.radius * np.cos(a), cfg.radius * np.sin(a), a + np.pi / 2])


def monte_carlo_fn(cfg: Config) -> Callable:
    """One compiled ``(keys (R,), cmds (T, 2)) ->`` per-run, per-step arrays: true pose ``(R, T, 3)``, pose
    mean and covariance, landmark means and σ, whether landmark 0 was seen, pose NEES."""
    lms = jnp.asarray(landmarks(cfg))
    q_u = jnp.diag(jnp.array([cfg.sigma_v, np.radians(cfg.sigma_w_deg)]) ** 2)
    r = jnp.diag(jnp.array([cfg.sigma_range, np.radians(cfg.sigma_bearing_deg)]) ** 2)
    p0 = jnp.diag(jnp.array([cfg.sigma0_pos, cfg.sigma0_pos, np.radians(cfg.sigma0_heading_deg)]) ** 2)
    pose0 = jnp.asarray(start_pose(cfg))

    def motion(pose, u):
        return slam.unicycle(pose, u, cfg.dt)

    def one_run(key, cmds):
        k0, k1 = jax.random.split(key)
        truth0 = pose0 + jnp.sqrt(jnp.diag(p0)) * jax.random.normal(k0, (3,))
        state0 = slam.slam_init(pose0, p0, cfg.n_landmarks)

        def step(carry, inp):
            truth, state = carry
            u, k = inp
            ku, kz = jax.random.split(k)
            truth = motion(truth, u)
            odo = u + jnp.sqrt(jnp.diag(q_u)) * jax.random.normal(ku, (2,))
            state = slam.slam_predict(state, motion, odo, q_u)
            z_true = jax.vmap(slam.RANGE_BEARING.observe, (None, 0))(truth, lms)
            z = z_true + jnp.sqrt(jnp.diag(r)) * jax.random.normal(kz, z_true.shape)
            seen = z_true[:, 0] <= cfg.max_range
            state, _ = slam.slam_observe(state, slam.RANGE_BEARING, z, seen, r)
            lm_var = jnp.diagonal(state.cov)[3:].reshape(-1, 2)
            out = {
                "truth": truth,
                "mean": state.mean[:3],
                "cov": state.cov[:3, :3],
                "lm_mean": state.mean[3:].reshape(-1, 2),
                "lm_sigma": jnp.sqrt(lm_var.sum(1)),
                "seen0": seen[0],
                "nees": slam.pose_nees(state, truth),
            }
            return (truth, state), out

        keys = jax.random.split(k1, cmds.shape[0])
        return jax.lax.scan(step, (truth0, state0), (cmds, keys))[1]

    return jax.jit(jax.vmap(one_run, (0, None)))


def closure_index(cfg: Config, seen0: np.ndarray) -> int:
    """First step of lap 2's approach at which landmark 0 is seen again after being out of view."""
    n_lap = int(round(2.0 * np.pi * cfg.radius / cfg.speed / cfg.dt))
    gone = np.flatnonzero(~seen0[: n_lap + 1])
    first_gone = int(gone[0])
    back = np.flatnonzero(seen0[first_gone:]) + first_gone
    return int(back[0])


def summarise(cfg: Config, out: dict[str, np.ndarray], variant: str) -> tuple[dict[str, float], dict[str, Any]]:
    """Metrics of one variant from the Monte-Carlo arrays ``out`` (``(R, T, …)``)."""
    n_lap = int(round(2.0 * np.pi * cfg.radius / cfg.speed / cfg.dt))
    n_turn = int(round(cfg.turn_s / cfg.dt))
    sig = np.sqrt(out["cov"][..., 0, 0] + out["cov"][..., 1, 1])  # (R, T) position σ, m
    err = np.linalg.norm(out["truth"][..., :2] - out["mean"][..., :2], axis=-1)
    seen0 = out["seen0"][0]  # the sensor's view is (almost) the same in every run; take run 0's
    c = closure_index(cfg, np.asarray(seen0))
    lap1, lap2 = slice(0, n_lap), slice(n_lap + n_turn, None)
    runs = out["nees"].shape[0]
    lo, hi = chi2_bounds(3, runs)
    nees_avg = out["nees"].mean(0)
    lm_err = np.linalg.norm(out["lm_mean"][:, -1] - landmarks(cfg)[None], axis=-1)
    key = variant.split()[0]
    m = {
        f"{key}_closure_step_s": c * cfg.dt,
        f"{key}_closure_sigma_ratio": float(np.mean(sig[:, c] / sig[:, c - 1])),
        f"{key}_sigma_lap1_mean_m": float(sig[:, lap1].mean()),
        f"{key}_sigma_lap2_mean_m": float(sig[:, lap2].mean()),
        f"{key}_rms_error_lap1_m": float(np.sqrt((err[:, lap1] ** 2).mean())),
        f"{key}_rms_error_lap2_m": float(np.sqrt((err[:, lap2] ** 2).mean())),
        f"{key}_final_map_sigma_m": float(out["lm_sigma"][:, -1].mean()),
        f"{key}_final_map_rms_error_m": float(np.sqrt((lm_err**2).mean())),
        f"{key}_nees_fraction_in_band": float(np.mean((nees_avg >= lo) & (nees_avg <= hi))),
        f"{key}_nees_mean": float(nees_avg.mean()),
    }
    series = {"sigma_x": np.sqrt(out["cov"][0, :, 0, 0]), "err_x": out["truth"][0, :, 0] - out["mean"][0, :, 0]}
    series.update(nees_avg=nees_avg, band=(lo, hi), closure=c, sig_mean=sig.mean(0))
    return m, series


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    mc = monte_carlo_fn(cfg)
    keys = jax.random.split(jax.random.PRNGKey(cfg.seed), cfg.n_runs)  # the same seeds for both variants
    metrics: dict[str, float] = {}
    rows, series, finals = [], {}, {}
    for variant in progress(VARIANTS, desc="variants", unit="variant"):
        out = jax.tree_util.tree_map(np.asarray, mc(keys, jnp.asarray(commands(cfg, variant))))
        m, series[variant] = summarise(cfg, out, variant)
        metrics.update(m)
        finals[variant] = (out["truth"][0], out["mean"][0], out["lm_mean"][0, -1])
        key = variant.split()[0]
        rows.append({"variant": variant, **{k[len(key) + 1 :]: v for k, v in m.items()}})
    metrics["closure_drop_sharp"] = float(
        all(metrics[f"{v.split()[0]}_closure_sigma_ratio"] <= cfg.closure_drop_max for v in VARIANTS)
    )
    rev_lap2 = metrics["reverse_sigma_lap2_mean_m"]
    metrics["reverse_lap2_over_lap1_sigma"] = rev_lap2 / metrics["reverse_sigma_lap1_mean_m"]
    metrics["reverse_over_same_sigma_lap2"] = rev_lap2 / metrics["same_sigma_lap2_mean_m"]
    fig = _figure(cfg, series, finals)
    own = stages.Stage(
        metrics=metrics,
        tables={"variants": rows},
        figures={"slam": fig},
        notes=[
            f"{cfg.n_runs} Monte-Carlo runs per variant, the same seeds for both; NEES band: 95 % of the "
            "average of the runs' χ²(3) pose NEES",
            "closure_sigma_ratio: position σ right after landmark 0 is seen again over σ one step before",
            "all model values are assumed (the paper gives none); association is by landmark index",
        ],
    )
    return stages.merge(own)


def _figure(cfg: Config, series: dict, finals: dict):
    t = lambda s: np.arange(1, len(s["sigma_x"]) + 1) * cfg.dt  # noqa: E731
    lms = landmarks(cfg)
    plt = figures._plt()
    fig, axes = plt.subplots(1, 4, figsize=(24, 5))
    ax = axes[0]
    for (variant, (_, mean, lm_est)), style in zip(finals.items(), ("b", "r")):
        ax.plot(mean[:, 0], mean[:, 1], style + "-", lw=0.8, label=f"estimate ({variant}, run 0)")
        ax.plot(lm_est[:, 0], lm_est[:, 1], style + "x", ms=9)
    truth = finals[VARIANTS[0]][0]
    ax.plot(truth[:, 0], truth[:, 1], "k:", lw=0.8, label="true track")
    ax.plot(lms[:, 0], lms[:, 1], "k^", ms=9, label="landmarks")
    ax.set(title="tracks and final maps", xlabel="x, m", ylabel="y, m", aspect="equal")
    for ax, variant in zip(axes[1:3], VARIANTS):
        s = series[variant]
        tt = t(s)
        ax.plot(tt, s["err_x"], "b-", lw=0.8, label="x error (run 0)")
        ax.plot(tt, 2 * s["sigma_x"], "r--", lw=0.8, label="±2σ")
        ax.plot(tt, -2 * s["sigma_x"], "r--", lw=0.8)
        ax.axvline(s["closure"] * cfg.dt, color="k", lw=0.6, label="landmark 0 seen again")
        ax.set(title=f"{variant}: x error", xlabel="t, s", ylabel="x error, m")
    ax = axes[3]
    for variant, style in zip(VARIANTS, ("b-", "r-")):
        s = series[variant]
        ax.plot(t(s), s["nees_avg"], style, lw=0.8, label=f"{variant}: mean pose NEES")
    lo, hi = series[VARIANTS[0]]["band"]
    ax.axhline(lo, color="k", ls="--", lw=0.6, label="95 % band")
    ax.axhline(hi, color="k", ls="--", lw=0.6)
    ax.set(title=f"pose NEES, average of {cfg.n_runs} runs", xlabel="t, s", ylabel="NEES", yscale="log")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


STUDY = Study(
    name="gravity_map_slam",
    description="Seed 004 B2: EKF-SLAM with state augmentation, 4 landmarks, two laps — loop closure, NEES",
    config=Config,
    presets=PRESETS,
    claims=CLAIMS,
    assumptions=ASSUMPTIONS,
    run=run,
)
