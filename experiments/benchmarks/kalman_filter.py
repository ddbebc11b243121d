"""Benchmark: a 4-state / 2-measurement Kalman filter, 1,000 steps × 100,000 Monte-Carlo runs.

Model: planar constant-velocity target (state ``[x, vx, y, vy]``, ``dt = 1 s``, white-acceleration
process noise ``q = 0.1``), position measurements with ``σ = 1``.  Every run gets its own noise
draw; every implementation computes each run's total log-likelihood (so all do the same work:
filtered moments every step, one number per run kept).

Rows:

* ours, generic: ``jit(vmap(kalman_filter))`` (Joseph form, every run carries its own covariance),
  float64 and float32, the batch in chunks of ``--chunk`` runs, all ``--runs`` runs timed;
* ours, shared gain: :mod:`jaxsim.estimation.shared_gain` — the covariance recursion once, then
  only the means per run (exact for runs sharing the model and the measurement schedule);
* dynamax ``vmap(lgssm_filter)`` (float64; jitted; on ``--dynamax-runs`` runs, extrapolated);
* a NumPy filter vectorised over runs (per-run covariances, ``np.matmul`` on ``(N, 4, 4)`` stacks),
  and its shared-gain twin (on subsets, extrapolated);
* FilterPy ``KalmanFilter`` in a Python loop (``--filterpy-runs`` runs, extrapolated).

GFLOP/s = (analytic flop count of one filter step, a multiply-add counted as 2) × steps × runs /
wall time; it is printed next to the machine's measured matmul peak (median time of a
``2048 × 2048`` ``jnp.dot``, ``2n³`` flops).  Timings: median of ``--repeats`` runs after a warm-up.

Usage: ``python -m experiments.benchmarks.kalman_filter [--runs 100000] [--steps 1000] [--json F]``
(``XLA_FLAGS=--xla_force_host_platform_device_count=2`` to shard the batch over two CPU cores).
"""

from __future__ import annotations

import argparse
import json
import statistics
import time

import jax
import jax.numpy as jnp
import numpy as np

import jaxsim  # noqa: F401  (float64)
from experiments.benchmarks.closed_loop_pid import shard_batch
from jaxsim.estimation.lgssm import LinearGaussianSSM, kalman_filter, lgssm, sample
from jaxsim.estimation.shared_gain import covariance_sequence, mean_filter

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
    update = (2 * p * n + p          # r = y − H m
              + 2 * n * n * p        # P Hᵀ
              + 2 * p * n * p + p * p  # S = H (P Hᵀ) + R
              + p**3 // 3            # Cholesky of S
              + 2 * 2 * p * p * n    # K by two triangular solves with n right-hand sides
              + 2 * n * p + n        # m + K r
              + 2 * n * p * n + n    # I − K H
              + 2 * 2 * n**3         # (I − K H) P (I − K H)ᵀ
              + 2 * n * p * p + 2 * n * p * n + n * n  # + K R Kᵀ
              + 2 * n * n            # symmetrise
              + p * p + 2 * p + 10)  # whitened residual, NIS, log-likelihood
    predict = 2 * n * n + 2 * 2 * n**3 + n * n + 2 * n * n  # F m, F P Fᵀ, + Q, symmetrise
    return update + predict


def shared_step_flops(n: int = N_STATES, p: int = N_MEAS) -> int:
    """Flops of one mean-only step: r, m + K r, whitened r and its square, F m."""
    return (2 * p * n + p) + (2 * n * p + n) + (2 * p * p + 2 * p + 2) + 2 * n * n


def _median_time(fn, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def make_data(model: LinearGaussianSSM, runs: int, steps: int, chunk: int, seed: int = 0) -> list[jax.Array]:
    gen = jax.jit(jax.vmap(lambda k: sample(model, k, steps)[1]))
    keys = jax.random.split(jax.random.PRNGKey(seed), runs)
    return [gen(keys[i:i + chunk]).block_until_ready() for i in range(0, runs, chunk)]


def ours_generic(model: LinearGaussianSSM):
    return jax.jit(jax.vmap(lambda y: kalman_filter(model, y).log_likelihood))


def ours_shared(model: LinearGaussianSSM, steps: int):
    seq = covariance_sequence(model, steps)
    return jax.jit(jax.vmap(lambda y: mean_filter(model, seq, y, save_means=False).log_likelihood))


def run_chunks(fn, chunks) -> np.ndarray:
    outs = [fn(c) for c in chunks]
    return np.concatenate([np.asarray(o.block_until_ready()) for o in outs])


def dynamax_fn(model: LinearGaussianSSM):
    from dynamax.linear_gaussian_ssm.inference import lgssm_filter, make_lgssm_params

    params = make_lgssm_params(model.m0, model.P0, model.F, model.Q, model.H, model.R)
    return jax.jit(jax.vmap(lambda y: lgssm_filter(params, y).marginal_loglik))


def numpy_filter(model: LinearGaussianSSM, y: np.ndarray) -> np.ndarray:
    """Kalman filter vectorised over runs: ``y (N, T, p)``; per-run covariances ``(N, n, n)``."""
    F, Q, H, R = (np.asarray(v, float) for v in (model.F, model.Q, model.H, model.R))
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
    t = _median_time(lambda: dot(a, a).block_until_ready(), repeats)
    return 2 * size**3 / t / 1e9


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=100_000)
    ap.add_argument("--steps", type=int, default=1000)
    ap.add_argument("--chunk", type=int, default=10_000, help="runs per jitted call (memory bound)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--dynamax-runs", type=int, default=2000)
    ap.add_argument("--numpy-runs", type=int, default=2000)
    ap.add_argument("--filterpy-runs", type=int, default=3)
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    runs, steps = args.runs, args.steps
    chunk = min(args.chunk, runs)
    work = steps * runs
    out: dict = {"runs": runs, "steps": steps, "chunk": chunk, "devices": str(jax.devices()),
                 "flops_per_step_generic": generic_step_flops(), "flops_per_step_shared": shared_step_flops()}

    model64, model32 = cv_model(jnp.float64), cv_model(jnp.float32)
    chunks64 = [shard_batch(c, jnp.float64) for c in make_data(model64, runs, steps, chunk)]
    ref_y = np.asarray(chunks64[0][: max(args.dynamax_runs, args.numpy_runs, args.filterpy_runs)])

    results: dict[str, float] = {}
    lls: dict[str, np.ndarray] = {}

    def time_ours(name, fn, chunks):
        start = time.perf_counter()
        lls[name] = run_chunks(fn, chunks[:1])
        out[f"{name}_first_call_s"] = time.perf_counter() - start
        results[name] = _median_time(lambda: run_chunks(fn, chunks), args.repeats)
        lls[name] = run_chunks(fn, chunks[:1])

    time_ours("ours_generic_f64", ours_generic(model64), chunks64)
    time_ours("ours_shared_f64", ours_shared(model64, steps), chunks64)
    chunks32 = [c.astype(jnp.float32) for c in chunks64]
    time_ours("ours_generic_f32", ours_generic(model32), chunks32)
    time_ours("ours_shared_f32", ours_shared(model32, steps), chunks32)
    del chunks32

    try:
        dyn = dynamax_fn(model64)
        sub = jnp.asarray(ref_y[: args.dynamax_runs])
        lls["dynamax"] = np.asarray(dyn(sub).block_until_ready())
        results["dynamax"] = _median_time(lambda: dyn(sub).block_until_ready(), args.repeats) * runs / args.dynamax_runs
    except ImportError:
        out["dynamax"] = "not installed"

    sub = ref_y[: args.numpy_runs]
    lls["numpy_generic"] = numpy_filter(model64, sub)
    results["numpy_generic"] = _median_time(lambda: numpy_filter(model64, sub), max(1, args.repeats - 1)) \
        * runs / args.numpy_runs
    lls["numpy_shared"] = numpy_shared(model64, sub)
    results["numpy_shared"] = _median_time(lambda: numpy_shared(model64, sub), max(1, args.repeats - 1)) \
        * runs / args.numpy_runs

    start = time.perf_counter()
    lls["filterpy"] = np.array([filterpy_loglik(model64, ref_y[i]) for i in range(args.filterpy_runs)])
    results["filterpy"] = (time.perf_counter() - start) * runs / args.filterpy_runs

    ref = lls["ours_generic_f64"]
    out["max_rel_loglik_diff_vs_ours_f64"] = {
        k: float(np.max(np.abs(v - ref[: len(v)]) / np.abs(ref[: len(v)]))) for k, v in lls.items()}
    peak64, peak32 = matmul_peak(jnp.float64), matmul_peak(jnp.float32)
    out["matmul_peak_gflops_f64"], out["matmul_peak_gflops_f32"] = peak64, peak32
    out["seconds"] = results
    base = results["ours_generic_f64"]
    print(f"Kalman filter 4×2, {steps} steps × {runs} runs, devices {out['devices']} "
          f"(peers extrapolated from subsets; median of {args.repeats})")
    print(f"{'implementation':<26}{'wall s':>12}{'× ours f64':>12}{'GFLOP/s':>10}{'rel. ll diff':>14}")
    for name, sec in results.items():
        flops = shared_step_flops() if "shared" in name else generic_step_flops()
        gflops = flops * work / sec / 1e9
        diff = out["max_rel_loglik_diff_vs_ours_f64"].get(name, float("nan"))
        print(f"{name:<26}{sec:>12.3f}{sec / base:>12.2f}{gflops:>10.2f}{diff:>14.1e}")
    print(f"speed-ups: ours generic f64 vs FilterPy {results['filterpy'] / base:.0f}×, "
          f"vs NumPy vectorised {results['numpy_generic'] / base:.1f}×"
          + (f", vs dynamax {results['dynamax'] / base:.1f}×" if "dynamax" in results else ""))
    best = min(v for k, v in results.items() if k.startswith("ours"))
    print(f"           best of ours ({min((v, k) for k, v in results.items() if k.startswith('ours'))[1]}) "
          f"vs FilterPy {results['filterpy'] / best:.0f}×"
          + (f", vs dynamax {results['dynamax'] / best:.0f}×" if "dynamax" in results else ""))
    print(f"matmul peak (2048² jnp.dot): {peak64:.1f} GFLOP/s float64, {peak32:.1f} GFLOP/s float32; "
          f"flops/step: generic {generic_step_flops()}, shared-gain {shared_step_flops()}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(out, fh, indent=2)
    return out


if __name__ == "__main__":
    main()
