"""Benchmark: gradients of the LQR gain for 10,000 (Q, R) weight sets.

Problem: the TRMS design model (7 states, 2 inputs, linearised at the pitch -0.05 rad hover),
weights ``Q = diag(q)``, ``R = diag(r)`` with ``log10 q ~ U(-1, 3)``, ``log10 r ~ U(-2, 1)``; for
every set the full Jacobian ``∂K/∂(q, r)`` (14 × 9 = 126 numbers).

* ours: ``jit(vmap(jacfwd(K)))`` — one CARE solve per set (matrix sign function + Newton–Kleinman)
  plus 9 tangent Lyapunov solves through the implicit derivative;
* peer: SciPy ``solve_continuous_are`` + central finite differences per set (relative step 1e-4,
  the most accurate of 1e-3…1e-6 here; 2·9 + 1 = 19 CARE
  solves per set), timed on a subset and extrapolated linearly to the full batch.

The two Jacobians are compared on the subset (max relative difference printed next to the timings).

Usage: ``python -m experiments.benchmarks.lqr_gradients [--n 10000] [--subset 50] [--repeats 3]``
"""

from __future__ import annotations

import argparse
import time

import jax
import jax.numpy as jnp
import numpy as np
import scipy.linalg as sl

import jaxsim  # noqa: F401  (float64)
from experiments.benchmarks.timing import median_time, write_json
from jaxsim.control.lqr import lqr
from jaxsim.plants.trms import FEEDBACK_MANUFACTURER, hover_equilibrium, linearize_at


def design_model() -> tuple[np.ndarray, np.ndarray]:
    x_eq, u_eq, _ = hover_equilibrium(FEEDBACK_MANUFACTURER, -0.05)
    lin = linearize_at(FEEDBACK_MANUFACTURER, x_eq, u_eq)
    return np.asarray(lin.a), np.asarray(lin.b)


def ours_fn(a: np.ndarray, b: np.ndarray):
    n = a.shape[0]

    def gain(w):
        return lqr(a, b, jnp.diag(w[:n]), jnp.diag(w[n:])).k

    return jax.jit(jax.vmap(jax.jacfwd(gain)))


def scipy_gain(a, b, w):
    n = a.shape[0]
    r = np.diag(w[n:])
    x = sl.solve_continuous_are(a, b, np.diag(w[:n]), r)
    return np.linalg.solve(r, b.T @ x)


def scipy_jacobian(a, b, w, rel_step=1e-4):
    cols = []
    for i in range(w.size):
        h = rel_step * w[i]
        e = np.zeros_like(w)
        e[i] = h
        cols.append((scipy_gain(a, b, w + e) - scipy_gain(a, b, w - e)) / (2 * h))
    scipy_gain(a, b, w)  # the value itself, which a user needs too
    return np.stack(cols, axis=-1)


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=10_000, help="number of (Q, R) sets")
    ap.add_argument("--subset", type=int, default=50, help="sets timed for SciPy + finite differences")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--json", default=None, help="write the numbers to this file")
    args = ap.parse_args(argv)

    a, b = design_model()
    n, m = b.shape
    rng = np.random.default_rng(0)
    w = np.concatenate([10 ** rng.uniform(-1, 3, (args.n, n)), 10 ** rng.uniform(-2, 1, (args.n, m))], axis=1)
    out = {"n": args.n, "states": n, "inputs": m, "devices": str(jax.devices())}

    fn = ours_fn(a, b)
    wj = jnp.asarray(w)
    start = time.perf_counter()
    jac = np.asarray(fn(wj).block_until_ready())
    out["ours_first_call_s"] = time.perf_counter() - start
    out["ours_s"] = median_time(lambda: fn(wj).block_until_ready(), args.repeats)
    out["ours_failed_sets"] = int(np.sum(~np.all(np.isfinite(jac), axis=(1, 2, 3))))

    idx = rng.choice(args.n, size=args.subset, replace=False)
    start = time.perf_counter()
    ref = np.stack([scipy_jacobian(a, b, w[i]) for i in idx])
    out["scipy_fd_s_extrapolated"] = (time.perf_counter() - start) / args.subset * args.n
    out["ratio"] = out["scipy_fd_s_extrapolated"] / out["ours_s"]
    scale = np.abs(ref).max(axis=(1, 2, 3), keepdims=True)
    out["max_rel_diff_vs_fd"] = float(np.max(np.abs(jac[idx] - ref) / scale))

    print(f"LQR gain Jacobians dK/d(q, r): {args.n} weight sets, n={n}, m={m}, devices {out['devices']}")
    print(
        f"  ours (jit+vmap+jacfwd, implicit):  {out['ours_s']:.3f} s median of {args.repeats} "
        f"(first call incl. compile {out['ours_first_call_s']:.2f} s), failed sets: {out['ours_failed_sets']}"
    )
    print(
        f"  SciPy CARE + central differences:  {out['scipy_fd_s_extrapolated']:.1f} s "
        f"(extrapolated from {args.subset} sets, 19 CARE solves each)"
    )
    print(
        f"  speed-up: {out['ratio']:.0f}x;  max relative difference of the Jacobians: {out['max_rel_diff_vs_fd']:.1e}"
    )
    write_json(args.json, out)
    return out


if __name__ == "__main__":
    main()
