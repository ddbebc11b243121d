"""Benchmark: forward- vs reverse-mode gradients of a closed-loop PID loss as the parameter count grows.

The loss is :class:`optim.problems.PIDTuning`'s (static plant of the fuzzy-PID paper, sampled PID,
``J = ∫ e² + ρu² dt``) with a *gain schedule*: ``kp``, ``ki`` and ``kd`` are each piecewise constant
over ``n_seg`` equal segments of the horizon, so there are ``p = 3·n_seg`` parameters while the
simulation itself costs the same for every ``p``.  Timed (jitted, median of repeats), exactly as
:func:`optim.tune.tune` evaluates them:

* reverse: ``jax.value_and_grad(loss)``;
* forward: ``jax.jacfwd`` with the value as auxiliary output (one pass of ``p`` tangents).

The three take turns in every timing round and each sample averages enough calls to last 10 ms,
so load from other processes on a shared machine hits them alike; the median and the minimum over
rounds are printed (on a loaded machine the minimum is the less contaminated estimate).

The crossover — the parameter count from which reverse mode stays faster — sets
``optim.tune.FORWARD_MODE_MAX_PARAMS`` (what ``mode="auto"`` uses).

Usage: ``python -m experiments.benchmarks.ad_mode_crossover [--repeats 7] [--json out.json]``
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import statistics
import time

import jax
import jax.numpy as jnp

import jaxsim  # noqa: F401  (float64)
from experiments.benchmarks.timing import write_json
from jaxsim.control.pid import PIDParams, pid_init, pid_step
from jaxsim.core.rollout import ClosedLoop, fold
from jaxsim.core.signals import Step
from jaxsim.core.system import Controller
from jaxsim.plants.second_order import StaticParams, static_plant
from optim.problems import PIDTuning
from optim.tune import FORWARD_MODE_MAX_PARAMS


def scheduled_loss(problem: PIDTuning, n_seg: int):
    """``theta`` ``(3·n_seg,)`` = rows kp, ki, kd over the segments → the problem's loss."""
    n_ticks = problem.n_ticks
    per_seg = math.ceil(n_ticks / n_seg)
    base = PIDParams(tf=problem.tf, anti_windup="none", derivative_on="measurement")
    plant = static_plant(StaticParams(K=problem.K, T1=problem.T1, T2=problem.T2))

    def init(table, r0, y0):
        return pid_init(base, r0, y0), jnp.asarray(0)

    def step(table, state, r, y, dt, t):
        s, k = state
        seg = jnp.minimum(k // per_seg, n_seg - 1)
        p = dataclasses.replace(base, kp=table[0, seg], ki=table[1, seg], kd=table[2, seg])
        s, u = pid_step(p, s, r, y, dt)
        return (s, k + 1), u

    def loss(theta):
        ctrl = Controller(theta.reshape(3, n_seg), init, step, name="scheduled_pid")
        loop = ClosedLoop(plant, ctrl, reference=Step(jnp.asarray(problem.reference, theta.dtype)))

        def add(acc, tick):
            e = tick.r[0] - tick.y[0]
            return acc + (e**2 + problem.rho * tick.u[0] ** 2) * problem.ts

        return fold(loop, jnp.zeros(2, theta.dtype), problem.timing, add, jnp.zeros((), theta.dtype))[0]

    return loss


def _sample(fn, x, number: int) -> float:
    t0 = time.perf_counter()
    for _ in range(number):
        jax.block_until_ready(fn(x))
    return (time.perf_counter() - t0) / number


def interleaved_times(fns: dict, x, repeats: int, min_sample_s: float = 0.01) -> dict[str, tuple[float, float]]:
    """``(median, min)`` seconds per call of each function over ``repeats`` rounds; the functions
    take turns in every round and each sample averages enough calls to last ``min_sample_s``."""
    numbers = {}
    for name, fn in fns.items():
        jax.block_until_ready(fn(x))
        once = max(_sample(fn, x, 1), 1e-6)
        numbers[name] = max(1, int(min_sample_s / once))
    samples: dict[str, list[float]] = {name: [] for name in fns}
    for _ in range(repeats):
        for name, fn in fns.items():
            samples[name].append(_sample(fn, x, numbers[name]))
    return {name: (statistics.median(v), min(v)) for name, v in samples.items()}


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--segments", type=int, nargs="+", default=[1, 2, 4, 6, 8, 10, 12, 16, 24, 32, 64])
    ap.add_argument("--t-final", type=float, default=3.0)
    ap.add_argument("--repeats", type=int, default=25)
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    problem = PIDTuning(t_final=args.t_final)
    rows = []
    print(
        f"closed-loop PID loss, {problem.n_ticks} ticks × {problem.substeps} RK4 substeps; "
        f"median of {args.repeats}; devices {jax.devices()}"
    )
    print(f"{'':>6} {'median':>38} | {'minimum':>28}")
    print(
        f"{'params':>6} {'loss ms':>8} {'reverse ms':>10} {'forward ms':>10} {'rev/fwd':>8} "
        f"{'reverse ms':>10} {'forward ms':>10} {'rev/fwd':>8}"
    )
    for n_seg in args.segments:
        loss = scheduled_loss(problem, n_seg)
        x = jnp.tile(jnp.array([[6.0], [6.0], [0.3]]), (1, n_seg)).ravel()
        plain = jax.jit(loss)
        rev = jax.jit(jax.value_and_grad(loss))
        fwd = jax.jit(jax.jacfwd(lambda v: (loss(v), loss(v)), has_aux=True))
        g_r, g_f = rev(x)[1], fwd(x)[0]
        err = float(jnp.max(jnp.abs(g_r - g_f)) / jnp.max(jnp.abs(g_r)))
        t = interleaved_times({"loss": plain, "reverse": rev, "forward": fwd}, x, args.repeats)
        row = {"params": 3 * n_seg, "grad_rel_diff": err}
        for name, (med, best) in t.items():
            row[f"{name}_s"], row[f"{name}_min_s"] = med, best
        row["reverse_over_forward"] = row["reverse_s"] / row["forward_s"]
        row["reverse_over_forward_min"] = row["reverse_min_s"] / row["forward_min_s"]
        rows.append(row)
        print(
            f"{row['params']:>6} {1e3 * row['loss_s']:>8.3f} {1e3 * row['reverse_s']:>10.3f} "
            f"{1e3 * row['forward_s']:>10.3f} {row['reverse_over_forward']:>8.2f} "
            f"{1e3 * row['reverse_min_s']:>10.3f} {1e3 * row['forward_min_s']:>10.3f} "
            f"{row['reverse_over_forward_min']:>8.2f}"
        )

    def crossover(key: str) -> int:
        """Smallest tested p from which reverse mode stays faster (forward wins everywhere below)."""
        for r in rows:
            if all(q["reverse_over_forward" + key] < 1 for q in rows if q["params"] >= r["params"]):
                return r["params"]
        return rows[-1]["params"] * 2

    cross_med, cross_min = crossover(""), crossover("_min")
    print(
        f"reverse mode stays faster from {cross_med} parameters on (medians), from {cross_min} (minima); "
        f"optim.tune.FORWARD_MODE_MAX_PARAMS = {FORWARD_MODE_MAX_PARAMS}"
    )
    out = {
        "rows": rows,
        "reverse_faster_from_params_median": cross_med,
        "reverse_faster_from_params_min": cross_min,
        "n_ticks": problem.n_ticks,
    }
    write_json(args.json, out)
    return out


if __name__ == "__main__":
    main()
