"""Computed torque on the nominal model plus a variable-structure term (seed 002, eqs. 17–24).

The follower tracks a moving point ``X*`` (position, velocity and acceleration ``(X, V, A)``
given by a predictor) with a fully actuated Fossen vehicle::

    E    = [X − p;  w·wrap(Θ* − Θ)]                     position and attitude error (eq. 18)
    V*   = J(η)⁻¹ [V; w·Θ̇*]                             desired body velocities
    ν_r  = V* + Λ J(η)⁻¹ E                               reference velocity
    s    = ν_r − ν                                       sliding variable (eq. 21)
    τ_n  = M_n ν̇_r + C_n(ν) ν_r + D_n(ν) ν_r + g_n(η)    computed torque, nominal model (eq. 20)
    τ_s  = K_s f(s)                                      variable structure (eq. 21)
    τ    = τ_n + τ_s                                     (eq. 19)

with ``J = blockdiag(R(Θ), T(Θ))`` (position error in the absolute frame; the paper writes it in the
follower's level frame FR, which gives the same ``J⁻¹E``).  ``f`` is the exact ``sign`` or a
smooth switch of :mod:`jaxsim.core.switching` (``tanh``, ``saturation``, ``ratio``) with a width.

Attitude reference (assumed — the symbol of the paper's rule "near the target point" is lost):
roll 0, yaw and pitch along the target point's velocity ``V`` (so the follower keeps the leader's
tangent heading while it holds station); ``Θ̇*`` follows from ``A``.  Both are weighted by
:func:`course_gate` (1 above 0.5 m/s, 0 below 0.2 m/s): a slow target point has no course.  ``ν̇_r`` is the exact time
derivative along the model ``Ẋ = V, V̇ = A, Ȧ = 0, η̇ = J ν`` (one ``jax.jvp``), so it needs no
follower acceleration and no numerical differentiation (which would spike at every frame).

Before ``t_start`` (the follower starts 4 s after the leader, paper line 1112) ``τ = 0``.

Controller input each tick: a :class:`~jaxsim.estimation.leader_predictor.LeaderEstimate` (or
any object with its fields ``follower (12,)`` and ``target (3, 3)``), as read from
:func:`jaxsim.estimation.leader_predictor.leader_predictor`; the start gate uses the tick time
``t`` the rollout passes to ``step``.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.pytree import pytree_dataclass, static_field
from jaxsim.core.switching import get_switch
from jaxsim.core.system import Controller
from jaxsim.core.validation import check_finite, check_positive, check_shape
from jaxsim.plants import auv, marine

PAPER_LAMBDA = (0.2, 0.2, 0.2, 0.2, 0.4, 0.4)  # paper line 1004
PAPER_KS = (100.0, 100.0, 100.0, 100.0, 100.0, 100.0)  # paper line 1003


@pytree_dataclass
class TrackingParams:
    """lam ``(6,)`` (1/s), k_s ``(6,)`` (N, N·m), width (units of ``s``; unused by ``sign``),
    model: nominal :class:`~jaxsim.plants.auv.AUVParams`, t_start (s); switch name (static)."""

    lam: Any
    k_s: Any
    width: Any
    model: auv.AUVParams
    t_start: Any = 4.0
    switch: str = static_field(default="sign")


COURSE_SPEED_BAND = (0.2, 0.5)  # m/s: below/above it the course reference is off/on (assumed)


def course_gate(velocity: jax.Array) -> jax.Array:
    """Weight in ``[0, 1]`` of the course (attitude) reference: a C¹ smoothstep of the horizontal
    speed over :data:`COURSE_SPEED_BAND`.  The direction of a slow target point is ill-defined (its
    rate ``|A|/|V|`` blows up), e.g. while the estimator's window fills; the follower then holds
    its attitude and only tracks the position.  At the paper's cruise (≥ 0.83 m/s) it is exactly 1."""
    lo, hi = COURSE_SPEED_BAND
    vh = jnp.sqrt(velocity[0] ** 2 + velocity[1] ** 2 + 1e-30)
    r = jnp.clip((vh - lo) / (hi - lo), 0.0, 1.0)
    return r * r * (3.0 - 2.0 * r)


def wrap_angle(a: jax.Array) -> jax.Array:
    """Angle(s) wrapped to ``[−π, π)``."""
    return (a + jnp.pi) % (2.0 * jnp.pi) - jnp.pi


def attitude_reference(velocity: jax.Array, acceleration: jax.Array) -> tuple[jax.Array, jax.Array]:
    """``Θ*`` and ``Θ̇*`` ``(3,)`` each: roll 0, pitch and yaw along ``velocity``."""
    # below half the course band's lower edge course_gate is 0 anyway
    return jax.jvp(lambda v: marine.course_attitude(v, 0.5 * COURSE_SPEED_BAND[0]), (velocity,), (acceleration,))


def tracking_errors(eta: jax.Array, position: jax.Array, gate: jax.Array, att: jax.Array) -> jax.Array:
    """``E = [X − p; w·wrap(Θ* − Θ)]`` ``(6,)`` for target ``position (3,)``, course gate ``w`` and
    ``Θ* (3,)`` (from :func:`course_gate` and :func:`attitude_reference`)."""
    return jnp.concatenate([position - eta[:3], gate * wrap_angle(att - eta[3:6])])


def reference_velocity(lam: jax.Array, eta: jax.Array, target: jax.Array) -> jax.Array:
    """``ν_r = V* + Λ J⁻¹ E`` (paper eq. 20) with ``V* = J⁻¹[V; w·Θ̇*]``, for ``target = [X, V, A]``
    ``(3, 3)``; ``(6,)``.  ``Λ`` acts on the body-frame error ``J⁻¹E``, not on ``E``: the two differ
    in attitude once roll/pitch ≠ 0 (``T(Θ)⁻¹`` does not commute with ``diag(0.2, 0.4, 0.4)``)."""
    x, v, a = target
    gate = course_gate(v)
    att, att_rate = attitude_reference(v, a)  # once per tick, shared by V* and E
    j_inv = marine.kinematics_jacobian_inverse(eta)
    v_star = j_inv @ jnp.concatenate([v, gate * att_rate])
    return v_star + lam * (j_inv @ tracking_errors(eta, x, gate, att))


def control_force(params: TrackingParams, x: jax.Array, target: jax.Array) -> jax.Array:
    """``τ = τ_n + τ_s`` ``(6,)`` at follower state ``x (12,)`` for ``target (3, 3)``."""
    lam = jnp.asarray(params.lam)
    eta, nu = x[:6], x[6:]
    eta_dot = marine.kinematics_jacobian(eta) @ nu
    target_dot = jnp.stack([target[1], target[2], jnp.zeros(3)])
    nu_r, nu_r_dot = jax.jvp(lambda e, tg: reference_velocity(lam, e, tg), (eta, target), (eta_dot, target_dot))
    tau_n = auv.inverse_dynamics(params.model, x, nu_r, nu_r_dot)
    tau_s = jnp.asarray(params.k_s) * get_switch(params.switch)(nu_r - nu, params.width)
    return tau_n + tau_s


def _init(params: TrackingParams, r0: Any, y0: jax.Array) -> jax.Array:
    return jnp.zeros(())


def _step(
    params: TrackingParams, state: jax.Array, r: Any, y: Any, dt: Any, t: jax.Array
) -> tuple[jax.Array, jax.Array]:
    """``y``: a ``LeaderEstimate`` (fields ``follower``, ``target``); ``t``: tick time (s)."""
    tau = control_force(params, y.follower, y.target)
    return state, jnp.where(t >= params.t_start - 1e-9, tau, 0.0)


def auv_tracking(
    model: auv.AUVParams | None = None,
    lam: Any = PAPER_LAMBDA,
    k_s: Any = PAPER_KS,
    switch: str = "sign",
    width: Any = 0.01,
    t_start: Any = 4.0,
) -> Controller:
    """The controller as a :class:`~jaxsim.core.system.Controller` (paper gains by default).

    ``model`` is what the controller believes (default: the nominal AUV).  ``ValueError`` for
    non-positive gains, a wrong shape, an unknown switch, a non-positive width or a non-finite
    ``t_start``.
    """
    m = auv.nominal_params() if model is None else model
    auv.validate(m)
    get_switch(switch)
    for name, value in (("lam", lam), ("k_s", k_s)):
        check_shape(name, value, (6,))
        check_positive(name, value)
    check_positive("width", width)
    check_finite("t_start", t_start)
    params = TrackingParams(
        jnp.asarray(lam, dtype=float),
        jnp.asarray(k_s, dtype=float),
        jnp.asarray(width, dtype=float),
        m,
        jnp.asarray(t_start, dtype=float),
        switch,
    )
    return Controller(params, _init, _step, name=f"auv_tracking_{switch}")
