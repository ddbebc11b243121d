"""Sampled-data LQG tracker around an operating point: LQ tracking law + Kalman–Bucy observer.

Design (continuous time, on the plant linearised at ``(x_eq, u_eq)``, ``y_eq = C x_eq``):

* ``K`` from :func:`~jaxsim.control.lqr.lqr` with weights ``Q``, ``R``;
* ``L`` from :func:`~jaxsim.control.kalman_gain.kalman_bucy` with process/measurement noise
  intensities ``W``, ``V``;
* ``(Π, Γ)`` from the regulator equations for constant references (``S = 0``, ``ξ = r − y_eq``),
  so the law is ``u = u_eq + Γ ξ + K (Π ξ − δx̂)`` — seed paper eq. (4), ``u = L_g ξ − K x``.

Implementation in the rollout (controller period ``Ts``): the observer ODE
``δx̂̇ = (A − LC) δx̂ + B δu + L δy`` is integrated *exactly* over each period with ``δu`` (the
saturated command) and ``δy`` (the last measurement) held — a zero-order-hold discretisation
(``Φ, Γ_u, Γ_y`` from :func:`~jaxsim.core.discretize.c2d_zoh`), i.e. the continuous Kalman–Bucy
observer fed by sampled data, not a re-designed discrete filter.  The measurement taken at
``t_k`` enters the estimate from ``t_k`` to ``t_{k+1}``, so the controller at ``t_k`` acts on the
estimate built from measurements up to ``t_{k−1}``.

Everything in :func:`design` is differentiable (Riccati solves implicitly, ``expm`` by autodiff)
and vmappable, so a loss over a rollout can be differentiated with respect to ``Q, R, W, V``.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from jaxsim.control.kalman_gain import kalman_bucy
from jaxsim.control.lqr import lqr
from jaxsim.control.tracking import constant_exosystem, regulator_equations
from jaxsim.core.discretize import c2d_zoh
from jaxsim.core.linearize import Linearization
from jaxsim.core.pytree import pytree_dataclass
from jaxsim.core.system import Controller, Estimator


@pytree_dataclass
class LQGTrackerParams:
    """Operating point, gains and the observer's one-period transition (all arrays)."""

    x_eq: Any  # (n,)
    u_eq: Any  # (m,)
    y_eq: Any  # (p,)
    k: Any  # (m, n) state-feedback gain
    pi: Any  # (n, p) regulator-equation state map
    gamma: Any  # (m, p) regulator-equation input map
    phi: Any  # (n, n) observer transition over Ts
    gamma_u: Any  # (n, m) observer input map over Ts
    gamma_y: Any  # (n, p) observer measurement map over Ts
    u_min: Any  # (m,) saturation the observer assumes for the applied input
    u_max: Any  # (m,)


class ObserverState(NamedTuple):
    dx: jax.Array  # (n,) estimate of x − x_eq
    y: jax.Array  # (p,) last measurement (held)


def design(
    lin: Linearization,
    x_eq: jax.Array,
    u_eq: jax.Array,
    q: jax.Array,
    r: jax.Array,
    w: jax.Array,
    v: jax.Array,
    ts: float,
    u_min: Any = -jnp.inf,
    u_max: Any = jnp.inf,
) -> LQGTrackerParams:
    """Gains for weights ``q (n, n)``, ``r (m, m)`` and noise intensities ``w (n, n)``, ``v (p, p)``
    at controller period ``ts`` (s)."""
    a, b, c = lin.a, lin.b, lin.c
    m, p = b.shape[1], c.shape[0]
    k = lqr(a, b, q, r).k
    obs = kalman_bucy(a, c, w, v)
    pi, gamma = regulator_equations(a, b, c, constant_exosystem(p))
    phi, gam = c2d_zoh(a - obs.l @ c, jnp.concatenate([b, obs.l], axis=1), ts)
    x_eq = jnp.asarray(x_eq, dtype=a.dtype)
    u_eq = jnp.asarray(u_eq, dtype=a.dtype)
    return LQGTrackerParams(
        x_eq=x_eq,
        u_eq=u_eq,
        y_eq=c @ x_eq,
        k=k,
        pi=pi,
        gamma=gamma,
        phi=phi,
        gamma_u=gam[:, :m],
        gamma_y=gam[:, m:],
        u_min=jnp.broadcast_to(jnp.asarray(u_min, a.dtype), (m,)),
        u_max=jnp.broadcast_to(jnp.asarray(u_max, a.dtype), (m,)),
    )


def control_law(params: LQGTrackerParams, r: jax.Array, x_hat: jax.Array) -> jax.Array:
    """``u = u_eq + Γ ξ + K (Π ξ − (x̂ − x_eq))`` with ``ξ = r − y_eq`` (unsaturated command)."""
    xi = r - params.y_eq
    return params.u_eq + params.gamma @ xi + params.k @ (params.pi @ xi - (x_hat - params.x_eq))


def _ctrl_init(params: LQGTrackerParams, r0: jax.Array, y0: jax.Array) -> jax.Array:
    return jnp.zeros((), dtype=params.k.dtype)


def _ctrl_step(params: LQGTrackerParams, state, r, x_hat, dt, t):
    return state, control_law(params, r, x_hat)


def _obs_init(params: LQGTrackerParams, y0: jax.Array) -> ObserverState:
    return ObserverState(jnp.zeros_like(params.x_eq), y0)


def _obs_update(params: LQGTrackerParams, state: ObserverState, y: jax.Array) -> ObserverState:
    return ObserverState(state.dx, y)


def _obs_predict(params: LQGTrackerParams, state: ObserverState, u: jax.Array, dt) -> ObserverState:
    du = jnp.clip(u, params.u_min, params.u_max) - params.u_eq
    dx = params.phi @ state.dx + params.gamma_u @ du + params.gamma_y @ (state.y - params.y_eq)
    return ObserverState(dx, state.y)


def _obs_read(params: LQGTrackerParams, state: ObserverState) -> jax.Array:
    return params.x_eq + state.dx


def lqg_tracker(params: LQGTrackerParams) -> tuple[Controller, Estimator]:
    """The controller (tracking law) and estimator (observer) to put in a
    :class:`~jaxsim.core.rollout.ClosedLoop`; the controller's output is the unsaturated command,
    the plant saturates it and the observer assumes the same saturation."""
    ctrl = Controller(params, _ctrl_init, _ctrl_step, name="lq_tracking")
    est = Estimator(params, _obs_init, _obs_predict, _obs_update, _obs_read, name="kalman_bucy_zoh")
    return ctrl, est


def sampled_closed_loop_matrix(lin: Linearization, params: LQGTrackerParams, ts: float) -> jax.Array:
    """One-period transition ``(2n, 2n)`` of ``[δx; δx̂]`` for the linear plant under this sampled
    controller (no saturation, zero reference): its spectral radius < 1 is closed-loop stability."""
    a_d, b_d = c2d_zoh(lin.a, lin.b, ts)
    top = jnp.concatenate([a_d, -b_d @ params.k], axis=1)
    bottom = jnp.concatenate([params.gamma_y @ lin.c, params.phi - params.gamma_u @ params.k], axis=1)
    return jnp.concatenate([top, bottom], axis=0)
