"""CasADi/IPOPT transcription of the fuel-optimal station slew (:mod:`jaxsim.control.station_slew`).

Direct multiple shooting on the same discretisation as the JAX rollout (``N`` piecewise-constant torque
intervals, ``substeps`` RK4 steps each, CasADi's own symbolic RK4 and its own copy of the rigid-body
equations), the same smoothed fuel and the same sign-invariant terminal conditions, so the optimal
costs of the two are directly comparable.  Node states are decision variables; quaternion nodes are
free (the RK4 map keeps their norm to the integration error).
"""

from __future__ import annotations

import time
from typing import Any, Sequence

import casadi as ca
import numpy as np

from jaxsim.control.station_slew import SlewProblem, rest_state_scaled


def _quat_mul(p: Any, q: Any) -> Any:
    pw, pv, qw, qv = p[0], p[1:4], q[0], q[1:4]
    return ca.vertcat(pw * qw - ca.dot(pv, qv), pw * qv + qw * pv + ca.cross(pv, qv))


def _dcm_t_col(q: Any, v: Any) -> Any:
    """``R(q)ᵀ v``: orbital-frame vector ``v`` in body axes, ``R`` written out as in
    ``orbital_station.dcm`` (the same expression off the unit sphere, e.g. inside RK4 stages)."""
    w, x, y, z = q[0], q[1], q[2], q[3]
    r = ca.vertcat(
        ca.horzcat(1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)),
        ca.horzcat(2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)),
        ca.horzcat(2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)),
    )
    return r.T @ v


def scaled_ode(prob: SlewProblem) -> ca.Function:
    """``f(x (7), u (3)) → dx/dτ`` in CasADi symbols (scaled units, see ``orbital_station.scaled_rhs``)."""
    jn = np.asarray(prob.params.inertia) / prob.params.inertia[2]
    n = prob.params.orbit_rate * prob.horizon
    x, u = ca.SX.sym("x", 7), ca.SX.sym("u", 3)
    q, w = x[0:4], x[4:7]
    rel = w - _dcm_t_col(q, ca.DM([0.0, -n, 0.0]))
    qdot = 0.5 * _quat_mul(q, ca.vertcat(0, rel))
    c = _dcm_t_col(q, ca.DM([0.0, 0.0, 1.0]))
    jv = ca.DM(jn)
    wdot = (-ca.cross(w, jv * w) + 3 * n * n * ca.cross(c, jv * c) + u) / jv
    return ca.Function("f", [x, u], [ca.vertcat(qdot, wdot)])


def _solver(prob: SlewProblem, tol: float) -> tuple[Any, np.ndarray, np.ndarray]:
    """The IPOPT solver of the multiple-shooting NLP, and the initial and final rest states."""
    f = scaled_ode(prob)
    n_int, m = prob.n_intervals, prob.substeps
    h = 1.0 / (n_int * m)
    xs, us = ca.MX.sym("x", 7), ca.MX.sym("u", 3)
    x = xs
    for _ in range(m):
        k1 = f(x, us)
        k2 = f(x + 0.5 * h * k1, us)
        k3 = f(x + 0.5 * h * k2, us)
        k4 = f(x + h * k3, us)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    step = ca.Function("step", [xs, us], [x])

    X = ca.MX.sym("X", 7, n_int + 1)
    U = ca.MX.sym("U", 3, n_int)
    x0 = np.asarray(prob.x0())
    qf = np.asarray(prob.qf())
    xf = np.asarray(rest_state_scaled(prob.qf(), prob))
    g = [X[:, 0] - x0]
    g += [X[:, k + 1] - step(X[:, k], U[:, k]) for k in range(n_int)]
    conj = ca.DM([qf[0], -qf[1], -qf[2], -qf[3]])
    g += [_quat_mul(conj, X[0:4, -1])[1:4], X[4:7, -1] - xf[4:]]
    eps = prob.eps
    cost = ca.sum1(ca.sum2(ca.sqrt(U * U + eps * eps) - eps)) / n_int
    nlp = {"x": ca.vertcat(ca.vec(X), ca.vec(U)), "f": cost, "g": ca.vertcat(*g)}
    options = {
        "ipopt.print_level": 0,
        "print_time": False,
        "ipopt.tol": tol,
        "ipopt.constr_viol_tol": tol,
        "ipopt.sb": "yes",
    }
    return ca.nlpsol("slew", "ipopt", nlp, options), x0, xf


def solve_many(
    prob: SlewProblem,
    starts: Sequence[np.ndarray | None],
    *,
    states: Sequence[np.ndarray] | None = None,
    tol: float = 1e-10,
) -> list[dict[str, Any]]:
    """IPOPT on the multiple-shooting NLP from each initial torque history in ``starts`` (each
    ``(N, 3)`` scaled torques, or None for zeros), the solver built once.  Node states start at
    ``states[k]`` (``(N+1, 7)``, e.g. the rollout of ``starts[k]``, to warm-start at a known solution)
    or, without ``states``, on the interpolation between the rest states.  Each result: ``u`` (N, 3),
    ``fuel`` (smoothed, scaled), ``x`` (N+1, 7), ``status``, ``iterations``, ``wall_s``."""
    n_int = prob.n_intervals
    if states is not None:  # checked before the (seconds-long) NLP build
        if len(states) != len(starts):
            raise ValueError(f"states: need one (N+1, 7) array per start ({len(starts)}), got {len(states)}")
        for k, x in enumerate(states):
            if np.shape(x) != (n_int + 1, 7):
                raise ValueError(f"states[{k}]: shape must be ({n_int + 1}, 7), got {np.shape(x)}")
    solver, x0, xf = _solver(prob, tol)
    s = np.linspace(0, 1, n_int + 1)[None]
    xg = (1 - s) * x0[:, None] + s * xf[:, None]
    nx = 7 * (n_int + 1)
    results = []
    for k, u0 in enumerate(starts):
        ug = np.zeros((3, n_int)) if u0 is None else np.asarray(u0).T
        if states is not None:
            xg = np.asarray(states[k]).T
        t0 = time.perf_counter()
        sol = solver(x0=np.concatenate([xg.ravel(order="F"), ug.ravel(order="F")]), lbg=0, ubg=0)
        wall = time.perf_counter() - t0
        z = np.asarray(sol["x"]).ravel()
        results.append(
            {
                "u": z[nx:].reshape(n_int, 3),
                "x": z[:nx].reshape(n_int + 1, 7),
                "fuel": float(sol["f"]),
                "status": solver.stats()["return_status"],
                "iterations": int(solver.stats()["iter_count"]),
                "wall_s": wall,
            }
        )
    return results


def solve(prob: SlewProblem, u0: np.ndarray | None = None, *, tol: float = 1e-10) -> dict[str, Any]:
    """IPOPT from one initial torque history ``u0 (N, 3)`` (zeros if None); see :func:`solve_many`."""
    return solve_many(prob, [u0], tol=tol)[0]
