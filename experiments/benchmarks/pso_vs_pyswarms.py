"""Benchmark: particle swarm on a closed-loop PID loss, ours (JAX) vs pyswarms — 64 particles × 100 iterations.

The loss is :class:`optim.problems.PIDTuning`'s: the PID of the fuzzy-PID paper's static plant
``2/((0.1s+1)(0.5s+1))``, sampled at 10 ms with 2 RK4 substeps, ``J = ∫ e² + 0.01 u² dt`` over 3 s
(300 ticks), gains in the box ``[0, 20] × [0, 20] × [0, 2]``.  Both swarms use the same settings:
global best, ``c1 = c2 = 1.5``, inertia 0.9 → 0.4 (pyswarms' ``lin_variation``), velocity clamp
±0.5·range, reflecting bounds.

* ours: :func:`optim.pso.pso` — the swarm evaluated by one jitted ``vmap`` of the rollout per
  iteration (wall time without compilation; compile time printed separately);
* pyswarms + NumPy: pyswarms hands the objective the whole ``(64, 3)`` position matrix; the
  objective steps the same sampled-data loop in NumPy, vectorised over the 64 particles (a Python
  loop over the 300 ticks and 2 RK4 substeps, NumPy arrays of 64 inside — the fastest plain-NumPy
  formulation, far faster than a per-particle loop);
* pyswarms + Python loop (``--python-loop``): the objective loops over the particles in plain
  Python floats, as a per-particle objective is usually written; timed on 2 iterations and
  extrapolated to 100;
* pyswarms + our loss: pyswarms calling our jitted batched loss ``jit(vmap(loss))`` — isolates
  pyswarms' own per-iteration overhead from the simulation cost.

All timings are medians of ``--repeats`` runs, the variants taking turns in every round; ratios are
pyswarms time / ours.
Usage: ``python -m experiments.benchmarks.pso_vs_pyswarms [--repeats 3] [--python-loop] [--json out.json]``
"""

from __future__ import annotations

import argparse
import logging
import statistics
import time

import jax
import jax.numpy as jnp
import numpy as np

import jaxsim  # noqa: F401  (float64)
from experiments.benchmarks.timing import write_json
from optim.problems import PIDTuning
from optim.pso import pso

N_PARTICLES, N_ITERS = 64, 100
OPTIONS = {"c1": 1.5, "c2": 1.5, "w": 0.9}


def numpy_swarm_loss(problem: PIDTuning, gains: np.ndarray) -> np.ndarray:
    """The problem's loss for every row of ``gains`` ``(n, 3)``, stepped in NumPy over the swarm."""
    kp, ki, kd = gains[:, 0], gains[:, 1], gains[:, 2]
    n = gains.shape[0]
    K, T1, T2, tf, ts, rho, r = (
        problem.K,
        problem.T1,
        problem.T2,
        problem.tf,
        problem.ts,
        problem.rho,
        problem.reference,
    )
    h = ts / problem.substeps
    y, v = np.zeros(n), np.zeros(n)
    integ, deriv, prev = np.zeros(n), np.zeros(n), np.zeros(n)
    cost = np.zeros(n)

    def f(y, v, u):
        return v, (K * u - y - (T1 + T2) * v) / (T1 * T2)

    for _ in range(problem.n_ticks):
        e = r - y
        sig = -y
        deriv = (tf * deriv + (sig - prev)) / (tf + ts)
        u = kp * e + integ + kd * deriv
        cost += (e * e + rho * u * u) * ts
        integ = integ + ts * ki * e
        prev = sig
        for _ in range(problem.substeps):
            k1y, k1v = f(y, v, u)
            k2y, k2v = f(y + 0.5 * h * k1y, v + 0.5 * h * k1v, u)
            k3y, k3v = f(y + 0.5 * h * k2y, v + 0.5 * h * k2v, u)
            k4y, k4v = f(y + h * k3y, v + h * k3v, u)
            y = y + h / 6 * (k1y + 2 * k2y + 2 * k3y + k4y)
            v = v + h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
    return cost


def python_particle_loss(problem: PIDTuning, g: np.ndarray) -> float:
    """The same loss for one gain vector in plain Python floats."""
    kp, ki, kd = (float(v) for v in g)
    K, T1, T2, tf, ts, rho, r = (
        problem.K,
        problem.T1,
        problem.T2,
        problem.tf,
        problem.ts,
        problem.rho,
        problem.reference,
    )
    h = ts / problem.substeps
    y = v = integ = deriv = prev = cost = 0.0
    for _ in range(problem.n_ticks):
        e = r - y
        sig = -y
        deriv = (tf * deriv + (sig - prev)) / (tf + ts)
        u = kp * e + integ + kd * deriv
        cost += (e * e + rho * u * u) * ts
        integ += ts * ki * e
        prev = sig
        for _ in range(problem.substeps):
            a1 = (K * u - y - (T1 + T2) * v) / (T1 * T2)
            y2, v2 = y + 0.5 * h * v, v + 0.5 * h * a1
            a2 = (K * u - y2 - (T1 + T2) * v2) / (T1 * T2)
            y3, v3 = y + 0.5 * h * v2, v + 0.5 * h * a2
            a3 = (K * u - y3 - (T1 + T2) * v3) / (T1 * T2)
            y4, v4 = y + h * v3, v + h * a3
            a4 = (K * u - y4 - (T1 + T2) * v4) / (T1 * T2)
            y, v = y + h / 6 * (v + 2 * v2 + 2 * v3 + v4), v + h / 6 * (a1 + 2 * a2 + 2 * a3 + a4)
    return cost


def run_pyswarms(objective, lo, hi, iters: int, seed: int):
    import pyswarms as ps

    np.random.seed(seed)
    opt = ps.single.GlobalBestPSO(
        N_PARTICLES,
        3,
        options=dict(OPTIONS),
        bounds=(lo, hi),
        oh_strategy={"w": "lin_variation"},
        bh_strategy="reflective",
        velocity_clamp=(-0.5 * (hi - lo), 0.5 * (hi - lo)),
    )
    t0 = time.perf_counter()
    cost, pos = opt.optimize(objective, iters, verbose=False)
    return time.perf_counter() - t0, float(cost), pos


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--python-loop", action="store_true", help="also time a per-particle Python loop")
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    logging.getLogger("pyswarms").setLevel(logging.WARNING)
    problem = PIDTuning()
    lo, hi = problem.box
    out: dict = {
        "n_particles": N_PARTICLES,
        "n_iters": N_ITERS,
        "n_ticks": problem.n_ticks,
        "devices": str(jax.devices()),
    }

    check = np.random.default_rng(0).uniform(lo, hi, (8, 3))
    ref = np.asarray(jax.vmap(problem.loss)(jnp.asarray(check)))
    out["numpy_loss_rel_diff"] = float(np.max(np.abs(numpy_swarm_loss(problem, check) - ref) / ref))
    batched = jax.jit(jax.vmap(problem.loss))
    batched(jnp.asarray(check)).block_until_ready()
    jax_objective = lambda x: np.asarray(batched(jnp.asarray(x)))  # noqa: E731
    numpy_objective = lambda x: numpy_swarm_loss(problem, x)  # noqa: E731

    first = pso(problem.loss, lo, hi, n_particles=N_PARTICLES, n_iters=N_ITERS, key=jax.random.PRNGKey(0))
    out["ours_compile_s"] = first.compile_s
    ours, numpy_runs, jax_runs = [], [], []
    for s in range(args.repeats):  # the three take turns, so load from other processes hits them alike
        ours.append(pso(problem.loss, lo, hi, n_particles=N_PARTICLES, n_iters=N_ITERS, key=jax.random.PRNGKey(s + 1)))
        numpy_runs.append(run_pyswarms(numpy_objective, lo, hi, N_ITERS, s))
        jax_runs.append(run_pyswarms(jax_objective, lo, hi, N_ITERS, s))
    out["ours_s"] = statistics.median(r.wall_s for r in ours)
    out["ours_best_loss"] = statistics.median(r.loss for r in ours)
    out["pyswarms_numpy_s"] = statistics.median(t for t, _, _ in numpy_runs)
    out["pyswarms_numpy_best_loss"] = statistics.median(c for _, c, _ in numpy_runs)
    out["pyswarms_our_loss_s"] = statistics.median(t for t, _, _ in jax_runs)

    out["ratio_pyswarms_numpy_over_ours"] = out["pyswarms_numpy_s"] / out["ours_s"]
    out["ratio_pyswarms_our_loss_over_ours"] = out["pyswarms_our_loss_s"] / out["ours_s"]
    if args.python_loop:
        out["python_loss_rel_diff"] = float(abs(python_particle_loss(problem, check[0]) - ref[0]) / ref[0])
        loop_obj = lambda x: np.array([python_particle_loss(problem, g) for g in x])  # noqa: E731
        times = [run_pyswarms(loop_obj, lo, hi, 2, s)[0] for s in range(2)]
        out["pyswarms_python_loop_s_extrapolated"] = statistics.median(times) / 2 * N_ITERS
        out["ratio_pyswarms_python_loop_over_ours"] = out["pyswarms_python_loop_s_extrapolated"] / out["ours_s"]

    print(
        f"PSO, {N_PARTICLES} particles × {N_ITERS} iterations on the closed-loop PID loss "
        f"({problem.n_ticks} ticks × {problem.substeps} RK4 substeps), median of {args.repeats}"
    )
    print(
        f"  ours (jit + vmap, float64):        {out['ours_s']:.3f} s  "
        f"(+ compile {out['ours_compile_s']:.2f} s), "
        f"best loss {out['ours_best_loss']:.6f}"
    )
    print(
        f"  pyswarms + NumPy swarm loss:       {out['pyswarms_numpy_s']:.3f} s  → ratio "
        f"{out['ratio_pyswarms_numpy_over_ours']:.1f}×, best loss {out['pyswarms_numpy_best_loss']:.6f} "
        f"(NumPy vs JAX loss rel. diff {out['numpy_loss_rel_diff']:.1e})"
    )
    print(
        f"  pyswarms + our jitted batched loss: {out['pyswarms_our_loss_s']:.3f} s  → ratio "
        f"{out['ratio_pyswarms_our_loss_over_ours']:.2f}×"
    )
    if args.python_loop:
        print(
            f"  pyswarms + per-particle Python loop: {out['pyswarms_python_loop_s_extrapolated']:.1f} s "
            f"(extrapolated from 2 iterations) → ratio {out['ratio_pyswarms_python_loop_over_ours']:.0f}×"
        )
    write_json(args.json, out)
    return out


if __name__ == "__main__":
    main()
