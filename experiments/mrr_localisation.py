"""Study ``mrr_localisation``: localisation of 10 moving objects in the work zone of a modular
reconfigurable robot from stationary monitoring points — two cameras, then two cameras and a 2-D
scanning laser rangefinder (seed 000, paper 3; spec §3).

The paper's method: per-axis constant-acceleration Kalman filters (state ``(L, V, a)``, 25 Hz) predict
each object; each sensor's detections are assigned to objects by likelihood ("the highest likelihood
wins"); accuracy and MOTA come from an Octave simulation of an 8 × 7 m zone with 10 objects for 60 s.
Its table: mean / SD / max error 1.7 / 0.98 / 10.5 cm and MOTA 82 % (two cameras), 1.3 / 0.93 / 9.8 cm
and 86 % (with the rangefinder).  The scene, the sensor models and every filter parameter are missing
(spec: "not reproducible"), so all of them are assumed here (named in the paper-facts file) and the
claims are the paper's two trends — the rangefinder lowers the error and raises MOTA — checked with
paired Monte-Carlo intervals; the paper's values are printed beside ours for reference only.

Simulation (one compiled program, ``vmap`` over runs of a ``scan`` over frames; the rangefinder is a
mask, so both sensor sets share the program): objects with Ornstein–Uhlenbeck accelerations, drag and
springs near the walls; sensors in three corners; a camera measures the ground-plane position with a small
cross-ray and a larger along-ray error, the rangefinder range and bearing; an object is missed when
another object hides its centre from the sensor (discs of ``object_radius``) or at random; clutter
detections appear uniformly.  Each frame, sensor by sensor: Gaussian scores, a χ² gate, greedy
assignment (:mod:`jaxsim.estimation.association`), Kalman updates with the measurement's own
covariance.  The tracks report where they were updated in the frame; MOTA by CLEAR MOT
(:mod:`jaxsim.estimation.mot_metrics`, equal to ``motmetrics`` in the tests).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np
import scipy.stats

from experiments import figures, stages
from experiments.runner import Study, StudyResult, paper_facts
from jaxsim.estimation import kalman
from jaxsim.estimation.association import gaussian_scores, greedy_assignment
from jaxsim.estimation.gating import chi2_threshold
from jaxsim.estimation.mot_metrics import clear_mot
from jaxsim.estimation.motion_models import ca_planar
from jaxsim.estimation.types import GaussianState

SENSOR_SETS = {"two cameras": (1.0, 1.0, 0.0), "two cameras + rangefinder": (1.0, 1.0, 1.0)}
PAPER = {  # line 2793: mean, SD, max error (cm), MOTA (%) — reference only, not claims
    "two cameras": (1.7, 0.98, 10.5, 82.0),
    "two cameras + rangefinder": (1.3, 0.93, 9.8, 86.0),
}


@dataclass(frozen=True)
class Config:
    width: float = 8.0  # m (paper)
    height: float = 7.0  # m (paper)
    n_objects: int = 10  # paper
    rate_hz: float = 25.0  # paper
    duration_s: float = 60.0  # paper: 1500 measurements
    accel_sigma: float = 0.3  # m/s², stationary σ of each acceleration component (OU; assumed)
    accel_tau: float = 1.0  # s, its correlation time (assumed)
    drag_tau: float = 3.0  # s, velocity damping: speeds stay bounded (≈ 0.4 m/s per axis; assumed)
    wall_margin: float = 0.5  # m: within it a spring of ``wall_stiffness`` pushes objects back
    wall_stiffness: float = 10.0  # 1/s²
    object_radius: float = 0.15  # m, a disc that hides objects behind it (assumed)
    cameras: tuple[tuple[float, float], ...] = ((0.0, 0.0), (8.0, 7.0))  # m, opposite corners (assumed)
    rangefinder: tuple[float, float] = (8.0, 0.0)  # m (assumed)
    camera_bearing_sigma_deg: float = 0.1  # ° (≈ a pixel; assumed)
    camera_depth_sigma_rel: float = 0.01  # along-ray σ as a fraction of the range (assumed)
    laser_range_sigma: float = 0.01  # m (assumed)
    laser_bearing_sigma_deg: float = 0.25  # ° (assumed)
    p_detect: float = 0.98  # per sensor and object, besides occlusion (assumed)
    clutter_rate: float = 0.1  # false detections per sensor and frame (assumed)
    clutter_slots: int = 2
    jerk_density: float = 1.0  # m²/s⁵, CA filter's white-jerk density (assumed; the OU acceleration
    # alone has 2σ²/τ = 0.18, the walls add jerk)
    gate_prob: float = 0.999
    feature_dim: int = 3  # a feature vector per object (colour, shape), unit normal across objects (assumed)
    feature_sigma: float = 0.3  # its measurement noise σ (assumed)
    lost_frames: int = 5  # a track not updated for this many frames is re-acquired by features alone
    match_threshold: float = 0.15  # m, CLEAR MOT distance (assumed; above the paper's max error)
    n_runs: int = 10
    seed: int = 0


PRESETS = {"quick": dict(n_runs=4, duration_s=30.0), "tiny": dict(n_runs=2, duration_s=6.0)}
CLAIMS, ASSUMPTIONS = paper_facts("mrr_localisation")


def _sensor_positions(cfg: Config) -> jax.Array:
    return jnp.asarray([*cfg.cameras, cfg.rangefinder], dtype=float)  # (3, 2): cam, cam, laser


def _polar_cov(rho: jax.Array, beta: jax.Array, s_along: jax.Array, s_cross: jax.Array) -> jax.Array:
    """Covariance ``(…, 2, 2)`` of a position error ``s_along`` along the ray at bearing ``beta`` and
    ``s_cross`` across it."""
    c, s = jnp.cos(beta), jnp.sin(beta)
    rot = jnp.stack([jnp.stack([c, -s], -1), jnp.stack([s, c], -1)], -2)
    d = jnp.stack([s_along**2, s_cross**2], -1)
    return rot @ (d[..., :, None] * jnp.swapaxes(rot, -1, -2))


def sensor_sigmas(cfg: Config, k: int, rho: jax.Array) -> tuple[jax.Array, jax.Array]:
    """Along- and cross-ray σ (m) of sensor ``k`` (0, 1 cameras, 2 rangefinder) at range ``rho``."""
    if k < 2:
        return cfg.camera_depth_sigma_rel * rho, rho * np.radians(cfg.camera_bearing_sigma_deg)
    return jnp.full_like(rho, cfg.laser_range_sigma), rho * np.radians(cfg.laser_bearing_sigma_deg)


def visible(pos: jax.Array, sensor: jax.Array, radius: float) -> jax.Array:
    """``(n,)`` bool: the object's centre is not hidden by a nearer object's disc, seen from ``sensor``."""
    d = pos - sensor
    rho = jnp.linalg.norm(d, axis=1)
    beta = jnp.arctan2(d[:, 1], d[:, 0])
    dbeta = jnp.abs(jnp.angle(jnp.exp(1j * (beta[:, None] - beta[None, :]))))
    half = jnp.arcsin(jnp.clip(radius / rho, 0.0, 1.0))
    hides = (rho[None, :] < rho[:, None]) & (dbeta < half[None, :])  # [i, j]: j hides i
    return ~jnp.any(hides, axis=1)


def simulate_fn(cfg: Config) -> Callable:
    """One compiled ``(keys (R,), use (3,)) ->`` per run and frame: true positions ``(R, T, n, 2)``,
    track position means ``(R, T, n, 2)`` and covariances ``(R, T, n, 2, 2)``, whether each track was
    updated ``(R, T, n)``, and the number of assigned clutter detections ``(R, T)``; ``use``: which of
    the sensors (camera, camera, rangefinder) report."""
    n, dt = cfg.n_objects, 1.0 / cfg.rate_hz
    T = int(round(cfg.duration_s * cfg.rate_hz))
    F, Q, H = (jnp.asarray(a) for a in ca_planar(dt, cfg.jerk_density))
    sensors = _sensor_positions(cfg)
    gate = chi2_threshold(2, cfg.gate_prob)
    f_gate = chi2_threshold(cfg.feature_dim, cfg.gate_prob)
    p_restart = jnp.kron(jnp.eye(2), jnp.diag(jnp.array([0.0, 0.5, 1.0]) ** 2))  # velocity, acceleration σ
    lo = jnp.array([cfg.wall_margin, cfg.wall_margin])
    hi = jnp.array([cfg.width - cfg.wall_margin, cfg.height - cfg.wall_margin])
    a_ou = np.exp(-dt / cfg.accel_tau)
    s_ou = cfg.accel_sigma * np.sqrt(1.0 - a_ou**2)
    area = jnp.array([cfg.width, cfg.height])
    m = n + cfg.clutter_slots

    def move(pos, vel, acc, key):
        """Smooth motion: OU acceleration, drag, and a spring near the walls (semi-implicit Euler)."""
        acc = a_ou * acc + s_ou * jax.random.normal(key, acc.shape)
        wall = cfg.wall_stiffness * (jnp.maximum(lo - pos, 0.0) - jnp.maximum(pos - hi, 0.0))
        vel = vel + (acc + wall - vel / cfg.drag_tau) * dt
        return jnp.clip(pos + vel * dt, 0.0, area), vel, acc

    def detections(k, pos, feats, key):
        """Sensor ``k``'s detections ``(m, 2)``, their covariances ``(m, 2, 2)``, features ``(m, d)`` and
        presence ``(m,)``."""
        kd, kn, kc, kp, kf = jax.random.split(key, 5)
        c = sensors[k]
        seen = visible(pos, c, cfg.object_radius) & (jax.random.uniform(kd, (n,)) < cfg.p_detect)
        clutter = jax.random.uniform(kc, (cfg.clutter_slots, 2)) * jnp.array([cfg.width, cfg.height])
        has_clutter = jax.random.uniform(kp, (cfg.clutter_slots,)) < cfg.clutter_rate / cfg.clutter_slots
        d = pos - c
        rho, beta = jnp.linalg.norm(d, axis=1), jnp.arctan2(d[:, 1], d[:, 0])
        s_al, s_cr = sensor_sigmas(cfg, k, rho)
        e = jax.random.normal(kn, (n, 2))
        if k < 2:  # camera: Gaussian position error along / across the ray
            z = pos + jnp.stack([jnp.cos(beta), jnp.sin(beta)], 1) * (s_al * e[:, 0])[:, None]
            z = z + jnp.stack([-jnp.sin(beta), jnp.cos(beta)], 1) * (s_cr * e[:, 1])[:, None]
        else:  # rangefinder: Gaussian range and bearing
            r_m = rho + cfg.laser_range_sigma * e[:, 0]
            b_m = beta + np.radians(cfg.laser_bearing_sigma_deg) * e[:, 1]
            z = c + r_m[:, None] * jnp.stack([jnp.cos(b_m), jnp.sin(b_m)], 1)
        z = jnp.concatenate([z, clutter])
        dz = z - c  # the covariance the system knows: evaluated at the measurement
        rho_z, beta_z = jnp.linalg.norm(dz, axis=1), jnp.arctan2(dz[:, 1], dz[:, 0])
        R = _polar_cov(rho_z, beta_z, *sensor_sigmas(cfg, k, rho_z))
        f_noise = jax.random.normal(kf, (m, cfg.feature_dim))
        fz = jnp.concatenate([feats, jnp.zeros((cfg.clutter_slots, cfg.feature_dim))]) + jnp.concatenate(
            [cfg.feature_sigma * f_noise[:n], f_noise[n:]]
        )
        return z, R, fz, jnp.concatenate([seen, has_clutter])

    def assign_and_update(tracks, active, feats, z, R, fz, present):
        """Tracks that are ``active`` take detections by position + feature likelihood within the
        position gate; lost ones take a remaining detection by feature alone and restart on it."""
        zh = tracks.mean @ H.T
        S = H @ tracks.cov @ H.T
        sc = gaussian_scores(zh, S, z, R)
        f_nis = jnp.sum((fz[None, :, :] - feats[:, None, :]) ** 2, -1) / cfg.feature_sigma**2
        score = sc.log_lik - 0.5 * f_nis
        pick = greedy_assignment(score, active[:, None] & present[None, :] & (sc.nis <= gate))
        free = present & ~jnp.any(jnp.arange(m)[None, :] == pick[:, None], axis=0)
        again = greedy_assignment(-f_nis, ~active[:, None] & free[None, :] & (f_nis <= f_gate))
        got, restart = pick >= 0, again >= 0
        j = jnp.where(restart, again, jnp.maximum(pick, 0))

        def upd(mean, cov, zj, Rj, ok, new):
            post = kalman.update(GaussianState(mean, cov), zj, H, Rj, mask=jnp.broadcast_to(ok, (2,)))[0]
            fresh = GaussianState(H.T @ zj, H.T @ Rj @ H + p_restart)
            return jax.tree_util.tree_map(lambda a, b: jnp.where(new, a, b), fresh, post)

        post = jax.vmap(upd)(tracks.mean, tracks.cov, z[j], R[j], got, restart)
        taken = got | restart
        return post, taken, jnp.sum(taken & (j >= n))  # clutter taken by a track

    def one_run(key, use):
        k0, k1, k2, k4 = jax.random.split(key, 4)
        pos0 = lo + jax.random.uniform(k0, (n, 2)) * (hi - lo)
        k1, k3 = jax.random.split(k1)
        acc0 = cfg.accel_sigma * jax.random.normal(k3, (n, 2))
        vel0 = (
            cfg.accel_sigma * cfg.drag_tau * jax.random.normal(k1, (n, 2)) / np.sqrt(1 + cfg.drag_tau / cfg.accel_tau)
        )
        x0 = jnp.zeros((n, 6)).at[:, 0].set(pos0[:, 0]).at[:, 3].set(pos0[:, 1])
        x0 = x0.at[:, 1].set(vel0[:, 0]).at[:, 4].set(vel0[:, 1]).at[:, 2].set(acc0[:, 0]).at[:, 5].set(acc0[:, 1])
        p0 = jnp.diag(jnp.array([0.01, 0.1, 1.0, 0.01, 0.1, 1.0]) ** 2)
        tracks0 = GaussianState(x0, jnp.broadcast_to(p0, (n, 6, 6)))  # initialised on the objects ([29])

        def frame(carry, k):
            pos, vel, acc, tracks, stale = carry
            km, *ks = jax.random.split(k, 4)
            pos, vel, acc = move(pos, vel, acc, km)
            tracks = jax.vmap(lambda a, b: kalman.predict(GaussianState(a, b), F, Q))(tracks.mean, tracks.cov)
            updated = jnp.zeros(n, bool)
            clutter = jnp.zeros((), jnp.int32)
            active = stale < cfg.lost_frames
            for s in range(3):
                z, R, fz, present = detections(s, pos, feats, ks[s])
                post, got, cl = assign_and_update(tracks, active, feats, z, R, fz, present & (use[s] > 0))
                tracks, updated, clutter = post, updated | got, clutter + cl.astype(jnp.int32)
            stale = jnp.where(updated, 0, stale + 1)
            cov_xy = tracks.cov[:, (0, 3), :][:, :, (0, 3)]
            return (pos, vel, acc, tracks, stale), (pos, tracks.mean[:, (0, 3)], cov_xy, updated, clutter)

        feats = jax.random.normal(k4, (n, cfg.feature_dim))  # each track knows its object's feature
        stale0 = jnp.zeros(n, jnp.int32)
        return jax.lax.scan(frame, (pos0, vel0, acc0, tracks0, stale0), jax.random.split(k2, T))[1]

    return jax.jit(jax.vmap(one_run, (0, None)))


def score_run(cfg: Config, truth: np.ndarray, est: np.ndarray, updated: np.ndarray) -> dict[str, Any]:
    """CLEAR MOT of one run (``truth, est (T, n, 2)``, ``updated (T, n)``) and its error statistics."""
    ids = np.arange(cfg.n_objects)
    res = clear_mot(
        [ids] * len(truth),
        list(truth),
        [ids[u] for u in updated],
        [e[u] for e, u in zip(est, updated)],
        cfg.match_threshold,
    )
    return {"mot": res, "distances": res.distances}


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    sim = simulate_fn(cfg)
    keys = jax.random.split(jax.random.PRNGKey(cfg.seed), cfg.n_runs)  # same scenes for both sensor sets
    per_run: dict[str, list[dict[str, Any]]] = {}
    example = {}
    for name in progress(list(SENSOR_SETS), desc="sensor sets", unit="set"):
        truth, est, cov, updated, clutter = (np.asarray(a) for a in sim(keys, jnp.asarray(SENSOR_SETS[name])))
        per_run[name] = []
        for r in range(cfg.n_runs):
            sc = score_run(cfg, truth[r], est[r], updated[r])
            sc["clutter_taken"] = int(clutter[r].sum())
            e = (truth[r] - est[r])[updated[r]]
            sc["nees"] = np.einsum("ki,kij,kj->k", e, np.linalg.inv(cov[r][updated[r]]), e)
            per_run[name].append(sc)
        example[name] = (truth[0], est[0], updated[0])
    rows, metrics = [], {}
    nees_lo, nees_hi = scipy.stats.chi2.ppf([0.025, 0.975], 2)
    for name, runs in per_run.items():
        d = np.concatenate([s["distances"] for s in runs])
        mot = [s["mot"] for s in runs]
        nees = np.concatenate([s["nees"] for s in runs])
        tot = {k: sum(getattr(x, k) for x in mot) for k in ("num_objects", "misses", "false_positives", "switches")}
        mota = 1.0 - (tot["misses"] + tot["false_positives"] + tot["switches"]) / tot["num_objects"]
        key = "cameras" if name == "two cameras" else "with_rangefinder"
        row = {
            "sensors": name,
            "mean_error_cm": 100 * float(d.mean()),
            "sd_error_cm": 100 * float(d.std(ddof=1)),
            "max_error_cm": 100 * float(d.max()),
            "mota_pct": 100 * mota,
            "misses": tot["misses"],
            "false_positives": tot["false_positives"],
            "switches": tot["switches"],
            "clutter_taken": sum(s["clutter_taken"] for s in runs),
            "object_frames": tot["num_objects"],
            "median_position_nees": float(np.median(nees)),
            "position_nees_in_95_pct": 100 * float(np.mean((nees >= nees_lo) & (nees <= nees_hi))),
        }
        for label, v in zip(("paper_mean_cm", "paper_sd_cm", "paper_max_cm", "paper_mota_pct"), PAPER[name]):
            row[label] = v
        rows.append(row)
        metrics.update({f"{key}_{k}": float(row[k]) for k in ("mean_error_cm", "sd_error_cm", "max_error_cm")})
        metrics[f"{key}_mota_pct"] = row["mota_pct"]
        metrics[f"{key}_median_position_nees"] = row["median_position_nees"]
        metrics[f"{key}_position_nees_in_95_pct"] = row["position_nees_in_95_pct"]
    # paired differences over the runs (same scenes): rangefinder − cameras
    a, b = per_run["two cameras + rangefinder"], per_run["two cameras"]
    d_err = np.array([100 * (x["distances"].mean() - y["distances"].mean()) for x, y in zip(a, b)])
    d_mota = np.array([100 * (x["mot"].mota - y["mot"].mota) for x, y in zip(a, b)])
    diff_rows = []
    for label, d in (("mean_error_cm", d_err), ("mota_pct", d_mota)):
        half = 1.96 * float(d.std(ddof=1)) / np.sqrt(len(d)) if len(d) > 1 else float("inf")
        diff_rows.append(
            {"difference": label, "mean": float(d.mean()), "ci95_lo": d.mean() - half, "ci95_hi": d.mean() + half}
        )
    metrics["rangefinder_error_change_cm"] = diff_rows[0]["mean"]
    metrics["rangefinder_mota_change_pct"] = diff_rows[1]["mean"]
    metrics["rangefinder_lowers_mean_error"] = float(diff_rows[0]["ci95_hi"] < 0)
    metrics["rangefinder_raises_mota"] = float(diff_rows[1]["ci95_lo"] > 0)
    fig = _figure(cfg, example, per_run)
    own = stages.Stage(
        metrics=metrics,
        tables={"localisation": rows, "paired_differences": diff_rows},
        figures={"localisation": fig},
        notes=[
            f"{cfg.n_runs} scenes of {cfg.duration_s:g} s at {cfg.rate_hz:g} Hz, the same for both sensor sets; "
            "errors: distances of the CLEAR-MOT matches; intervals: paired over scenes, 95 %",
            "position NEES of the updated tracks against χ²(2): median (1.39 if consistent) and the share inside "
            "its 95 % interval (95 % if consistent); the mean is dominated by the few mis-associated tracks",
            "the scene, sensors and filter are assumed (the paper gives none of them): the paper's values are "
            "shown for reference, only the trends are claims",
        ],
    )
    return stages.merge(own)


def _figure(cfg: Config, example: dict, per_run: dict):
    plt = figures._plt()
    fig, axes = plt.subplots(1, 3, figsize=(18, 5))
    truth, est, upd = example["two cameras + rangefinder"]
    ax = axes[0]
    for i in range(cfg.n_objects):
        ax.plot(truth[:, i, 0], truth[:, i, 1], lw=0.7)
    sens = np.asarray(_sensor_positions(cfg))
    ax.plot(sens[:2, 0], sens[:2, 1], "ks", ms=9, label="cameras")
    ax.plot(sens[2, 0], sens[2, 1], "r^", ms=9, label="rangefinder")
    ax.set(title="run 0: object tracks", xlabel="x, m", ylabel="y, m", aspect="equal")
    ax.set_xlim(-0.3, cfg.width + 0.3)
    ax.set_ylim(-0.3, cfg.height + 0.3)
    ax = axes[1]
    for name, runs in per_run.items():
        d = np.sort(np.concatenate([s["distances"] for s in runs])) * 100
        ax.plot(d, np.arange(1, d.size + 1) / d.size, label=name)
    ax.set(title="localisation error", xlabel="error, cm", ylabel="fraction of matches ≤", xscale="log")
    ax = axes[2]
    t = np.arange(1, truth.shape[0] + 1) / cfg.rate_hz
    for name, (tr, es, up) in example.items():
        err = np.where(up, np.linalg.norm(tr - es, axis=-1), np.nan)
        ax.plot(t, 100 * np.nanmean(err, axis=1), lw=0.7, label=name)
    ax.set(title="run 0: mean error of the updated tracks", xlabel="t, s", ylabel="error, cm")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


STUDY = Study(
    name="mrr_localisation",
    description="Seed 000 paper 3: 10 objects tracked from two cameras (+ a rangefinder), CA Kalman filters, MOTA",
    config=Config,
    presets=PRESETS,
    claims=CLAIMS,
    assumptions=ASSUMPTIONS,
    run=run,
)
