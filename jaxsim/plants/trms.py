"""Twin-rotor MIMO system (TRMS, Feedback Instruments 33-220): nonlinear 7-state model.

Seed 004, lines 3302–3443 (spec ``seed004_part1.md`` §B1): the paper names the state vector
``x = (ψ, φ, ψ̇, φ̇, τ1, τ2, M_R)`` — pitch (vertical) angle ψ = α_v, yaw (horizontal) angle φ = α_h,
their rates, the main- and tail-motor momentum states τ1, τ2 and the cross-coupling (reaction)
torque M_R — but gives no equations or numbers.  The equations are the commonly cited
manufacturer model (spec §B1.1)::

    I1 ψ̈ = M1 − Mg sin ψ − (B1ψ ψ̇ + B2ψ sgn ψ̇) − Kgy M1 φ̇ cos ψ,    M1 = a1 τ1² + b1 τ1
    I2 φ̈ = M2 − (B1φ φ̇ + B2φ sgn φ̇) − M_R,                          M2 = a2 τ2² + b2 τ2
    T11 τ̇1 = k1 u1 − T10 τ1,      T21 τ̇2 = k2 u2 − T20 τ2
    M_R = kc (T0 s + 1)/(Tp s + 1) τ1   →   Tp Ṁ_R = kc (τ1 + T0 τ̇1) − M_R

(the last line is the cross-reaction filter realised with ``M_R`` itself as the 7th state, which
makes ``Ṁ_R`` depend on ``u1`` through ``τ̇1``).  Inputs ``u = (u1, u2)`` in volts are saturated at
``±u_max``; outputs are the two angles ``y = (ψ, φ)`` (the stand's optical encoders).

Parameter sets (public sources disagree; spec §B1.1 lists the differences):

* :data:`FEEDBACK_MANUFACTURER` (default, :class:`TRMSParams` defaults): the table "TRMS parameters —
  from the Feedback manufacturer" in J. Automation, Mobile Robotics & Intelligent Systems (JAMRIS)
  2025, doi:10.14313/jamris-2025-026 — the only complete public table found (it includes Tp, T0):
  b2 = 0.09, Kgy = 0.5 s/rad, kc = −0.2, T20 = 1.
* :data:`SCIREP_2022`: Table 2 of "Real-time robust generalized dynamic inversion based optimization
  control for coupled twin rotor MIMO system", Sci. Rep. 12 (2022), doi:10.1038/s41598-022-21357-3:
  b2 = 0.9, Kgy = 0.05, kc = 2; that table has no Tp, T0, which are taken from the default set.
  (Some sources also quote T20 = 1.3; no complete table with it was found, so it is not used.)

With the default set the tail rotor's torque ``a2 τ2² + b2 τ2 ≥ −b2²/(4 a2) ≈ −0.10 N·m`` can only
balance the main rotor's steady reaction ``M_R = kc τ1`` for pitch angles ``ψ ≲ 0.15 rad``; operating
points must stay inside that envelope (:func:`hover_equilibrium` reports the residual).

Friction ``sgn`` terms: exact by default; ``sign_smoothing = ε > 0`` replaces ``sgn v`` by
``tanh(v/ε)`` (ε in rad/s; :func:`jaxsim.core.switching.smooth_sign`) — the smooth surrogate used
on gradient paths (DESIGN principle 5).
Units: SI (kg·m², N·m, s, rad, V).
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.linearize import Equilibrium, Linearization, find_equilibrium, linearize
from jaxsim.core.pytree import pytree_dataclass, replace
from jaxsim.core.switching import smooth_sign
from jaxsim.core.system import Plant, Sensor, gaussian_sensor
from jaxsim.core.validation import check_finite, check_positive

STATE_NAMES = ("pitch", "yaw", "pitch_rate", "yaw_rate", "tau1", "tau2", "M_R")
INPUT_NAMES = ("u1_main", "u2_tail")
OUTPUT_NAMES = ("pitch", "yaw")


@pytree_dataclass
class TRMSParams:
    """Physical parameters (defaults: the Feedback manufacturer table, JAMRIS 2025-026)."""

    I1: Any = 6.8e-2  # kg·m², moment of inertia about the pitch axis
    I2: Any = 2e-2  # kg·m², moment of inertia about the yaw axis
    a1: Any = 0.0135  # N·m, main-rotor torque M1 = a1 τ1² + b1 τ1
    b1: Any = 0.0924  # N·m
    a2: Any = 0.02  # N·m, tail-rotor torque M2 = a2 τ2² + b2 τ2
    b2: Any = 0.09  # N·m
    Mg: Any = 0.32  # N·m, gravity moment
    B1psi: Any = 6e-3  # N·m·s/rad, viscous friction (pitch)
    B2psi: Any = 1e-3  # N·m, dry-friction level (pitch), multiplies sgn ψ̇
    B1phi: Any = 1e-1  # N·m·s/rad, viscous friction (yaw)
    B2phi: Any = 1e-2  # N·m, dry-friction level (yaw)
    Kgy: Any = 0.5  # s/rad, gyroscopic moment parameter
    k1: Any = 1.1  # main-motor gain
    k2: Any = 0.8  # tail-motor gain
    T11: Any = 1.1  # s, main-motor lag k1/(T11 s + T10)
    T10: Any = 1.0
    T21: Any = 1.0  # s, tail-motor lag k2/(T21 s + T20)
    T20: Any = 1.0
    Tp: Any = 2.0  # s, cross-reaction filter kc (T0 s + 1)/(Tp s + 1)
    T0: Any = 3.5  # s
    kc: Any = -0.2  # N·m, cross-reaction gain
    u_max: Any = 2.5  # V, input saturation |u_i| ≤ u_max (assumed; see the study's assumptions)
    sign_smoothing: Any = 0.0  # rad/s; 0 → exact sgn (a leaf: exact and smooth share compiled code)


FEEDBACK_MANUFACTURER = TRMSParams()
SCIREP_2022 = TRMSParams(b2=0.9, Kgy=0.05, kc=2.0)
PARAMETER_SETS = {"feedback_manufacturer": FEEDBACK_MANUFACTURER, "scirep_2022": SCIREP_2022}


def main_torque(p: TRMSParams, tau1: jax.Array) -> jax.Array:
    """``M1 = a1 τ1² + b1 τ1`` (N·m)."""
    return p.a1 * tau1**2 + p.b1 * tau1


def tail_torque(p: TRMSParams, tau2: jax.Array) -> jax.Array:
    """``M2 = a2 τ2² + b2 τ2`` (N·m)."""
    return p.a2 * tau2**2 + p.b2 * tau2


def saturate(p: TRMSParams, u: jax.Array) -> jax.Array:
    """``clip(u, −u_max, u_max)`` (V)."""
    return jnp.clip(u, -p.u_max, p.u_max)


def motor_derivatives(p: TRMSParams, x: jax.Array, u: jax.Array) -> jax.Array:
    """``(τ̇1, τ̇2, Ṁ_R)`` of the motor lags and the cross-reaction filter (``u`` saturated here)."""
    tau1, tau2, m_r = x[4], x[5], x[6]
    u1, u2 = saturate(p, u)
    dtau1 = (p.k1 * u1 - p.T10 * tau1) / p.T11
    dtau2 = (p.k2 * u2 - p.T20 * tau2) / p.T21
    dm_r = (p.kc * (tau1 + p.T0 * dtau1) - m_r) / p.Tp
    return jnp.stack([dtau1, dtau2, dm_r])


def applied_moments(p: TRMSParams, x: jax.Array) -> jax.Array:
    """Moments about the (pitch, yaw) axes that are not rigid-body terms (N·m, shape ``(2,)``).

    Rotor moments, the rotor's gyroscopic moment, dry friction and the cross-reaction torque:
    everything on the right-hand sides except gravity ``Mg sin ψ`` and viscous friction ``B1·rate``.
    An MJCF model of the stand (:mod:`jaxsim.mjx.trms`) applies exactly these as actuator torques.
    """
    psi, dpsi, dphi, tau1, tau2, m_r = x[0], x[2], x[3], x[4], x[5], x[6]
    m1 = main_torque(p, tau1)
    eps = p.sign_smoothing
    pitch = m1 - p.B2psi * smooth_sign(dpsi, eps) - p.Kgy * m1 * dphi * jnp.cos(psi)
    yaw = tail_torque(p, tau2) - p.B2phi * smooth_sign(dphi, eps) - m_r
    return jnp.stack([pitch, yaw])


def dynamics(p: TRMSParams, x: jax.Array, u: jax.Array, t: jax.Array) -> jax.Array:
    """``ẋ`` for state ``x (7,)`` and commanded voltages ``u (2,)`` (saturated here)."""
    psi, dpsi, dphi = x[0], x[2], x[3]
    pitch_moment, yaw_moment = applied_moments(p, x)
    ddpsi = (pitch_moment - p.Mg * jnp.sin(psi) - p.B1psi * dpsi) / p.I1
    ddphi = (yaw_moment - p.B1phi * dphi) / p.I2
    return jnp.concatenate([jnp.stack([dpsi, dphi, ddpsi, ddphi]), motor_derivatives(p, x, u)])


def output(p: TRMSParams, x: jax.Array) -> jax.Array:
    """``y = (ψ, φ)`` (rad)."""
    return x[:2]


def validate_params(p: TRMSParams) -> None:
    """Raise ``ValueError`` for non-physical parameters (concrete values only)."""
    for name in ("I1", "I2", "T11", "T10", "T21", "T20", "Tp", "u_max"):
        check_positive(name, getattr(p, name))
    for name in ("a1", "b1", "a2", "b2", "Mg", "B1psi", "B2psi", "B1phi", "B2phi", "Kgy", "k1", "k2", "T0", "kc"):
        check_finite(name, getattr(p, name))
    check_positive("sign_smoothing", p.sign_smoothing, allow_zero=True)


def trms_plant(params: TRMSParams | None = None) -> Plant:
    """The TRMS as a :class:`~jaxsim.core.system.Plant` (7 states, 2 inputs, 2 outputs)."""
    params = FEEDBACK_MANUFACTURER if params is None else params
    validate_params(params)
    return Plant(params, dynamics, output, n_states=7, n_inputs=2, n_outputs=2, name="trms")


def angle_sensor(std: Any = 2e-3, period: float | None = None) -> Sensor:
    """Additive white Gaussian noise on the two measured angles (``std`` rad, scalar or ``(2,)``)."""
    return gaussian_sensor(std, period)


def hover_equilibrium(params: TRMSParams, pitch: float, yaw: float = 0.0) -> tuple[jax.Array, jax.Array, jax.Array]:
    """Equilibrium ``(x_eq (7,), u_eq (2,), residual_norm)`` holding the angles ``(pitch, yaw)``.

    Solves ``f(x, u) = 0`` for ``(τ1, τ2, M_R, u1, u2)`` at zero rates with
    :func:`~jaxsim.core.linearize.find_equilibrium` (Gauss–Newton), the initial guess being the
    linear-torque approximation.  Dry friction is zero at rest, so the exact ``sgn`` is used.
    Differentiable in ``params`` (e.g. for Monte-Carlo perturbations); a residual well above 1e-10
    means the angles are outside the stand's trim envelope.
    """
    p = replace(params, sign_smoothing=0.0)
    pitch = jnp.asarray(pitch, dtype=float)
    yaw = jnp.asarray(yaw, dtype=float)

    def state(z):
        return jnp.stack([pitch, yaw, 0.0 * pitch, 0.0 * pitch, z[0], z[1], z[2]])

    def residual(z):
        return dynamics(p, state(z), z[3:], 0.0)[2:]

    tau1 = p.Mg * jnp.sin(pitch) / p.b1
    m_r = p.kc * tau1
    tau2 = m_r / p.b2
    z0 = jnp.stack([tau1, tau2, m_r, p.T10 * tau1 / p.k1, p.T20 * tau2 / p.k2])
    eq: Equilibrium = find_equilibrium(residual, z0, n_iter=30)
    return state(eq.z), eq.z[3:], eq.residual_norm


def linearize_at(params: TRMSParams, x_eq: jax.Array, u_eq: jax.Array) -> Linearization:
    """``jacfwd`` linearisation at an equilibrium (exact ``sgn``: dry friction has zero slope there,
    so the design model keeps the viscous friction only)."""
    return linearize(trms_plant(replace(params, sign_smoothing=0.0)), x_eq, u_eq)
