"""Benchmark: cold compile time of study losses (TRMS LQG loss and its gradient, PID loss and its gradient).

Each program is traced, lowered and compiled in a *fresh* Python process with JAX's persistent
compilation cache off, so nothing from an earlier measurement (in-memory or on disk) is reused —
what a user pays the first time ``tune`` or a study compiles the loss.  Printed per program:

* ``trace``: ``jax.jit(f).lower(θ)`` (Python tracing, autodiff, lowering to StableHLO), wall seconds;
* ``compile``: ``.compile()`` (XLA), wall seconds;
* ``cpu``: process CPU seconds of both (on a loaded machine the less contaminated number; XLA
  compiles on several threads, so on an idle machine the wall time can be below it);
* ``hlo``: instructions in the optimised HLO.

Programs: ``trms_loss`` = :meth:`jaxsim.problem.trms.TRMSTuning.loss` (quick preset horizon, 30 s
at 10 ms: LQG design by two CAREs, Kalman–Bucy gain, regulator equations, ``c2d_zoh``, stability
penalty, rollout of the nonlinear plant); ``trms_grad`` = ``jax.value_and_grad`` of it (what the
gradient tuner compiles); ``trms_design`` / ``trms_design_grad`` = the design and stability penalty
alone; ``pid_loss`` / ``pid_grad`` = :class:`optim.problems.PIDTuning`'s; ``auv_loss`` /
``auv_grad`` = the AUV formation's tuning loss (:func:`jaxsim.problem.auv_formation.tuning_problem`,
CVaR over 2 vmapped draws, the study's tiny preset horizon: 7 s at 4 ms).

``--no-carry-promotion`` measures the rollout without :func:`jaxsim.core.rollout._promote_like`
(the loop carry then reaches its batched / tangent / unknown pattern by JAX's fixed-point rounds,
each re-transforming the whole tick body): the baseline of that change.

Usage: ``python -m experiments.benchmarks.compile_time [--programs trms_loss trms_grad ...]
[--t-final 30] [--repeats 1] [--no-carry-promotion]`` (default: ``trms_loss trms_grad pid_loss
pid_grad``; about a minute).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

PROGRAMS = ("trms_loss", "trms_grad", "trms_design", "trms_design_grad", "pid_loss", "pid_grad", "auv_loss", "auv_grad")
DEFAULT = ("trms_loss", "trms_grad", "pid_loss", "pid_grad")
ROOT = Path(__file__).resolve().parents[2]


def _function(program: str, t_final: float):
    """``(f, θ)`` for one program (imports inside: run in the measuring child process)."""
    import jax
    import jax.numpy as jnp

    if program.startswith("pid"):
        from optim.problems import PIDTuning

        loss, theta = PIDTuning().loss, jnp.array([2.0, 1.0, 0.1])
    elif program.startswith("auv"):
        from jaxsim.problem.auv_formation import FormationSetup, tuning_problem

        pb = tuning_problem(FormationSetup(tune_t_final=7.0, tune_loss_start=4.0, tune_dt=0.004), 2, 1)
        loss, theta = pb.loss, pb.space.init
    else:
        from jaxsim.problem.trms import Scenario, TRMSTuning

        tr = TRMSTuning(Scenario(t_final=t_final))
        theta = jnp.asarray(tr.bryson_theta())
        if program.startswith("trms_design"):

            def loss(th):
                params = tr.design(th)
                return sum(jnp.sum(leaf) for leaf in jax.tree_util.tree_leaves(params)) + tr.stability_penalty(params)
        else:
            loss = tr.loss
    grad = program.endswith("grad")
    return (jax.value_and_grad(loss) if grad else loss), theta


def measure_here(program: str, t_final: float, promote: bool = True) -> dict[str, float]:
    """Trace+lower and compile ``program`` in this process (cache off); seconds and HLO size."""
    import time

    import jax

    jax.config.update("jax_enable_compilation_cache", False)
    import jaxsim  # noqa: F401  (float64)

    if not promote:
        import jaxsim.core.rollout as rollout

        rollout._promote_like = lambda carry, inputs: carry

    f, theta = _function(program, t_final)
    cpu0, t0 = time.process_time(), time.perf_counter()
    lowered = jax.jit(f).lower(theta)
    t1 = time.perf_counter()
    compiled = lowered.compile()
    t2, cpu2 = time.perf_counter(), time.process_time()
    hlo = sum(" = " in line for line in compiled.as_text().splitlines())
    return {"trace": t1 - t0, "compile": t2 - t1, "total": t2 - t0, "cpu": cpu2 - cpu0, "hlo": hlo}


def measure(program: str, t_final: float, promote: bool = True) -> dict[str, float]:
    """:func:`measure_here` in a fresh process (nothing cached from earlier measurements)."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))}
    proc = subprocess.run(
        [sys.executable, "-m", "experiments.benchmarks.compile_time", "--child", program, "--t-final", str(t_final)]
        + ([] if promote else ["--no-carry-promotion"]),
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    if proc.returncode != 0:
        raise RuntimeError(f"{program}: measuring process failed:\n{proc.stderr[-3000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m experiments.benchmarks.compile_time",
        description="Cold (no persistent cache, fresh process) trace and XLA compile time of study losses.",
    )
    p.add_argument("--programs", nargs="+", choices=PROGRAMS, default=list(DEFAULT), help="what to measure")
    p.add_argument("--t-final", type=float, default=30.0, help="TRMS horizon in s (default 30: the quick preset)")
    p.add_argument("--repeats", type=int, default=1, help="fresh processes per program; the median is printed")
    p.add_argument(
        "--no-carry-promotion", action="store_true", help="the rollout without carry promotion (the baseline)"
    )
    p.add_argument("--child", help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.child:
        print(json.dumps(measure_here(args.child, args.t_final, not args.no_carry_promotion)))
        return 0
    try:
        load = f"{os.getloadavg()[0]:.2f}"
    except OSError:
        load = "n/a"
    promotion = "off" if args.no_carry_promotion else "on"
    print(
        f"cold compile, {os.cpu_count()} CPUs, load {load}, carry promotion {promotion}; "
        f"seconds (median of {args.repeats})"
    )
    print(f"{'program':18s} {'trace':>7s} {'compile':>8s} {'total':>7s} {'cpu':>7s} {'hlo':>7s}")
    for program in args.programs:
        runs = [measure(program, args.t_final, not args.no_carry_promotion) for _ in range(args.repeats)]
        m = {k: statistics.median(r[k] for r in runs) for k in runs[0]}
        print(
            f"{program:18s} {m['trace']:7.2f} {m['compile']:8.2f} {m['total']:7.2f} {m['cpu']:7.2f} {m['hlo']:7.0f}",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
