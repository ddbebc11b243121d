"""Mean log-likelihood-ratio increments of competing steady-state Kalman filters on known-turn models,
and Wald's average sample number (ASN) of the test between them (Golubkov, seed 004 part 4 §B3).

Hypotheses: planar motion with state ``x = (x, vx, y, vy)`` (m, m/s) at a known turn rate ``ω`` (rad/s,
``> 0`` turns left, ``0`` straight, ``ω = ±|v|/r`` for a radius ``r``), piecewise-constant white
acceleration ``w ~ N(0, Q)`` (2 inputs), positions measured with ``R``::

    x⁺ = F(ω, T) x + G(T) w,     y = H x + v

Each hypothesis has a steady-state Kalman filter (gain ``K_j``, innovation covariance ``S_j``); its
log-likelihood increment is ``ℓ_j = −½ ln det(2π S_j) − ½ ν_jᵀ S_j⁻¹ ν_j``.  When the truth follows
model ``i`` and filter ``j`` runs, the prior error obeys::

    e⁺ = (F_i − F_j) x + F_j (I − K_j H) e − F_j K_j v + G w

so its innovation ``ν_j = H e + v`` has a mean (a bias driven by the true velocity) and a covariance:
``Γ_ij = H (P_e + ē ēᵀ) Hᵀ + R`` with ``P_e`` from the discrete Lyapunov equation of
``A_j = F_j (I − K_j H)`` (:func:`jaxsim.control.solve_discrete_lyapunov`).  Every matrix commutes
with a common rotation of the (x, y) plane (isotropic ``Q`` and ``R``), so in steady state the bias
rotates with the true velocity at constant size: ``ē = (Rot(ω_i T) − A_j)⁻¹ (F_i − F_j) x̄`` with
``x̄`` the state at the current speed (only ``|v|`` matters).  Then::

    E_i[ℓ_j] = −½ ln det(2π S_j) − ½ tr(S_j⁻¹ Γ_ij)

and ``μ₀ = E₀[ℓ₁ − ℓ₀] < 0``, ``μ₁ = E₁[ℓ₁ − ℓ₀] > 0`` (the spec's reconstructed eq. 3).  The random
walk of the true speed under ``Q`` is neglected inside the bias term (the statistics are conditioned
on the start speed, as the paper conditions on ``x_start``).  All functions are pure JAX and
differentiable in ``ω`` and ``T`` (the DARE and Lyapunov solvers differentiate implicitly).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from jaxsim.control.kalman_gain import discrete_kalman
from jaxsim.control.lyapunov import solve_discrete_lyapunov
from jaxsim.core.validation import is_concrete

H_POSITION = jnp.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]])  # (x, y) of (x, vx, y, vy)


def _check_dt(dt: Any) -> None:
    if is_concrete(dt) and not float(dt) > 0.0:
        raise ValueError(f"dt: must be positive, got {dt!r}")


def turn_model(omega: Any, dt: Any) -> tuple[jax.Array, jax.Array]:
    """``(F (4, 4), G (4, 2))`` of the known-turn model over ``dt`` (s) at turn rate ``omega`` (rad/s).

    ``F`` is the exact discretisation (the velocity rotates by ``ω dt``), written with ``sinc`` so that
    it is smooth in ``ω`` and equals the constant-velocity model at ``ω = 0``; ``G`` is the
    piecewise-constant acceleration input ``[[dt²/2, 0], [dt, 0], [0, dt²/2], [0, dt]]``.
    """
    _check_dt(dt)
    omega = jnp.asarray(omega, float)
    a = omega * dt
    s = dt * jnp.sinc(a / jnp.pi)  # sin(ω dt)/ω
    c = 0.5 * a * dt * jnp.sinc(a / (2.0 * jnp.pi)) ** 2  # (1 − cos(ω dt))/ω
    ca, sa = jnp.cos(a), jnp.sin(a)
    F = jnp.array(
        [
            [1.0, s, 0.0, -c],
            [0.0, ca, 0.0, -sa],
            [0.0, c, 1.0, s],
            [0.0, sa, 0.0, ca],
        ]
    )
    z = jnp.zeros_like(jnp.asarray(dt, float))
    G = jnp.array([[0.5 * dt**2, z], [dt, z], [z, 0.5 * dt**2], [z, dt]])
    return F, G


def plane_rotation(angle: Any) -> jax.Array:
    """``(4, 4)`` rotation of the (x, y) plane acting on both position and velocity of ``(x, vx, y, vy)``."""
    ca, sa = jnp.cos(angle), jnp.sin(angle)
    return jnp.kron(jnp.array([[ca, -sa], [sa, ca]]), jnp.eye(2))


class SteadyFilter(NamedTuple):
    """A steady-state Kalman filter: ``F``, ``G`` of its model, gain ``K (4, 2)``, innovation covariance
    ``S (2, 2)``, prior covariance ``P (4, 4)``."""

    F: jax.Array
    G: jax.Array
    K: jax.Array
    S: jax.Array
    P: jax.Array


def steady_filter(omega: Any, dt: Any, Q: Any, R: Any) -> SteadyFilter:
    """The steady-state Kalman filter of the known-turn model ``omega`` (rad/s) sampled at ``dt`` (s),
    ``Q (2, 2)`` acceleration-noise covariance per step, ``R (2, 2)`` position-noise covariance."""
    F, G = turn_model(omega, dt)
    Q, R = jnp.asarray(Q, float), jnp.asarray(R, float)
    gain = discrete_kalman(F, H_POSITION, Q, R, G, names=("F", "H", "Q", "R"))
    S = H_POSITION @ gain.p_prior @ H_POSITION.T + R
    return SteadyFilter(F, G, gain.k, 0.5 * (S + S.T), gain.p_prior)


def innovation_moments(truth_omega: Any, filt: SteadyFilter, dt: Any, Q: Any, R: Any, speed: Any):
    """``(bias (2,), cov (2, 2))`` of filter ``filt``'s steady-state innovation when the truth turns at
    ``truth_omega`` with ``speed`` (m/s); ``Γ = cov + bias biasᵀ``.  (The bias's direction rotates
    with the velocity; its size and ``Γ``'s trace and determinant do not.)"""
    F0, _ = turn_model(truth_omega, dt)
    Q, R = jnp.asarray(Q, float), jnp.asarray(R, float)
    eye = jnp.eye(4)
    A = filt.F @ (eye - filt.K @ H_POSITION)
    FK = filt.F @ filt.K
    noise = FK @ R @ FK.T + filt.G @ Q @ filt.G.T
    Pe = solve_discrete_lyapunov(A, 0.5 * (noise + noise.T))
    xbar = jnp.array([0.0, speed, 0.0, 0.0])
    ebar = jnp.linalg.solve(plane_rotation(truth_omega * dt) - A, (F0 - filt.F) @ xbar)
    bias = H_POSITION @ ebar
    return bias, H_POSITION @ Pe @ H_POSITION.T + R


def expected_loglik(truth_omega: Any, filt: SteadyFilter, dt: Any, Q: Any, R: Any, speed: Any) -> jax.Array:
    """``E[ℓ_j]`` per step: ``−½ ln det(2π S_j) − ½ tr(S_j⁻¹ Γ)`` of filter ``filt`` under the truth."""
    bias, cov = innovation_moments(truth_omega, filt, dt, Q, R, speed)
    gamma = cov + jnp.outer(bias, bias)
    m = filt.S.shape[0]
    _, logdet = jnp.linalg.slogdet(filt.S)
    return -0.5 * (m * jnp.log(2.0 * jnp.pi) + logdet) - 0.5 * jnp.trace(jnp.linalg.solve(filt.S, gamma))


def llr_drifts(omega0: Any, omega1: Any, dt: Any, Q: Any, R: Any, speed: Any) -> tuple[jax.Array, jax.Array]:
    """``(μ₀, μ₁)``: mean increment of ``Λ = Σ (ℓ₁ − ℓ₀)`` under H0 (truth ``omega0``) and H1 (``omega1``)."""
    f0, f1 = steady_filter(omega0, dt, Q, R), steady_filter(omega1, dt, Q, R)

    def drift(truth):
        return expected_loglik(truth, f1, dt, Q, R, speed) - expected_loglik(truth, f0, dt, Q, R, speed)

    return drift(omega0), drift(omega1)


def wald_bank_size(mu0: Any, mu1: Any, upper: Any, lower: Any, alpha: Any) -> jax.Array:
    """Golubkov's eqs. (1)–(2): ``N = max(N_A, N_B)``, ``N_A = (A − B)/μ₁``, ``N_B = (αA + (1 − α)B)/μ₀``
    (thresholds given, so that the same function serves a smooth surrogate; see
    :func:`jaxsim.estimation.mmae.sprt_bank_size` for the version from ``α, β``)."""
    return jnp.maximum((upper - lower) / mu1, (alpha * upper + (1.0 - alpha) * lower) / mu0)


__all__ = [
    "H_POSITION",
    "SteadyFilter",
    "expected_loglik",
    "innovation_moments",
    "llr_drifts",
    "plane_rotation",
    "steady_filter",
    "turn_model",
    "wald_bank_size",
]
