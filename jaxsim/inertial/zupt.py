"""Zero-velocity (ZUPT) alignment of a stationary strapdown INS: the 15-state error model with position and
velocity measurements, and the 9-state model that sets the velocity error to zero and measures the
accelerometer outputs (seed 004 part 2, #20, spec §2.2).

Frame ENU, instrument axes along it (so body-frame drifts are navigation-frame drifts), Earth rate
``ω = (0, U cos φ, U sin φ)``, specific force ``f = (0, 0, g)``, ``Ω = [ω×]``, ``F_f = [f×]``.

* 15 states ``[Φ (3, rad), δr (3, m), δV (3, m/s), ε (3, rad/s), δa (3, m/s²)]``::

      Φ̇ = −Ω Φ + ε + w_g,   δṙ = δV,   δV̇ = F_f Φ − 2Ω δV + δa + w_a,   ε̇ = 0,   δȧ = 0

  measurements ``z = [δr, δV] + v`` with a "minimal possible" ``R`` (the true noise is zero);
* 9 states ``[Φ, ε, δa]`` (eqs. 3–7 of the spec: Φ̇ = −ΩΦ + ε reproduces its printed U sin φ, U cos φ
  structure); measurement ``z = F_f Φ + δa + w`` (eq. 8: ``n_E = −gΦ_N + δa_E``, ``n_N = gΦ_E + δa_N``,
  ``n_U − g = δa_U``) with the accelerometer white noise averaged over the step, ``R = N_a²/Δt``.

``w_g``, ``w_a`` are white with densities ``N_g`` (rad/√s) and ``N_a`` (m/s/√s).  Both discretised by
Van Loan (:func:`jaxsim.core.discretize.van_loan`); :func:`covariance_run` propagates the covariance
channel (predict, Joseph update by :func:`jaxsim.estimation.kalman.condition`) — what the paper's
Fig. 1 compares.  :func:`dense_flops` counts the floating-point operations of one dense step.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from jaxsim.core.discretize import van_loan
from jaxsim.core.validation import check_positive_scalar
from jaxsim.estimation import kalman
from jaxsim.estimation.types import GaussianState
from jaxsim.inertial.carousel import EARTH_RATE

GRAVITY = 9.81  # m/s² (assumed; the paper works at 60° latitude)


class DiscreteModel(NamedTuple):
    """``F (n, n)``, ``Q (n, n)``, ``H (p, n)``, ``R (p, p)`` of one filter at step ``dt``."""

    F: jax.Array
    Q: jax.Array
    H: jax.Array
    R: jax.Array


def _skew(v: jax.Array) -> jax.Array:
    return jnp.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def _earth(latitude: Any, gravity: float) -> tuple[jax.Array, jax.Array]:
    lat = jnp.asarray(latitude, float)
    w = EARTH_RATE * jnp.array([0.0, 1.0, 0.0]) * jnp.cos(lat) + EARTH_RATE * jnp.array([0.0, 0.0, 1.0]) * jnp.sin(lat)
    return _skew(w), _skew(jnp.array([0.0, 0.0, gravity]))


def _check(dt: Any, gyro_noise: Any, accel_noise: Any) -> None:
    for name, v in (("dt", dt), ("gyro_noise", gyro_noise), ("accel_noise", accel_noise)):
        if not isinstance(v, jax.core.Tracer):
            check_positive_scalar(name, v)


def model15(
    latitude: Any,
    dt: float,
    gyro_noise: Any,
    accel_noise: Any,
    r_position: float = 1e-3,
    r_velocity: float = 1e-4,
    gravity: float = GRAVITY,
) -> DiscreteModel:
    """The 15-state ZUPT filter at step ``dt`` (s): ``N_g`` rad/√s, ``N_a`` m/s/√s; the fictitious
    measurement standard deviations ``r_position`` (m) and ``r_velocity`` (m/s)."""
    _check(dt, gyro_noise, accel_noise)
    Om, Ff = _earth(latitude, gravity)
    I3, Z = jnp.eye(3), jnp.zeros((3, 3))
    A = jnp.block(
        [
            [-Om, Z, Z, I3, Z],
            [Z, Z, I3, Z, Z],
            [Ff, Z, -2 * Om, Z, I3],
            [Z, Z, Z, Z, Z],
            [Z, Z, Z, Z, Z],
        ]
    )
    G = jnp.block([[I3, Z], [Z, Z], [Z, I3], [Z, Z], [Z, Z]])
    qc = jnp.diag(jnp.concatenate([jnp.full(3, gyro_noise**2), jnp.full(3, accel_noise**2)]))
    F, Q = van_loan(A, qc, dt, G)
    H = jnp.block([[Z, I3, Z, Z, Z], [Z, Z, I3, Z, Z]])
    R = jnp.diag(jnp.concatenate([jnp.full(3, r_position**2), jnp.full(3, r_velocity**2)]))
    return DiscreteModel(F, Q, H, R)


def model9(latitude: Any, dt: float, gyro_noise: Any, accel_noise: Any, gravity: float = GRAVITY) -> DiscreteModel:
    """The 9-state ZUPT filter (velocity error ≡ 0, accelerometer outputs as measurements) at step ``dt``."""
    _check(dt, gyro_noise, accel_noise)
    Om, Ff = _earth(latitude, gravity)
    I3, Z = jnp.eye(3), jnp.zeros((3, 3))
    A = jnp.block([[-Om, I3, Z], [Z, Z, Z], [Z, Z, Z]])
    G = jnp.block([[I3], [Z], [Z]])
    F, Q = van_loan(A, jnp.eye(3) * gyro_noise**2, dt, G)
    H = jnp.block([[Ff, Z, I3]])
    R = jnp.eye(3) * accel_noise**2 / dt
    return DiscreteModel(F, Q, H, R)


def _update(model: DiscreteModel, P: jax.Array) -> jax.Array:
    zero_state = GaussianState(jnp.zeros(P.shape[0], P.dtype), P)
    return kalman.condition(zero_state, jnp.zeros(model.H.shape[0], P.dtype), model.H, model.R)[0].cov


def covariance_step(model: DiscreteModel, P: jax.Array) -> jax.Array:
    """One filter cycle of the covariance channel: Joseph update with ``H, R``, then ``F P Fᵀ + Q``."""
    return kalman.propagate_covariance(_update(model, P), model.F, model.Q)


def covariance_run(model: DiscreteModel, P0: jax.Array, n_steps: int) -> jax.Array:
    """Posterior covariances ``(n_steps, n, n)`` of the covariance channel over ``n_steps`` cycles."""

    def step(P, _):
        post = _update(model, P)
        return kalman.propagate_covariance(post, model.F, model.Q), post

    return jax.lax.scan(step, P0, None, length=n_steps)[1]


def dense_flops(n: int, p: int) -> int:
    """Floating-point operations of one dense cycle (multiply and add counted separately): Joseph update
    ``S = HPHᵀ + R``, Cholesky of ``S``, ``K = PHᵀS⁻¹``, ``(I − KH) P (I − KH)ᵀ + K R Kᵀ``, then
    ``F P Fᵀ + Q``.  ``n`` states, ``p`` measurements."""
    ph = 2 * n * n * p  # P Hᵀ
    s = 2 * p * p * n + p * p  # H (P Hᵀ) + R
    chol = p**3 // 3
    k = 2 * p * p * n  # two triangular solves for n right-hand sides
    ikh = 2 * n * n * p + n  # I − K H
    joseph = 2 * (2 * n**3) + 2 * n * p * p + 2 * n * n * p + n * n  # (I−KH)P(I−KH)ᵀ + (KR)Kᵀ
    predict = 2 * (2 * n**3) + n * n  # F P Fᵀ + Q
    return ph + s + chol + k + ikh + joseph + predict
