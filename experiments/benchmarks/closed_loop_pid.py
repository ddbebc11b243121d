"""Benchmark: 10,000 PID gain sets on the fuzzy-PID paper's static plant, simulated in closed loop.

Ours: one jitted ``vmap`` of the closed-loop rollout (RK4, plant step = controller period = dt)
folding the ITAE of each gain set as it runs (``jaxsim.core.fold``: nothing stored per tick).  The
batch is sharded over every visible JAX device; on a CPU, run with
``XLA_FLAGS=--xla_force_host_platform_device_count=2`` to use both cores.  Peers, on the same horizon and time grid,
timed on a subset
and extrapolated linearly to the full batch:

* python-control: ``control.forced_response`` of the continuous closed loop ``C(s)P(s)/(1+C(s)P(s))``
  (one call per gain set; the transfer-function algebra is counted too, since a user needs it);
* SciPy: ``solve_ivp`` (RK45, rtol 1e-8, atol 1e-10) of the closed-loop ODE, one call per set.

All three use P and I on the error and the filtered derivative on the measurement (no derivative
kick), so they solve the same problem.  The peers simulate the continuous-time PID, ours the sampled-data PID at
``dt``; the ITAE difference
between the two is printed so the accuracy is visible next to the speed.

Usage: ``python -m experiments.benchmarks.closed_loop_pid [--n 10000] [--subset 20] [--float32]``
"""

from __future__ import annotations

import argparse
import dataclasses
import time

import control
import jax
import jax.numpy as jnp
import numpy as np
import scipy.integrate

import jaxsim  # noqa: F401  (float64)
from experiments.benchmarks.timing import median_time, write_json
from jaxsim.control.pid import PIDParams, pid, pid_transfer_function
from jaxsim.core.rollout import ClosedLoop, Timing, fold
from jaxsim.core.signals import Step
from jaxsim.plants.second_order import static_plant

K, T1, T2, TF = 2.0, 0.1, 0.5, 0.02


def ours_fn(t_final: float, dt: float, dtype):
    plant = static_plant()
    template = pid(kp=1.0, tf=TF, anti_windup="none", derivative_on="measurement")
    timing = Timing(t_final=t_final, dt=dt)

    def itae(g):
        p = PIDParams(
            kp=g[0], ki=g[1], kd=g[2], tf=jnp.asarray(TF, dtype), anti_windup="none", derivative_on="measurement"
        )
        loop = ClosedLoop(plant, dataclasses.replace(template, params=p), reference=Step(jnp.asarray(1.0, dtype)))

        def add(acc, tick):
            return acc + tick.t * jnp.abs(tick.r[0] - tick.y[0]) * timing.ts

        return fold(loop, jnp.zeros(2, dtype), timing, add, jnp.zeros((), dtype))[0]

    return jax.jit(jax.vmap(itae))


def shard_batch(x: np.ndarray, dtype) -> jax.Array:
    """Put the batch on every visible device (leading axis split evenly)."""
    devices = np.array(jax.devices())
    mesh = jax.sharding.Mesh(devices, ("batch",))
    spec = jax.sharding.PartitionSpec("batch")
    return jax.device_put(jnp.asarray(x, dtype), jax.sharding.NamedSharding(mesh, spec))


def control_itae(g, t):
    c_pi = control.tf(*pid_transfer_function(g[0], g[1], 0.0))
    d = control.tf([g[2], 0.0], [TF, 1.0])  # filtered derivative on −y
    plant = control.tf([K], [T1 * T2, T1 + T2, 1.0])
    closed = control.feedback(plant, c_pi + d) * c_pi
    y = control.forced_response(closed, T=t, U=np.ones_like(t)).outputs
    return float(np.sum(t * np.abs(1.0 - y)) * (t[1] - t[0]))


def scipy_itae(g, t):
    kp, ki, kd = g

    def rhs(_, z):
        y, v, integ, dstate = z  # dstate: filter state of D = s/(TF s + 1) on −y
        e = 1.0 - y
        deriv = (-y - dstate) / TF
        u = kp * e + ki * integ + kd * deriv
        acc = (K * u - y - (T1 + T2) * v) / (T1 * T2)
        return [v, acc, e, deriv]

    sol = scipy.integrate.solve_ivp(rhs, (t[0], t[-1]), [0.0, 0.0, 0.0, 0.0], t_eval=t, rtol=1e-8, atol=1e-10)
    return float(np.sum(t * np.abs(1.0 - sol.y[0])) * (t[1] - t[0]))


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=10_000, help="number of gain sets")
    ap.add_argument("--subset", type=int, default=20, help="gain sets timed for the peers")
    ap.add_argument("--t-final", type=float, default=5.0)
    ap.add_argument("--dt", type=float, default=1e-3)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--float32", action="store_true", help="also time our float32 fast path")
    ap.add_argument("--json", default=None, help="write the numbers to this file")
    args = ap.parse_args(argv)

    rng = np.random.default_rng(0)
    gains = rng.uniform([0.2, 0.1, 0.0], [3.0, 3.0, 0.1], size=(args.n, 3))
    t = np.arange(int(round(args.t_final / args.dt))) * args.dt
    out = {"n": args.n, "t_final": args.t_final, "dt": args.dt, "devices": str(jax.devices())}

    fn = ours_fn(args.t_final, args.dt, jnp.float64)
    g64 = shard_batch(gains, jnp.float64)
    start = time.perf_counter()
    ours = np.asarray(fn(g64).block_until_ready())
    out["ours_first_call_s"] = time.perf_counter() - start
    out["ours_s"] = median_time(lambda: fn(g64).block_until_ready(), args.repeats)
    if args.float32:
        fn32 = ours_fn(args.t_final, args.dt, jnp.float32)
        g32 = shard_batch(gains, jnp.float32)
        fn32(g32).block_until_ready()
        out["ours_float32_s"] = median_time(lambda: fn32(g32).block_until_ready(), args.repeats)

    idx = rng.choice(args.n, size=args.subset, replace=False)
    start = time.perf_counter()
    ctrl_vals = [control_itae(gains[i], t) for i in idx]
    out["control_s_extrapolated"] = (time.perf_counter() - start) / args.subset * args.n
    n_sp = max(2, args.subset // 2)
    start = time.perf_counter()
    sp_vals = [scipy_itae(gains[i], t) for i in idx[:n_sp]]
    out["scipy_s_extrapolated"] = (time.perf_counter() - start) / n_sp * args.n

    out["ratio_vs_control"] = out["control_s_extrapolated"] / out["ours_s"]
    out["ratio_vs_scipy"] = out["scipy_s_extrapolated"] / out["ours_s"]
    out["itae_rel_diff_vs_control_max"] = float(np.max(np.abs(ours[idx] - ctrl_vals) / np.abs(ctrl_vals)))
    out["itae_rel_diff_vs_scipy_max"] = float(np.max(np.abs(ours[idx[:n_sp]] - sp_vals) / np.abs(sp_vals)))
    out["control_vs_scipy_rel_diff_max"] = float(np.max(np.abs(np.array(ctrl_vals[:n_sp]) - sp_vals) / np.abs(sp_vals)))

    print(f"closed-loop PID, {args.n} gain sets, {len(t)} steps of {args.dt} s, devices {out['devices']}")
    print(
        f"  ours (jit+vmap, float64): {out['ours_s']:.3f} s median of {args.repeats} "
        f"(first call incl. compile {out['ours_first_call_s']:.2f} s)"
    )
    if args.float32:
        print(f"  ours (float32):           {out['ours_float32_s']:.3f} s")
    print(f"  python-control loop:      {out['control_s_extrapolated']:.1f} s (extrapolated from {args.subset})")
    print(f"  scipy solve_ivp loop:     {out['scipy_s_extrapolated']:.1f} s (extrapolated from {n_sp})")
    print(f"  speed-up vs python-control: {out['ratio_vs_control']:.0f}x; vs solve_ivp: {out['ratio_vs_scipy']:.0f}x")
    print(
        f"  ITAE max rel. difference: ours vs control {out['itae_rel_diff_vs_control_max']:.2e}, "
        f"ours vs scipy {out['itae_rel_diff_vs_scipy_max']:.2e}, control vs scipy "
        f"{out['control_vs_scipy_rel_diff_max']:.2e}"
    )
    write_json(args.json, out)
    return out


if __name__ == "__main__":
    main()
