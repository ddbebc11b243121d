"""CasADi cross-check of the PID tuning problem: the same sampled-data loop, CasADi's own RK4.

:func:`casadi_loss` rebuilds :class:`optim.problems.PIDTuning`'s loss as a CasADi expression
graph: the plant between two controller ticks is CasADi's fixed-step ``integrator("rk")`` (RK4,
``substeps`` finite elements per period, the control held as a parameter — zero-order hold); the
PID update is written out in CasADi symbols; ``mapaccum`` chains the ticks.  So the two losses are
the same discrete computation, written independently, and agree to rounding; CasADi's algorithmic
differentiation gives an independent gradient.

:func:`ipopt_tune` minimises it with IPOPT inside the box and reports a
:class:`optim.results.TuneResult` for the comparison harness.  Simulation accounting: every
objective evaluation counts 1, every gradient evaluation 1 (a forward and an adjoint sweep, as a
JAX ``value_and_grad`` counts in :func:`optim.tune.tune`), every exact-Hessian evaluation ``d``
(forward-over-adjoint sweeps).  IPOPT reports those totals only, so the per-iteration counts in the
history are the totals spread evenly over its iterations.
"""

from __future__ import annotations

import time
from typing import Any

import casadi as ca
import numpy as np

from optim.problems import PIDTuning
from optim.results import History, TuneResult, as_box


def casadi_loss(problem: PIDTuning) -> ca.Function:
    """``Function("pid_loss", [gains (3,)], [J])`` equal to ``problem.loss``."""
    K, T1, T2 = problem.K, problem.T1, problem.T2
    ts, tf, rho, r = problem.ts, problem.tf, problem.rho, problem.reference

    x = ca.SX.sym("x", 2)
    u = ca.SX.sym("u")
    ode = ca.vertcat(x[1], (K * u - x[0] - (T1 + T2) * x[1]) / (T1 * T2))
    plant = ca.integrator(
        "plant",
        "rk",
        {"x": x, "p": u, "ode": ode},
        0.0,
        ts,
        {"number_of_finite_elements": int(problem.substeps), "simplify": True},
    )

    # one tick: state z = [y, ẏ, integral, derivative filter, previous −y], cost accumulated
    z = ca.MX.sym("z", 5)
    g = ca.MX.sym("g", 3)
    kp, ki, kd = g[0], g[1], g[2]
    y = z[0]
    e = r - y
    sig = -y  # derivative on the measurement
    deriv = (tf * z[3] + (sig - z[4])) / (tf + ts)
    u_k = kp * e + z[2] + kd * deriv
    x_next = plant(x0=z[0:2], p=u_k)["xf"]
    z_next = ca.vertcat(x_next, z[2] + ts * ki * e, deriv, sig)
    cost = (e**2 + rho * u_k**2) * ts
    tick = ca.Function("tick", [z, g], [z_next, cost])

    n = problem.n_ticks
    chain = tick.mapaccum("ticks", n)
    z0 = ca.DM([0.0, 0.0, 0.0, 0.0, 0.0])  # plant at rest, PID state as pid_init with y0 = 0
    gains = ca.MX.sym("gains", 3)
    _, costs = chain(z0, ca.repmat(gains, 1, n))
    return ca.Function("pid_loss", [gains], [ca.sum2(costs)], ["gains"], ["loss"])


def casadi_value_and_grad(problem: PIDTuning, gains: Any) -> tuple[float, np.ndarray]:
    """``(J, ∇J)`` at ``gains`` by CasADi's algorithmic differentiation."""
    f = casadi_loss(problem)
    gsym = ca.MX.sym("g", 3)
    jg = ca.Function("jg", [gsym], [f(gsym), ca.gradient(f(gsym), gsym)])
    val, grad = jg(np.asarray(gains, float))
    return float(val), np.asarray(grad, float).ravel()


def ipopt_tune(
    problem: PIDTuning,
    x0: Any,
    *,
    lo: Any = None,
    hi: Any = None,
    max_iter: int = 200,
    tol: float = 1e-10,
    hessian: str = "limited-memory",
    print_level: int = 0,
) -> TuneResult:
    """Minimise the CasADi loss with IPOPT from ``x0`` inside ``[lo, hi]`` (default: the problem's box).

    ``hessian``: ``"limited-memory"`` (L-BFGS, gradients only) or ``"exact"``.  ``compile_s`` is
    the time to build the graph and the solver; ``wall_s`` the solve.
    """
    box_lo, box_hi = problem.box
    lo_a, hi_a = as_box(box_lo if lo is None else lo, box_hi if hi is None else hi)
    lo_a, hi_a = np.asarray(lo_a), np.asarray(hi_a)
    x0 = np.asarray(x0, float)
    if x0.shape != lo_a.shape or np.any(x0 < lo_a) or np.any(x0 > hi_a):
        raise ValueError(f"x0: must have shape {lo_a.shape} and lie inside [lo, hi], got {x0!r}")
    if hessian not in ("limited-memory", "exact"):
        raise ValueError(f"hessian: must be 'limited-memory' or 'exact', got {hessian!r}")

    t0 = time.perf_counter()
    f = casadi_loss(problem)
    gsym = ca.MX.sym("g", lo_a.size)
    trace: list[tuple[float, float]] = []
    start = [0.0]

    class _Record(ca.Callback):
        """IPOPT iteration callback: records (seconds since the solve started, objective)."""

        def __init__(self) -> None:
            ca.Callback.__init__(self)
            self.construct("record", {})

        def get_n_in(self):
            return ca.nlpsol_n_out()

        def get_n_out(self):
            return 1

        def get_name_in(self, i):
            return ca.nlpsol_out(i)

        def get_name_out(self, i):
            return "ret"

        def get_sparsity_in(self, i):
            name = ca.nlpsol_out(i)
            if name in ("f",):
                return ca.Sparsity.scalar()
            if name in ("x", "lam_x"):
                return ca.Sparsity.dense(lo_a.size)
            if name in ("g", "lam_g"):
                return ca.Sparsity(0, 0)
            return ca.Sparsity(0, 0)

        def eval(self, args):
            trace.append((time.perf_counter() - start[0], float(args[1])))
            return [0]

    record = _Record()
    opts = {
        "ipopt.max_iter": int(max_iter),
        "ipopt.tol": float(tol),
        "ipopt.print_level": int(print_level),
        "ipopt.hessian_approximation": hessian,
        "ipopt.sb": "yes",
        "print_time": False,
        "iteration_callback": record,
    }
    solver = ca.nlpsol("ipopt", "ipopt", {"x": gsym, "f": f(gsym)}, opts)
    compile_s = time.perf_counter() - t0
    start[0] = time.perf_counter()
    sol = solver(x0=x0, lbx=lo_a, ubx=hi_a)
    wall = time.perf_counter() - start[0]
    stats = solver.stats()
    n_f = int(stats.get("n_call_nlp_f", 0))
    n_grad = int(stats.get("n_call_nlp_grad_f", 0))
    n_hess = int(stats.get("n_call_nlp_hess_l", 0))
    n_sims = n_f + n_grad + n_hess * lo_a.size
    times = np.array([t for t, _ in trace]) if trace else np.array([wall])
    objs = np.array([v for _, v in trace]) if trace else np.array([float(sol["f"])])
    best = np.minimum.accumulate(objs)
    sims = np.round(np.arange(1, len(best) + 1) * n_sims / len(best)).astype(int)
    return TuneResult(
        params=np.asarray(sol["x"], float).ravel(),
        loss=float(sol["f"]),
        history=History(best, sims, times, loss=objs),
        n_sims=n_sims,
        wall_s=float(wall),
        compile_s=float(compile_s),
        converged=stats.get("return_status") in ("Solve_Succeeded", "Solved_To_Acceptable_Level"),
        message=f"IPOPT: {stats.get('return_status', '?')} after {stats.get('iter_count', '?')} iterations "
        f"({n_f} f, {n_grad} gradient, {n_hess} Hessian evaluations)",
    )
