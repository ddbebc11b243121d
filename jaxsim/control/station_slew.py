"""Fuel-optimal station slew: the discrete problem's pieces, the on-board guidance law (1), a standard eigen-axis slew
(seed 004 #5; plant :mod:`jaxsim.plants.orbital_station`).

Discrete problem (scaled time ``τ ∈ [0, 1]``, scaled torque ``ũ``, see
:func:`jaxsim.plants.orbital_station.scaled_rhs`): ``N`` piecewise-constant torque intervals,
``substeps`` RK4 steps each; fuel ``Σ_k Σ_i s(ũ_ik)·Δτ`` with the smoothed
``s(v) = √(v² + ε²) − ε``; terminal conditions ``vec(q_f* ⊗ q_N) = 0`` (sign-invariant) and
``Ω_N = Ω_rest(q_f)``.  :func:`shoot` solves it by SQP (Gauss–Newton-type Hessian), vmapped over
starts by :func:`multi_start`; :mod:`optim.casadi_slew` is the same problem in CasADi/IPOPT.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp

from jaxsim.core.integrators import RK4
from jaxsim.plants import orbital_station as st

__all__ = [
    "SlewProblem",
    "fuel",
    "fuel_kg",
    "guidance",
    "guidance_error",
    "kkt_residuals",
    "multi_start",
    "rest_state_scaled",
    "rollout",
    "shoot",
    "smooth_abs",
    "standard_slew_fuel_kg",
    "standard_slew_history",
    "standard_slew_torque",
    "terminal_error",
    "trajectory",
]


@dataclass(frozen=True)
class SlewProblem:
    """A rest-to-rest slew: ``q0 → qf`` (orbital frame) in ``horizon`` s."""

    params: st.StationParams = st.StationParams()
    horizon: float = 5400.0  # s (paper, Table 1)
    yaw_deg: float = 180.0  # paper
    n_intervals: int = 24
    substeps: int = 4
    eps: float = 0.5  # smoothing of |ũ| (scaled torque)

    def q0(self) -> jax.Array:
        return jnp.array([1.0, 0.0, 0.0, 0.0])

    def qf(self) -> jax.Array:
        h = jnp.deg2rad(self.yaw_deg) / 2
        return jnp.array([jnp.cos(h), 0.0, 0.0, jnp.sin(h)])

    def x0(self) -> jax.Array:
        return rest_state_scaled(self.q0(), self)

    def torque_scale(self) -> float:
        """N·m per unit of scaled torque."""
        return self.params.inertia[2] / self.horizon**2


def rest_state_scaled(q: jax.Array, prob: SlewProblem) -> jax.Array:
    """Scaled state ``[q, Ω = ωT]`` (7,) at rest in the orbital frame at attitude ``q``."""
    x = st.rest_state(q, prob.params)
    return x.at[4:].multiply(prob.horizon)


def smooth_abs(v: jax.Array, eps: float) -> jax.Array:
    """``√(v² + ε²) − ε`` (0 at 0, → |v| − ε far away)."""
    return jnp.sqrt(v * v + eps * eps) - eps


def rollout(u: jax.Array, prob: SlewProblem) -> jax.Array:
    """States at the interval ends, ``(N + 1, 7)``, of scaled torques ``u (N, 3)`` (``prob.substeps``
    RK4 steps per interval)."""
    return trajectory(u, prob, prob.substeps)[:: prob.substeps]


def trajectory(u: jax.Array, prob: SlewProblem, steps_per_interval: int) -> jax.Array:
    """States ``(N·steps_per_interval + 1, 7)`` every ``1/(N·steps_per_interval)`` of scaled time under
    the piecewise-constant torques ``u (N, 3)``, by classical RK4 (:data:`jaxsim.core.integrators.RK4`);
    with ``steps_per_interval = prob.substeps`` the discretisation of the optimal-control problem, finer
    for the dense attitude history the guidance law samples."""
    h = 1.0 / (prob.n_intervals * steps_per_interval)

    def step(x: jax.Array, uk: jax.Array) -> tuple[jax.Array, jax.Array]:
        x = RK4.step(lambda _t, x: st.scaled_rhs(x, uk, prob.params, prob.horizon), 0.0, x, h)
        return x, x

    x0 = prob.x0()
    _, xs = jax.lax.scan(step, x0, jnp.repeat(u, steps_per_interval, axis=0))
    return jnp.concatenate([x0[None], xs])


def terminal_error(x_end: jax.Array, prob: SlewProblem) -> jax.Array:
    """``[vec(q_f* ⊗ q_N), Ω_N − Ω_rest(q_f)]`` (6,)."""
    qf = prob.qf()
    conj = qf * jnp.array([1.0, -1.0, -1.0, -1.0])
    dq = st.quat_mul(conj, x_end[:4])
    return jnp.concatenate([dq[1:], x_end[4:] - rest_state_scaled(qf, prob)[4:]])


def fuel(u: jax.Array, prob: SlewProblem, eps: float | None = None) -> jax.Array:
    """Scaled fuel ``Σ s(ũ)·Δτ`` (``eps = 0``: the exact L1)."""
    e = prob.eps if eps is None else eps
    return jnp.sum(smooth_abs(u, e)) / prob.n_intervals if e > 0 else jnp.sum(jnp.abs(u)) / prob.n_intervals


def fuel_kg(u: jax.Array, prob: SlewProblem) -> jax.Array:
    """Propellant (kg) of scaled torques ``u (N, 3)``: the exact L1 ``∫Σ|u_i|dt`` in N·m·s through
    :func:`jaxsim.plants.orbital_station.fuel_kg`."""
    impulse = fuel(u, prob, 0.0) * prob.torque_scale() * prob.horizon
    return st.fuel_kg(impulse, prob.params)


def guidance(t: jax.Array, q_nodes: jax.Array, dt: float, n: float = 0.0) -> tuple[jax.Array, jax.Array]:
    """Eq. (1): command attitude and rate at time ``t`` (s) from quaternion nodes ``q_nodes (M, 4)``
    spaced ``dt`` s.  ``q_cmd = q_j ⊗ exp(θ_{j,j+1}(t − t_j)/Δt)``, θ the shortest rotation vector
    from ``q_j`` to ``q_{j+1}`` (body axes); ``ω_cmd = θ/Δt + ω_orb`` in body axes (rad/s)."""
    m = q_nodes.shape[0]
    j = jnp.clip(jnp.floor(t / dt).astype(int), 0, m - 2)
    qa, qb = q_nodes[j], q_nodes[j + 1]
    d = st.quat_mul(qa * jnp.array([1.0, -1.0, -1.0, -1.0]), qb)
    d = jnp.where(d[0] < 0, -d, d)
    s = jnp.linalg.norm(d[1:])
    angle = 2.0 * jnp.arctan2(s, d[0])
    theta = jnp.where(s > 1e-12, angle / jnp.where(s > 1e-12, s, 1.0), 2.0) * d[1:]
    frac = (t - j * dt) / dt
    phi = theta * frac
    a = jnp.linalg.norm(phi)
    half = 0.5 * a
    k = jnp.where(a > 1e-8, jnp.sin(half) / jnp.where(a > 1e-8, a, 1.0), 0.5)
    q = st.quat_mul(qa, jnp.concatenate([jnp.cos(half)[None], k * phi]))
    return q, theta / dt + st.orbit_rate_body(q, n)


def standard_slew_torque(t: jax.Array, p: st.StationParams, duration: float, yaw_deg: float = 180.0) -> jax.Array:
    """Inverse-dynamics torque (N·m, ``(3,)``) of a standard rest-to-rest eigen-axis yaw slew: yaw
    ``ψ(t) = ψ_f (t/T − sin(2πt/T)/2π)`` (cycloidal profile) about the nadir axis, ``T = duration``."""
    inertia = jnp.asarray(p.inertia)
    psi_f = jnp.deg2rad(yaw_deg)

    def omega(t: jax.Array) -> jax.Array:
        s = t / duration
        psi = psi_f * (s - jnp.sin(2 * jnp.pi * s) / (2 * jnp.pi))
        dpsi = psi_f * (1 - jnp.cos(2 * jnp.pi * s)) / duration
        q = jnp.array([jnp.cos(psi / 2), 0.0, 0.0, jnp.sin(psi / 2)])
        return q, jnp.array([0.0, 0.0, dpsi]) + st.orbit_rate_body(q, p.orbit_rate)

    q, w = omega(t)
    wdot = jax.jacfwd(lambda t: omega(t)[1])(t)
    c = st.nadir_body(q)
    n = p.orbit_rate
    return inertia * wdot + jnp.cross(w, inertia * w) - 3 * n * n * jnp.cross(c, inertia * c)


def standard_slew_history(
    p: st.StationParams, duration: float, yaw_deg: float = 180.0, samples: int = 6001
) -> tuple[jax.Array, jax.Array]:
    """Times ``(samples,)`` (s) over ``[0, duration]`` and :func:`standard_slew_torque` at them
    ``(samples, 3)`` (N·m)."""
    t = jnp.linspace(0.0, duration, samples)
    return t, jax.vmap(lambda t: standard_slew_torque(t, p, duration, yaw_deg))(t)


def standard_slew_fuel_kg(t: jax.Array, torque: jax.Array, p: st.StationParams) -> jax.Array:
    """Propellant (kg) of a sampled torque history ``torque (M, 3)`` at times ``t (M,)``:
    ``∫Σ|u_i|dt`` by the trapezoid rule (``|u_i|`` has kinks where a component changes sign; for the
    standard slew 6001 points over 3000 s agree with 60001 to 1e-7 relative)."""
    return st.fuel_kg(jnp.trapezoid(jnp.sum(jnp.abs(torque), axis=1), t), p)


def guidance_error(states: jax.Array, dt_state: float, node_every: int, n: float) -> dict[str, jax.Array]:
    """Worst error of the guidance law (1) against a dense attitude history: ``states (M, 7)`` SI
    (quaternion, inertial body rate in rad/s) every ``dt_state`` s; nodes every ``node_every`` samples
    (``Δt = node_every·dt_state``); the command at every sample against the state there.
    Returns ``angle_rad`` (largest rotation between command and state) and ``rate_rad_s`` (largest
    |ω_cmd − ω| over whole node intervals: the law's rate is constant on each)."""
    q = states[:, :4] / jnp.linalg.norm(states[:, :4], axis=1, keepdims=True)  # RK4 drifts off |q| = 1
    nodes = q[::node_every]
    dt = node_every * dt_state
    m = (nodes.shape[0] - 1) * node_every + 1
    t = jnp.arange(m) * dt_state
    q_cmd, w_cmd = jax.vmap(lambda t: guidance(t, nodes, dt, n))(t)
    dots = jnp.abs(jnp.sum(q_cmd * q[:m], axis=1))
    angle = 2.0 * jnp.arccos(jnp.clip(dots, 0.0, 1.0))
    return {"angle_rad": jnp.max(angle), "rate_rad_s": jnp.max(jnp.linalg.norm(w_cmd - states[:m, 4:], axis=1))}


def _flat_problem(
    shape: tuple[int, ...], prob: SlewProblem
) -> tuple[Callable[[jax.Array], jax.Array], Callable[[jax.Array], jax.Array]]:
    """The smoothed fuel and the terminal error (6,) as functions of the flattened torques ``z``."""

    def f(z: jax.Array) -> jax.Array:
        return fuel(z.reshape(shape), prob)

    def err(z: jax.Array) -> jax.Array:
        return terminal_error(rollout(z.reshape(shape), prob)[-1], prob)

    return f, err


def kkt_residuals(u: jax.Array, prob: SlewProblem) -> dict[str, jax.Array]:
    """First-order optimality of torques ``u (N, 3)``: the smoothed ``fuel``, the largest terminal
    ``error``, and the ``stationarity`` residual ``‖∇f + Aᵀλ‖∞ / ‖∇f‖∞`` with ``λ`` the least-squares
    multipliers (``A``: the terminal conditions' Jacobian by forward-mode autodiff) — e.g. to check a
    solution found by another solver (:mod:`optim.casadi_slew`) in this problem."""
    f, err = _flat_problem(u.shape, prob)
    z = u.ravel()
    g, a = jax.grad(f)(z), jax.jacfwd(err)(z)
    lam = jnp.linalg.lstsq(a.T, -g)[0]
    return {
        "fuel": f(z),
        "error": jnp.max(jnp.abs(err(z))),
        "stationarity": jnp.max(jnp.abs(g + a.T @ lam)) / jnp.max(jnp.abs(g)),
    }


def shoot(
    u0: jax.Array, prob: SlewProblem, *, iters: int = 200, floor: float = 1e-3, max_step: float = 1.0
) -> dict[str, jax.Array]:
    """SQP shooting from torques ``u0 (N, 3)``: each iteration solves the KKT system of the smoothed
    fuel with the terminal conditions linearised by forward-mode autodiff; the Hessian is the fuel's
    own (diagonal, exact) plus ``floor`` — the constraints' curvature is left out, so convergence is
    linear, not quadratic; the step is capped at ``max_step`` (scaled torque, ∞-norm).
    Returns ``u``, smoothed ``fuel``, terminal ``error`` (6,)."""
    shape = u0.shape
    f, err = _flat_problem(shape, prob)

    def step(carry: tuple[jax.Array, jax.Array], _: Any) -> tuple[tuple[jax.Array, jax.Array], None]:
        z, lam = carry
        e, a = err(z), jax.jacfwd(err)(z)
        curv = prob.eps**2 / (z * z + prob.eps**2) ** 1.5 / prob.n_intervals  # s''(z)/N
        h = jnp.diag(curv + floor)
        k = jnp.block([[h, a.T], [a, jnp.zeros((6, 6))]])
        sol = jnp.linalg.solve(k, -jnp.concatenate([jax.grad(f)(z), e]))
        d = sol[: z.size]
        d = d * jnp.minimum(1.0, max_step / jnp.max(jnp.abs(d)))
        return (z + d, sol[z.size :]), None

    (z, _lam), _ = jax.lax.scan(step, (u0.ravel(), jnp.zeros(6)), None, length=iters)
    u = z.reshape(shape)
    return {"u": u, "fuel": fuel(u, prob), "error": err(z)}


def multi_start(
    key: jax.Array, n_starts: int, prob: SlewProblem, scale: float = 3.0, **kw: Any
) -> dict[str, jax.Array]:
    """:func:`shoot` vmapped over ``n_starts`` Gaussian starts ``u0 ~ N(0, scale²)``."""
    u0 = scale * jax.random.normal(key, (n_starts, prob.n_intervals, 3))
    return jax.vmap(lambda u: shoot(u, prob, **kw))(u0)
