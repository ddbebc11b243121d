"""Planar target motion models for trackers: constant velocity (CV) and coordinated turn (CT).

State ``(x, y, vx, vy)`` (m, m/s) for CV and ``(x, y, vx, vy, ω)`` (ω in rad/s, > 0 turns left)
for CT; plots measure ``(x, y)``.

* CV with continuous white-noise acceleration of spectral density ``q`` (m²/s³) per axis over a
  step ``dt``: ``F = [[I, dt·I], [0, I]]``, ``Q = q·[[dt³/3·I, dt²/2·I], [dt²/2·I, dt·I]]``
  (Bar-Shalom, Li & Kirubarajan §6.2.2).
* CT with known-form exact discretisation (the velocity rotates by ``ω dt``)::

      x' = x + S vx − C vy,   y' = y + C vx + S vy,   v' = Rot(ω dt) v,   ω' = ω
      S = sin(ω dt)/ω,        C = (1 − cos(ω dt))/ω

  written with ``sinc`` so that it is smooth (and equal to CV) at ``ω = 0``.
* Constant acceleration (CA) per axis, state ``(L, V, a)``, white jerk of density ``q`` (m²/s⁵):
  :func:`ca_axis_transition`, :func:`ca_axis_process_noise`; :func:`ca_planar` stacks two axes.
* :func:`cv_ct_imm` — the two-model IMM (CV and CT, both on the 5-state so they can be mixed;
  the CV member keeps ω as a random walk it does not use) built from
  :func:`~jaxsim.estimation.imm.linear_member` and :func:`~jaxsim.estimation.imm.ekf_member`.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.validation import check_covariance, check_positive
from jaxsim.estimation.imm import IMM, ekf_member, imm, linear_member
from jaxsim.estimation.nonlinear import nonlinear_ssm

POSITION_2D = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]])


def cv_transition(dt: float) -> np.ndarray:
    """``F (4, 4)`` of the CV model over ``dt`` (s)."""
    check_positive("dt", dt)
    return np.block([[np.eye(2), dt * np.eye(2)], [np.zeros((2, 2)), np.eye(2)]])


def cv_process_noise(dt: float, q: float) -> np.ndarray:
    """``Q (4, 4)`` of white-noise acceleration with spectral density ``q`` (m²/s³) per axis."""
    check_positive("dt", dt)
    check_positive("q", q, allow_zero=True)
    return q * np.block([[dt**3 / 3 * np.eye(2), dt**2 / 2 * np.eye(2)], [dt**2 / 2 * np.eye(2), dt * np.eye(2)]])


def ca_axis_transition(dt: float) -> np.ndarray:
    """``F (3, 3)`` of one axis of the constant-acceleration (CA) model, state ``(L, V, a)`` (m, m/s, m/s²)."""
    check_positive("dt", dt)
    return np.array([[1.0, dt, dt**2 / 2], [0.0, 1.0, dt], [0.0, 0.0, 1.0]])


def ca_axis_process_noise(dt: float, q: float) -> np.ndarray:
    """``Q (3, 3)`` of one CA axis driven by white jerk of spectral density ``q`` (m²/s⁵)
    (Bar-Shalom, Li & Kirubarajan §6.2.3)."""
    check_positive("dt", dt)
    check_positive("q", q, allow_zero=True)
    return q * np.array(
        [[dt**5 / 20, dt**4 / 8, dt**3 / 6], [dt**4 / 8, dt**3 / 3, dt**2 / 2], [dt**3 / 6, dt**2 / 2, dt]]
    )


def ca_planar(dt: float, q: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(F (6, 6), Q (6, 6), H (2, 6))`` of the planar CA model as two independent axes, state
    ``(x, vx, ax, y, vy, ay)``, measuring ``(x, y)``; with a diagonal measurement covariance its Kalman
    filter is the two per-axis filters side by side."""
    eye = np.eye(2)
    H = np.kron(eye, np.array([[1.0, 0.0, 0.0]]))
    return np.kron(eye, ca_axis_transition(dt)), np.kron(eye, ca_axis_process_noise(dt, q)), H


def ct_transition(dt: Any, x: jax.Array) -> jax.Array:
    """One exact coordinated-turn step of ``x = (x, y, vx, vy, ω)`` over ``dt``."""
    px, py, vx, vy, w = x[0], x[1], x[2], x[3], x[4]
    a = w * dt
    s = dt * jnp.sinc(a / jnp.pi)  # sin(ω dt)/ω
    c = 0.5 * a * dt * jnp.sinc(a / (2.0 * jnp.pi)) ** 2  # (1 − cos(ω dt))/ω
    cos_a, sin_a = jnp.cos(a), jnp.sin(a)
    return jnp.stack([px + s * vx - c * vy, py + c * vx + s * vy, cos_a * vx - sin_a * vy, sin_a * vx + cos_a * vy, w])


def _ct_f(params: Any, x: jax.Array, u: Any) -> jax.Array:
    return ct_transition(params, x)


def _position(params: Any, x: jax.Array) -> jax.Array:
    return x[:2]


def cv_ct_imm(dt: float, q_cv: float, q_ct: float, q_turn_rate: float, R: Any, switch_prob: Any = 0.05) -> IMM:
    """IMM of a CV model (white-noise acceleration ``q_cv``) and a CT model (acceleration ``q_ct``,
    turn-rate random walk of spectral density ``q_turn_rate`` rad²/s³), plots with covariance ``R (2, 2)``.

    ``switch_prob``: scalar (both ways) or ``(p_cv→ct, p_ct→cv)`` per step.
    """
    check_positive("q_turn_rate", q_turn_rate, allow_zero=True)
    p = np.asarray(switch_prob, float)
    if p.shape not in ((), (2,)):
        raise ValueError(f"switch_prob: expected a scalar or shape (2,), got shape {p.shape}")
    p = np.broadcast_to(p, (2,))
    if np.any((p < 0) | (p > 1)):
        raise ValueError(f"switch_prob: must lie in [0, 1], got {switch_prob!r}")
    check_covariance("R", R, 2)
    R = jnp.asarray(R, float)
    h5 = np.hstack([POSITION_2D, np.zeros((2, 1))])
    f_cv = np.zeros((5, 5))
    f_cv[:4, :4], f_cv[4, 4] = cv_transition(dt), 1.0
    q_w = q_turn_rate * dt
    q5_cv, q5_ct = np.zeros((5, 5)), np.zeros((5, 5))
    q5_cv[:4, :4], q5_cv[4, 4] = cv_process_noise(dt, q_cv), q_w
    q5_ct[:4, :4], q5_ct[4, 4] = cv_process_noise(dt, q_ct), q_w
    cv = linear_member(f_cv, q5_cv, h5, R)
    ct_model = nonlinear_ssm(_ct_f, _position, q5_ct, R, np.zeros(5), np.eye(5), params=float(dt))
    transition = np.array([[1.0 - p[0], p[0]], [p[1], 1.0 - p[1]]])
    return imm([cv, ekf_member(ct_model)], transition)
