"""Benchmark: env-steps per second of the TRMS — our ODE vs the same plant through MJX vs C MuJoCo.

One env-step advances the plant by ``h = 1 ms`` under a held input; ``K`` steps per rollout, a batch
of ``B`` rollouts with different input sequences, all float64 on this CPU:

* **ODE (ours)**: ``jit(vmap(lax.scan))`` of one RK4 step of :func:`jaxsim.plants.trms.dynamics`
  (4 evaluations of the 7-state field per env-step; also an explicit-Euler row, 1 evaluation);
* **MJX**: the same scan over the MJCF TRMS (:func:`jaxsim.mjx.trms_mjx_plant`, ``field="step"``):
  one ``mjx.step`` of the rigid body (MuJoCo's semi-implicit Euler) plus our motor models per env-step;
* **C MuJoCo**: ``mujoco.rollout.rollout`` of the same MJCF rigid body with 1 and 2 threads.  The motor
  models cannot run inside C MuJoCo, so it is fed precomputed actuator torques (open loop): it times
  the rigid-body physics only — a lower bound on what the whole plant would cost there.

Every timing is the median of ``--repeats`` runs after a warm-up (compilation excluded and reported
separately).  Ratios are printed relative to our ODE (RK4).

Usage: ``python -m experiments.benchmarks.mjx_vs_ode [--batches 1 1024] [--steps 1000] [--repeats 3]``
"""

from __future__ import annotations

import argparse
import time

import jax
import jax.numpy as jnp
import mujoco
import mujoco.rollout
import numpy as np

import jaxsim  # noqa: F401  (float64)
from experiments.benchmarks.timing import median_time, write_json
from jaxsim.core.integrators import EULER, RK4
from jaxsim.core.rollout import hold_input
from jaxsim.mjx.trms import TO_ODE, trms_mjcf, trms_mjx_plant
from jaxsim.plants import trms

H = 1e-3  # s, env-step


def scan_rollout(plant, solver):
    """``jit(vmap)`` of ``K`` env-steps of ``plant`` (the plant step of ``simulate`` and the envs,
    :func:`~jaxsim.core.rollout.hold_input`) from ``x0 (B, n)`` under inputs ``us (B, K, m)``."""

    def one(x0, us):
        def body(x, u):
            return hold_input(plant, x, u, 0.0, H, 1, solver), None

        return jax.lax.scan(body, x0, us)[0]

    return jax.jit(jax.vmap(one))


def c_mujoco_states(model: mujoco.MjModel, x0: np.ndarray) -> np.ndarray:
    """Rigid states ``(B, nq + nv)`` → MuJoCo's full physics state vectors ``(B, nstate)``."""
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    data = mujoco.MjData(model)
    states = np.zeros((x0.shape[0], mujoco.mj_stateSize(model, spec)))
    for i, x in enumerate(x0):
        data.qpos[:], data.qvel[:] = x[: model.nq], x[model.nq : model.nq + model.nv]
        mujoco.mj_getState(model, data, states[i], spec)
    return states


def c_mujoco_rollout(model: mujoco.MjModel, threads: int, batch: int, steps: int):
    """``run(states, torques)``; the output arrays (every step's state: the API stores them) are
    allocated once, outside the timing."""
    datas = [mujoco.MjData(model) for _ in range(threads)]
    nstate = mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    out = np.empty((batch, steps, nstate))
    sensors = np.empty((batch, steps, model.nsensordata))

    def run(states: np.ndarray, torques: np.ndarray) -> np.ndarray:
        return mujoco.rollout.rollout(
            model, datas if threads > 1 else datas[0], states, torques, state=out, sensordata=sensors
        )[0]

    return run


def _timed(fn, repeats: int) -> tuple[float, float]:
    """(first call seconds, median of ``repeats`` further calls)."""
    start = time.perf_counter()
    jax.block_until_ready(fn())
    first = time.perf_counter() - start
    return first, median_time(lambda: jax.block_until_ready(fn()), repeats)


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--batches", type=int, nargs="+", default=[1, 1024])
    ap.add_argument("--steps", type=int, default=1000, help="env-steps per rollout (h = 1 ms)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--json", default=None, help="write the numbers to this file")
    args = ap.parse_args(argv)

    p = trms.FEEDBACK_MANUFACTURER
    x_eq, u_eq, _ = trms.hover_equilibrium(p, pitch=0.1)
    ode = trms.trms_plant(p)
    mjx_plant = trms_mjx_plant(p, field="step", timestep=H)
    runners = {
        "ode_rk4": (scan_rollout(ode, RK4), x_eq),
        "ode_euler": (scan_rollout(ode, EULER), x_eq),
        "mjx": (scan_rollout(mjx_plant, EULER), x_eq[TO_ODE]),
    }
    mj_model = mujoco.MjModel.from_xml_string(trms_mjcf(p, timestep=H))
    rng = np.random.default_rng(0)
    rows = []
    for b in args.batches:
        us = np.asarray(u_eq) + 0.3 * rng.standard_normal((b, args.steps, 2))
        row = {"batch": b, "steps": args.steps}
        for name, (fn, x0) in runners.items():
            x0s, us_j = jnp.tile(x0, (b, 1)), jnp.asarray(us)
            first, med = _timed(lambda: fn(x0s, us_j), args.repeats)
            row[name] = b * args.steps / med
            row[name + "_compile_s"] = first - med
        torques = 0.05 * rng.standard_normal((b, args.steps, 2))  # open-loop actuator torques (N·m)
        states = c_mujoco_states(mj_model, np.tile(np.asarray(x_eq[TO_ODE])[:4], (b, 1)))
        for threads in (1, 2):
            run = c_mujoco_rollout(mj_model, threads, b, args.steps)
            _, med = _timed(lambda: run(states, torques), args.repeats)
            row[f"c_mujoco_{threads}t"] = b * args.steps / med
        rows.append(row)
        print(
            f"batch {b:5d}: env-steps/s  "
            + "  ".join(f"{k} {row[k]:.3g}" for k in ("ode_rk4", "ode_euler", "mjx", "c_mujoco_1t", "c_mujoco_2t"))
        )
        print(
            f"             ratios to ODE RK4: mjx {row['mjx'] / row['ode_rk4']:.3g}×, "
            f"C MuJoCo 1 thread {row['c_mujoco_1t'] / row['ode_rk4']:.3g}×, "
            f"2 threads {row['c_mujoco_2t'] / row['ode_rk4']:.3g}×;  "
            f"compile s: ode {row['ode_rk4_compile_s']:.1f}, mjx {row['mjx_compile_s']:.1f}"
        )
    out = {"h": H, "rows": rows, "devices": str(jax.devices())}
    write_json(args.json, out)
    return out


if __name__ == "__main__":
    main()
