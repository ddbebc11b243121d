"""Benchmark: a 4-state / 2-measurement Kalman filter, 1,000 steps × 100,000 Monte-Carlo runs.

Model: planar constant-velocity target (state ``[x, vx, y, vy]``, ``dt = 1 s``, white-acceleration
process noise ``q = 0.1``), position measurements with ``σ = 1``.  Every run gets its own noise
draw (generated in float64, cast for the float32 rows); every implementation computes each run's
total log-likelihood, so all do the same filtering work and keep one number per run.

Two scenarios:

* ``shared_model`` (the issue's benchmark): all runs share the model.  The covariance recursion
  does not depend on the data, and ``vmap`` leaves it unbatched — JAX computes it once per step
  for all runs (dynamax's ``vmap`` gets the same benefit); :mod:`jaxsim.estimation.shared_gain`
  does it explicitly, and :func:`~jaxsim.estimation.batched.batched_kalman_loglik` (the
  ``ours_shared_gain`` rows) runs the covariances once per call — only until they reach their
  fixed point (about 50 steps for this model; tested at step 128), after which every step shares
  one gain — and advances the means of all runs 8 steps per GEMM (affine block maps).  Rows: ours
  ``jit(vmap(kalman_filter))`` (Joseph form) and batched, in float64 and float32, and dynamax
  ``jit(vmap(lgssm_filter))`` (float64), all on every run in chunks of ``--chunk`` runs;
  a NumPy filter vectorised over runs (per-run covariance stacks) and its shared-gain twin;
  FilterPy's ``KalmanFilter`` in a Python loop.
* ``per_run_model``: run ``i`` uses ``R·sᵢ`` (``sᵢ`` log-uniform in [0.5, 2]), so every run carries
  its own covariance recursion (a sweep over a model parameter).  Rows: ours (vmap, and batched with
  ``r_scale``: the covariance recursions batched with the runs on the fast axis), dynamax, NumPy.

NumPy and FilterPy run on subsets (``--numpy-runs``, ``--filterpy-runs``: the first runs of the
first chunk) and are extrapolated linearly to all runs.  GFLOP/s = analytic flops of the
work done (one Joseph-form step = :func:`generic_step_flops` per run and step; in the shared
scenario the vmapped/shared-gain rows do :func:`shared_step_flops` per run and step plus one
covariance step per step), a multiply-add counted as 2 — divided by the wall time; printed next
to the machine's matmul peak measured as the median time of a ``2048 × 2048`` ``jnp.dot``
(``2n³`` flops).  Timings: median of ``--repeats`` after a compiling call.

``--chunks 100,500,2000`` instead times only dynamax, ours ``vmap`` and ours batched, one chunk of
each size, in interleaved rounds (median of ``--repeats``), and prints the speed-up over dynamax, the
log-likelihoods' largest relative difference from dynamax's exact filter (its ``1e-9·I`` boost of
``S`` switched off) and each row as a fraction of the machine's roofline: GFLOP/s of the analytic
flops against the measured matmul peak, and GB/s of the minimum traffic (one read of ``ys``) against
a measured streaming ``2·x`` bandwidth.  The load average is printed: timings on a shared machine move
with it.

Usage: ``python -m experiments.benchmarks.kalman_filter [--runs 100000] [--steps 1000] [--json F]``;
``python -m experiments.benchmarks.kalman_filter --chunks 100,500,2000 --repeats 7``
(``XLA_FLAGS=--xla_force_host_platform_device_count=2`` shards each chunk over two CPU devices).
"""

from __future__ import annotations

import argparse
import functools
import time

import jax
import jax.numpy as jnp
import numpy as np

import jaxsim  # noqa: F401  (float64)
from experiments.benchmarks.closed_loop_pid import shard_batch
from experiments.benchmarks.timing import median_time, write_json
from jaxsim.core.pytree import replace
from jaxsim.estimation.batched import batched_kalman_loglik
from jaxsim.estimation.lgssm import LinearGaussianSSM, kalman_filter, lgssm, sample

N_STATES, N_MEAS = 4, 2


def cv_model(dtype=jnp.float64) -> LinearGaussianSSM:
    dt, q, sigma = 1.0, 0.1, 1.0
    f1 = np.array([[1.0, dt], [0.0, 1.0]])
    q1 = q * np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]])
    F, Q = np.kron(np.eye(2), f1), np.kron(np.eye(2), q1)
    H = np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0]])
    m = lgssm(F, Q, H, sigma**2 * np.eye(2), np.zeros(4), np.diag([100.0, 10.0, 100.0, 10.0]))
    return jax.tree_util.tree_map(lambda a: jnp.asarray(a, dtype), m)


def generic_step_flops(n: int = N_STATES, p: int = N_MEAS) -> int:
    """Analytic flops of one Joseph-form update + predict (multiply-add = 2 flops)."""
    update = (
        2 * p * n
        + p  # r = y − H m
        + 2 * n * n * p  # P Hᵀ
        + 2 * p * n * p
        + p * p  # S = H (P Hᵀ) + R
        + p**3 // 3  # Cholesky of S
        + 2 * 2 * p * p * n  # K by two triangular solves with n right-hand sides
        + 2 * n * p
        + n  # m + K r
        + 2 * n * p * n
        + n  # I − K H
        + 2 * 2 * n**3  # (I − K H) P (I − K H)ᵀ
        + 2 * n * p * p
        + 2 * n * p * n
        + n * n  # + K R Kᵀ
        + 2 * n * n  # symmetrise
        + p * p
        + 2 * p
        + 10
    )  # whitened residual, NIS, log-likelihood
    predict = 2 * n * n + 2 * 2 * n**3 + n * n + 2 * n * n  # F m, F P Fᵀ, + Q, symmetrise
    return update + predict


def shared_step_flops(n: int = N_STATES, p: int = N_MEAS) -> int:
    """Flops of one mean-only step: r, m + K r, whitened r and its square, F m."""
    return (2 * p * n + p) + (2 * n * p + n) + (2 * p * p + 2 * p + 2) + 2 * n * n


def data_chunk(index: int, chunk: int, steps: int, dtype) -> jax.Array:
    """Measurements ``(chunk, steps, 2)`` of runs ``index·chunk …``, drawn in float64 from the
    shared model and cast to ``dtype`` (the same draws for every implementation and dtype)."""
    keys = jax.random.split(jax.random.fold_in(jax.random.PRNGKey(0), index), chunk)
    y = _generate(cv_model(jnp.float64), keys, steps)
    return shard_batch(np.asarray(y), dtype)


@functools.partial(jax.jit, static_argnums=2)
def _generate(model, keys, steps):
    return jax.vmap(lambda k: sample(model, k, steps)[1])(keys)


def run_scales(runs: int) -> np.ndarray:
    """Per-run measurement-noise scale factors of the per-run-model scenario, in [0.5, 2]."""
    return np.exp(np.random.default_rng(1).uniform(np.log(0.5), np.log(2.0), runs))


def ours_generic(model: LinearGaussianSSM):
    """vmap over measurement sequences (the covariance recursion is unbatched: shared by all runs)."""
    return jax.jit(jax.vmap(lambda y: kalman_filter(model, y).log_likelihood))


def ours_per_run(model: LinearGaussianSSM):
    """vmap over (measurements, R scale): every run carries its own covariance recursion."""
    return jax.jit(jax.vmap(lambda y, s: kalman_filter(replace(model, R=model.R * s), y).log_likelihood))


def ours_shared(model: LinearGaussianSSM, steps: int | None = None):
    """:func:`~jaxsim.estimation.batched.batched_kalman_loglik`: covariances once per call, the means
    of all runs 8 steps per GEMM (``steps`` unused: kept for callers)."""
    return jax.jit(lambda y: batched_kalman_loglik(model, y))


def ours_batched_per_run(model: LinearGaussianSSM):
    """:func:`~jaxsim.estimation.batched.batched_kalman_loglik` with ``r_scale``: per-run covariance
    recursions, batched with the runs on the fast axis."""
    return jax.jit(lambda y, s: batched_kalman_loglik(model, y, r_scale=s))


def time_sweep(fn, runs, chunk, steps, dtype, repeats, scales=None) -> tuple[float, np.ndarray, float]:
    """Median wall time of ``fn`` over all runs (chunk by chunk, data generation not timed), the
    log-likelihoods of the first chunk, and the first (compiling) call's time."""
    total, first_ll, first_call = 0.0, None, 0.0
    for i in range(-(-runs // chunk)):
        y = data_chunk(i, chunk, steps, dtype)
        args = (y,) if scales is None else (y, jnp.asarray(scales[i * chunk : (i + 1) * chunk], dtype))
        if i == 0:
            start = time.perf_counter()
            first_ll = np.asarray(fn(*args).block_until_ready())
            first_call = time.perf_counter() - start
        total += median_time(lambda: fn(*args).block_until_ready(), repeats)
    return total, first_ll, first_call


def dynamax_fn(model: LinearGaussianSSM, per_run: bool = False):
    from dynamax.linear_gaussian_ssm.inference import lgssm_filter, make_lgssm_params

    # importing dynamax sets JAX's global default matmul precision; the kernels timed beside it keep JAX's default
    jax.config.update("jax_default_matmul_precision", None)

    def ll(y, s=1.0):
        params = make_lgssm_params(model.m0, model.P0, model.F, model.Q, model.H, model.R * s)
        return lgssm_filter(params, y).marginal_loglik

    return jax.jit(jax.vmap(ll) if per_run else jax.vmap(lambda y: ll(y)))


def dynamax_exact_loglik(model: LinearGaussianSSM, y, scales=None) -> np.ndarray:
    """dynamax's log-likelihoods with its ``1e-9·I`` boost of ``S`` in the gain solve switched off (the
    exact filter, for the 1e-10 equality check; the boost alone moves per-run log-likelihoods by
    ~3e-10 relative on this model)."""
    import dynamax.linear_gaussian_ssm.inference as dyn
    from dynamax.utils.utils import psd_solve

    orig = dyn.psd_solve
    dyn.psd_solve = functools.partial(psd_solve, diagonal_boost=0.0)
    try:  # traced (and so patched) on this call only
        fn = dynamax_fn(model, per_run=scales is not None)
        return np.asarray(fn(y) if scales is None else fn(y, scales))
    finally:
        dyn.psd_solve = orig
        jax.config.update("jax_default_matmul_precision", None)


def stream_bandwidth(n_bytes: int = 256 * 2**20, repeats: int = 5) -> float:
    """GB/s of a streaming ``y = 2·x`` over ``n_bytes`` of float64 (bytes read + bytes written, median)."""
    x = jnp.ones((n_bytes // 8,), jnp.float64)
    scale = jax.jit(lambda a: 2.0 * a)
    scale(x).block_until_ready()
    return 2 * n_bytes / median_time(lambda: scale(x).block_until_ready(), repeats) / 1e9


def chunk_sweep(chunks, steps: int, rounds: int) -> dict:
    """For each chunk size: dynamax, ours ``vmap(kalman_filter)`` and ours batched, in both scenarios,
    timed in interleaved rounds (median), with ratios vs dynamax and fractions of the machine's FLOP
    and bandwidth roofline.  The minimum memory traffic is one read of ``ys`` (plus the scales and
    the output), the flops are the analytic counts used by :func:`main`."""
    import os

    model = cv_model(jnp.float64)
    peak, bw = matmul_peak(jnp.float64), stream_bandwidth()
    out: dict = {"matmul_peak_gflops_f64": peak, "stream_gbs": bw, "load_average": os.getloadavg(), "chunks": {}}
    print(f"Kalman filter 4 states / 2 measurements, {steps} steps; interleaved rounds: median of {rounds}")
    print(
        f"roofline: matmul peak {peak:.1f} GFLOP/s (f64, 2048² jnp.dot); streaming copy {bw:.1f} GB/s; "
        f"load average {out['load_average'][0]:.2f}"
    )
    for chunk in chunks:
        y = data_chunk(0, chunk, steps, jnp.float64)
        s = jnp.asarray(run_scales(chunk), jnp.float64)
        fns = {
            ("shared", "dynamax"): (dynamax_fn(model), (y,)),
            ("shared", "ours_vmap"): (ours_generic(model), (y,)),
            ("shared", "ours_batched"): (ours_shared(model), (y,)),
            ("per_run", "dynamax"): (dynamax_fn(model, per_run=True), (y, s)),
            ("per_run", "ours_vmap"): (ours_per_run(model), (y, s)),
            ("per_run", "ours_batched"): (ours_batched_per_run(model), (y, s)),
        }
        lls = {k: np.asarray(f(*a)) for k, (f, a) in fns.items()}  # compiles
        exact = {"shared": dynamax_exact_loglik(model, y), "per_run": dynamax_exact_loglik(model, y, s)}
        times: dict = {k: [] for k in fns}
        for _ in range(rounds):
            for k, (f, a) in fns.items():
                start = time.perf_counter()
                f(*a).block_until_ready()
                times[k].append(time.perf_counter() - start)
        med = {k: float(np.median(v)) for k, v in times.items()}
        print(
            f"\n[{chunk} runs]  {'ms':>9}{'× dynamax':>11}{'GFLOP/s':>9}{'% peak':>8}{'GB/s':>7}{'% bw':>7}"
            f"{'rel Δ vs dynamax (exact)':>26}"
        )
        row: dict = {}
        for (scen, name), sec in med.items():
            work = chunk * steps
            if scen == "shared":
                flops = shared_step_flops() * work + generic_step_flops() * steps
            else:
                flops = generic_step_flops() * work
            n_bytes = y.size * 8 + chunk * 8 * (2 if scen == "per_run" else 1)
            ref = exact[scen]
            diff = float(np.max(np.abs(lls[(scen, name)] - ref) / np.abs(ref)))
            ratio = med[(scen, "dynamax")] / sec
            row[f"{scen}/{name}"] = {
                "seconds": sec,
                "x_dynamax": ratio,
                "gflops": flops / sec / 1e9,
                "peak_fraction": flops / sec / 1e9 / peak,
                "gbs": n_bytes / sec / 1e9,
                "bandwidth_fraction": n_bytes / sec / 1e9 / bw,
                "max_rel_diff": diff,
            }
            r = row[f"{scen}/{name}"]
            print(
                f"  {scen + '/' + name:<22}{sec * 1e3:>9.2f}{ratio:>11.2f}{r['gflops']:>9.2f}"
                f"{100 * r['peak_fraction']:>7.1f}%{r['gbs']:>7.2f}{100 * r['bandwidth_fraction']:>6.1f}%{diff:>26.1e}"
            )
        out["chunks"][chunk] = row
    out["load_average_end"] = os.getloadavg()
    print(f"\nload average at the end {out['load_average_end'][0]:.2f}")
    return out


def numpy_filter(model: LinearGaussianSSM, y: np.ndarray, scales: np.ndarray | None = None) -> np.ndarray:
    """Kalman filter vectorised over runs: ``y (N, T, p)``; per-run covariances ``(N, n, n)``
    (per-run ``R·scales[i]`` if given)."""
    F, Q, H, R = (np.asarray(v, float) for v in (model.F, model.Q, model.H, model.R))
    if scales is not None:
        R = R[None] * np.asarray(scales)[:, None, None]
    n_runs, steps, p = y.shape
    n = F.shape[0]
    m = np.broadcast_to(np.asarray(model.m0, float), (n_runs, n)).copy()
    P = np.broadcast_to(np.asarray(model.P0, float), (n_runs, n, n)).copy()
    eye, ll = np.eye(n), np.zeros(n_runs)
    for t in range(steps):
        r = y[:, t] - m @ H.T
        PHt = P @ H.T
        S = H @ PHt + R
        S_inv = np.linalg.inv(S)
        K = PHt @ S_inv
        m = m + np.einsum("nij,nj->ni", K, r)
        IKH = eye - K @ H
        P = IKH @ P @ IKH.transpose(0, 2, 1) + K @ R @ K.transpose(0, 2, 1)
        ll -= 0.5 * (np.einsum("ni,nij,nj->n", r, S_inv, r) + np.linalg.slogdet(S)[1] + p * np.log(2 * np.pi))
        m = m @ F.T
        P = F @ P @ F.T + Q
    return ll


def numpy_shared(model: LinearGaussianSSM, y: np.ndarray) -> np.ndarray:
    """Shared-gain NumPy filter: one covariance recursion, then ``(N, n)`` mean updates."""
    F, Q, H, R = (np.asarray(v, float) for v in (model.F, model.Q, model.H, model.R))
    n_runs, steps, p = y.shape
    P = np.asarray(model.P0, float)
    m = np.broadcast_to(np.asarray(model.m0, float), (n_runs, F.shape[0])).copy()
    ll = np.zeros(n_runs)
    for t in range(steps):
        S = H @ P @ H.T + R
        L = np.linalg.cholesky(S)
        K = np.linalg.solve(S, H @ P).T
        r = y[:, t] - m @ H.T
        z = np.linalg.solve(L, r.T).T
        ll -= 0.5 * (np.sum(z * z, axis=1) + 2 * np.sum(np.log(np.diag(L))) + p * np.log(2 * np.pi))
        m = (m + r @ K.T) @ F.T
        IKH = np.eye(F.shape[0]) - K @ H
        P = F @ (IKH @ P @ IKH.T + K @ R @ K.T) @ F.T + Q
    return ll


def filterpy_loglik(model: LinearGaussianSSM, y: np.ndarray) -> float:
    from filterpy.kalman import KalmanFilter

    kf = KalmanFilter(dim_x=N_STATES, dim_z=N_MEAS)
    kf.F, kf.Q, kf.H, kf.R = (np.asarray(v, float) for v in (model.F, model.Q, model.H, model.R))
    kf.x, kf.P = np.asarray(model.m0, float)[:, None].copy(), np.asarray(model.P0, float).copy()
    total = 0.0
    for t in range(y.shape[0]):
        kf.update(y[t][:, None])
        total += kf.log_likelihood
        kf.predict()
    return total


def matmul_peak(dtype, size: int = 2048, repeats: int = 3) -> float:
    """GFLOP/s of a ``size × size`` ``jnp.dot`` (median of ``repeats``), the machine's practical peak."""
    a = jax.random.normal(jax.random.PRNGKey(0), (size, size), dtype=dtype)
    dot = jax.jit(jnp.dot)
    dot(a, a).block_until_ready()
    t = median_time(lambda: dot(a, a).block_until_ready(), repeats)
    return 2 * size**3 / t / 1e9


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=100_000)
    ap.add_argument("--steps", type=int, default=1000)
    ap.add_argument("--chunk", type=int, default=2000, help="runs per jitted call (JAX rows, dynamax too)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--numpy-runs", type=int, default=1000)
    ap.add_argument("--filterpy-runs", type=int, default=3)
    ap.add_argument("--json", default=None)
    ap.add_argument(
        "--chunks",
        default=None,
        help="comma-separated chunk sizes (e.g. 100,500,2000): only the dynamax / ours_vmap / ours_batched "
        "comparison per chunk size, interleaved rounds (--repeats), roofline fractions",
    )
    args = ap.parse_args(argv)
    if args.chunks:
        out = chunk_sweep([int(c) for c in args.chunks.split(",")], args.steps, args.repeats)
        write_json(args.json, out)
        return out
    runs, steps = args.runs, args.steps
    chunk = min(args.chunk, runs)
    work = steps * runs
    n_sub = max(args.numpy_runs, args.filterpy_runs)
    if n_sub > chunk:
        ap.error(f"the peers' subsets ({n_sub} runs) must fit in one chunk ({chunk})")
    out: dict = {
        "runs": runs,
        "steps": steps,
        "chunk": chunk,
        "devices": str(jax.devices()),
        "flops_per_step_generic": generic_step_flops(),
        "flops_per_step_shared": shared_step_flops(),
    }
    model64, model32 = cv_model(jnp.float64), cv_model(jnp.float32)
    scales = run_scales(runs)
    sub_y = np.asarray(data_chunk(0, chunk, steps, jnp.float64))[:n_sub]  # the first runs of chunk 0
    seconds: dict[str, dict[str, float]] = {"shared_model": {}, "per_run_model": {}}
    lls: dict[str, dict[str, np.ndarray]] = {"shared_model": {}, "per_run_model": {}}

    def ours(scenario, name, fn, dtype, with_scales=False):  # all runs, chunk by chunk
        t, ll, first = time_sweep(fn, runs, chunk, steps, dtype, args.repeats, scales if with_scales else None)
        seconds[scenario][name], lls[scenario][name] = t, ll
        out[f"{scenario}/{name}_first_call_s"] = first

    def peer(scenario, name, fn, n):
        lls[scenario][name] = np.asarray(fn())
        seconds[scenario][name] = median_time(fn, args.repeats) * runs / n

    # --- scenario 1: all runs share the model (the benchmark) --------------------------
    ours("shared_model", "ours_vmap_f64", ours_generic(model64), jnp.float64)
    ours("shared_model", "ours_vmap_f32", ours_generic(model32), jnp.float32)
    ours("shared_model", "ours_shared_gain_f64", ours_shared(model64, steps), jnp.float64)
    ours("shared_model", "ours_shared_gain_f32", ours_shared(model32, steps), jnp.float32)
    try:
        ours("shared_model", "dynamax_vmap_f64", dynamax_fn(model64), jnp.float64)
    except ImportError:
        out["dynamax"] = "not installed"
    y_np = sub_y[: args.numpy_runs]
    peer("shared_model", "numpy_vectorised", lambda: numpy_filter(model64, y_np), args.numpy_runs)
    peer("shared_model", "numpy_shared_gain", lambda: numpy_shared(model64, y_np), args.numpy_runs)
    start = time.perf_counter()
    lls["shared_model"]["filterpy_loop"] = np.array(
        [filterpy_loglik(model64, sub_y[i]) for i in range(args.filterpy_runs)]
    )
    seconds["shared_model"]["filterpy_loop"] = (time.perf_counter() - start) * runs / args.filterpy_runs

    # --- scenario 2: every run has its own R (a sweep over a model parameter) -------------------
    ours("per_run_model", "ours_vmap_f64", ours_per_run(model64), jnp.float64, True)
    ours("per_run_model", "ours_vmap_f32", ours_per_run(model32), jnp.float32, True)
    ours("per_run_model", "ours_batched_f64", ours_batched_per_run(model64), jnp.float64, True)
    if "dynamax" not in out:
        ours("per_run_model", "dynamax_vmap_f64", dynamax_fn(model64, per_run=True), jnp.float64, True)
    peer(
        "per_run_model",
        "numpy_vectorised",
        lambda: numpy_filter(model64, y_np, scales[: args.numpy_runs]),
        args.numpy_runs,
    )

    peak64, peak32 = matmul_peak(jnp.float64), matmul_peak(jnp.float32)
    out.update(matmul_peak_gflops_f64=peak64, matmul_peak_gflops_f32=peak32, seconds=seconds)
    print(f"Kalman filter 4 states / 2 measurements, {steps} steps × {runs} runs; devices {out['devices']}")
    print(
        f"(NumPy and FilterPy timed on subsets and extrapolated linearly; medians of {args.repeats}; "
        f"matmul peak {peak64:.1f} GFLOP/s f64, {peak32:.1f} GFLOP/s f32 — 2048² jnp.dot)"
    )
    for scenario, rows in seconds.items():
        ref_ll = lls[scenario]["ours_vmap_f64"]
        base = rows["ours_vmap_f64"]
        print(f"\n[{scenario}]  {'wall s':>10}{'× ours f64':>12}{'GFLOP/s':>10}{'max rel. Δ loglik':>19}")
        for name, sec in rows.items():
            if (
                scenario == "shared_model"
                and not name.startswith("numpy_vectorised")
                and not name.startswith("filterpy")
            ):
                flops = shared_step_flops() * work + generic_step_flops() * steps  # covariances once
            else:
                flops = generic_step_flops() * work
            v = lls[scenario][name]
            diff = float(np.max(np.abs(v - ref_ll[: len(v)]) / np.abs(ref_ll[: len(v)])))
            out[f"{scenario}/{name}_gflops"] = flops / sec / 1e9
            out[f"{scenario}/{name}_max_rel_loglik_diff"] = diff
            print(f"  {name:<24}{sec:>10.3f}{sec / base:>12.2f}{flops / sec / 1e9:>10.2f}{diff:>19.1e}")
        ratios = {k: v / base for k, v in rows.items() if not k.startswith("ours")}
        out[f"{scenario}/ratios_vs_ours_f64"] = ratios
        print("  speed-up of ours (vmap, float64): " + ", ".join(f"{v:.1f}× vs {k}" for k, v in ratios.items()))
    write_json(args.json, out)
    return out


if __name__ == "__main__":
    main()
