"""Estimate and predict a moving target point between camera frames (seed 002, eqs. 7–16).

A follower sees its target point ``X*`` (paper eq. 6) through a camera every ``t_Δ`` (0.1 s) and
needs its position, velocity and acceleration every control tick ``h_Δ`` (1 ms).  Two stages:

1. **Sliding-window polynomial least squares** (eqs. 7–9): the last ``M + 1`` camera samples
   (``M = 50``) are fitted by a polynomial of degree ``N`` (``N = 4``); the fit is a fixed FIR
   filter, :func:`jaxsim.estimation.alpha_beta.poly_window_weights`, whose rows give position,
   velocity and acceleration at the newest sample.  The window is zero-filled at the start
   (the paper's ``Ω`` "filled with zeros": the target point at the follower's own position), so
   the fit is wrong until ``M + 1`` frames have arrived — the start-up transient.
2. **Multi-rate Kalman filter** (eqs. 14–16): state ``[v, X]`` per axis, prediction every tick
   with the double integrator ``A_p = [[1, 0], [h, 1]]``, ``B_p = [h, h²/2]`` driven by the fitted
   acceleration, correction on every frame with ``z = [v̂, X̂]`` from the fit (``H = I``).

**Frame.** The paper keeps the window and the filter in the follower's level frame FR and moves
them with the follower's own motion (eqs. 8, 11–13).  Because the follower's inertial navigation is
taken as exact (the paper's assumption), the same computation is done here in the follower's
non-rotating odometry frame (the absolute frame, since all frames start aligned): each camera
sample ``z_FR`` becomes ``p_F + R_z(ψ_F) z_FR``.  A fixed rigid transform commutes with a linear
least-squares fit, so the fit equals the paper's eq. (8)–(9) expressed in that frame; the transform
back into FR (:func:`jaxsim.plants.formation.level_frame_error`) is exact, so the follower's own
motion never enters the filter's input (the paper's eq. 13 needs it only because its filter lives
in the rotating frame).

**Noise model of the filter** (assumed; the paper gives no ``P_p(0)``, ``Q_p``, ``R_p``):

* process noise: white acceleration of power spectral density ``q`` (m²/s³) per axis — the error
  of the fitted acceleration used as input — discretised exactly over ``h``:
  ``Q = q [[h, h²/2], [h²/2, h³/3]]``;
* measurement noise: the covariance of the fit's ``[v̂, X̂]`` for white camera noise of standard
  deviation ``meas_std`` per axis, ``R = meas_std² · W₍₁,₀₎ W₍₁,₀₎ᵀ`` with ``W`` the FIR weights
  (exact for one frame; successive fits share samples and are correlated, which the filter ignores);
* the filter factorises per axis (``F, B, Q, R`` are ``⊗ I₃``), so it runs as three 2-state filters.

Prediction modes (static ``mode``): ``"kalman"`` (the paper: fit + filter predicting every tick),
``"polynomial"`` (the fit's Taylor polynomial, eq. 10, extrapolated between frames, no filter) and
``"hold"`` (no prediction between frames: the last frame's fit is held).

Measurement ``y`` each tick: ``[x_F (12), z_FR (3), frame]`` from
:func:`jaxsim.plants.formation.camera_sensor`.  What the controller reads: a :class:`LeaderEstimate`
(the follower's own state and ``X̂, V̂, Â`` of the target point in the odometry frame); the tick
time reaches the controller from the rollout (``Controller.step``'s ``t``).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from jaxsim.core.pytree import pytree_dataclass, static_field
from jaxsim.core.rotations import rotation_z
from jaxsim.core.system import Estimator
from jaxsim.core.validation import check_finite, check_positive, check_shape
from jaxsim.estimation import kalman
from jaxsim.estimation.alpha_beta import poly_window_weights
from jaxsim.estimation.types import GaussianState

MODES = ("kalman", "polynomial", "hold")


class LeaderEstimate(NamedTuple):
    """What :func:`leader_predictor` gives the follower's controller each tick (absolute frame,
    which is the follower's odometry frame).

    follower ``(12,)``: the follower's own state ``[η, ν]`` from its inertial navigation (taken as
    exact); position ``(3,)`` (m), velocity ``(3,)`` (m/s), acceleration ``(3,)`` (m/s²): the
    estimate of the target point ``X*`` now.  Fields gain a leading time axis in a recorded
    trajectory (``Trajectory.x_hat``).
    """

    follower: jax.Array
    position: jax.Array
    velocity: jax.Array
    acceleration: jax.Array

    @property
    def target(self) -> jax.Array:
        """``(..., 3, 3)``: rows position, velocity, acceleration (the controller's ``[X, V, A]``)."""
        return jnp.stack([self.position, self.velocity, self.acceleration], axis=-2)


@pytree_dataclass
class PredictorParams:
    """Tunable numbers (leaves) and the sizes/mode (static).

    weights ``(3, window)``: FIR weights of the fit's position, velocity and acceleration rows;
    accel_psd ``q`` (m²/s³); meas_cov ``(2, 2)``: the filter's ``R`` (:func:`fit_covariance`, built
    once by :func:`leader_predictor` from ``meas_std``); p0 ``(2,)`` initial variances of ``[v, X]``
    per axis; t_start (s): frames before it are ignored.
    """

    weights: jax.Array
    meas_cov: jax.Array
    accel_psd: Any = 1e-3
    p0: Any = (1.0, 1.0)
    t_start: Any = 0.0
    mode: str = static_field(default="kalman")


class PredictorState(NamedTuple):
    """t: time (s); ins ``(12,)`` last follower state; window ``(M + 1, 3)`` target samples in the
    odometry frame (oldest first); fit ``(3, 3)`` rows position, velocity, acceleration at the last
    frame; t_frame: its time; kf: per-axis :class:`GaussianState` (mean ``(3, 2)`` = ``[v, X]``,
    cov ``(3, 2, 2)``); frames: frames received."""

    t: jax.Array
    ins: jax.Array
    window: jax.Array
    fit: jax.Array
    t_frame: jax.Array
    kf: GaussianState
    frames: jax.Array


def double_integrator(h: Any, accel_psd: Any) -> tuple[jax.Array, jax.Array, jax.Array]:
    """``(F, B, Q)`` of ``[v, X]`` over a step ``h`` with white-acceleration noise ``q``."""
    h = jnp.asarray(h, dtype=float)
    F = jnp.array([[1.0, 0.0], [0.0, 1.0]]) + h * jnp.array([[0.0, 0.0], [1.0, 0.0]])
    B = jnp.stack([h, 0.5 * h**2])[:, None]
    Q = accel_psd * jnp.array([[h, h**2 / 2], [h**2 / 2, h**3 / 3]])
    return F, B, Q


def fit_covariance(weights: jax.Array, meas_std: Any) -> jax.Array:
    """Covariance ``(2, 2)`` of the fit's ``[v̂, X̂]`` for white sample noise ``meas_std``."""
    w = weights[jnp.array([1, 0])]
    return meas_std**2 * (w @ w.T)  # Gram of two independent weight rows: positive definite


def fit_window(weights: jax.Array, window: jax.Array) -> jax.Array:
    """Rows position, velocity, acceleration ``(3, 3)`` at the newest sample of ``window (W, 3)``
    for FIR ``weights (≥ 3, W)``."""
    return (weights @ window)[:3]


def _init(params: PredictorParams, y0: jax.Array) -> PredictorState:
    ins = y0[:12]
    size = params.weights.shape[1]
    p0 = jnp.asarray(params.p0, dtype=float)
    mean = jnp.stack([jnp.zeros(3), ins[:3]], axis=1)  # [v, X] per axis: the paper's χ(0) = 0
    cov = jnp.broadcast_to(jnp.diag(p0), (3, 2, 2))
    fit = jnp.stack([ins[:3], jnp.zeros(3), jnp.zeros(3)])
    return PredictorState(
        jnp.zeros(()),
        ins,
        jnp.tile(ins[:3], (size, 1)),
        fit,
        jnp.zeros(()),
        GaussianState(mean, cov),
        jnp.zeros((), dtype=jnp.int32),
    )


def _on_frame(params: PredictorParams, s: PredictorState, z_fr: jax.Array) -> PredictorState:
    """Shift the camera sample into the window, refit, and correct the filter with the fit."""
    sample = s.ins[:3] + rotation_z(s.ins[5]) @ z_fr
    window = jnp.concatenate([s.window[1:], sample[None]])
    fit = fit_window(params.weights, window)
    z = jnp.stack([fit[1], fit[0]], axis=1)  # (3, 2): [v̂, X̂] per axis
    kf = jax.vmap(lambda m, c, zz: kalman.update(GaussianState(m, c), zz, jnp.eye(2), params.meas_cov)[0])(
        s.kf.mean, s.kf.cov, z
    )
    return s._replace(window=window, fit=fit, t_frame=s.t, kf=kf, frames=s.frames + 1)


def _update(params: PredictorParams, s: PredictorState, y: jax.Array) -> PredictorState:
    ins, z_fr = y[:12], y[12:15]
    frame = (y[15] > 0.5) & (s.t >= params.t_start - 1e-9)
    s = s._replace(ins=ins)
    # only 1 tick in camera_period / h carries a frame: skip the refit otherwise (a select under vmap)
    return jax.lax.cond(frame, lambda st: _on_frame(params, st, z_fr), lambda st: st, s)


def _predict(params: PredictorParams, s: PredictorState, u: jax.Array, dt: Any) -> PredictorState:
    F, B, Q = double_integrator(dt, params.accel_psd)
    kf = jax.vmap(lambda m, c, a: kalman.predict(GaussianState(m, c), F, Q, B, a[None]))(s.kf.mean, s.kf.cov, s.fit[2])
    return s._replace(t=s.t + dt, kf=kf)


def target_estimate(params: PredictorParams, s: PredictorState) -> jax.Array:
    """``(3, 3)``: rows position, velocity, acceleration of the target point now (odometry frame)."""
    pos, vel, acc = s.fit
    if params.mode == "kalman":
        return jnp.stack([s.kf.mean[:, 1], s.kf.mean[:, 0], acc])
    if params.mode == "polynomial":
        tau = s.t - s.t_frame
        return jnp.stack([pos + vel * tau + 0.5 * acc * tau**2, vel + acc * tau, acc])
    return s.fit


def _read(params: PredictorParams, s: PredictorState) -> LeaderEstimate:
    position, velocity, acceleration = target_estimate(params, s)
    return LeaderEstimate(s.ins, position, velocity, acceleration)


def leader_predictor(
    window: int = 51,
    degree: int = 4,
    camera_period: float = 0.1,
    *,
    accel_psd: Any = 1e-3,
    meas_std: Any = 0.01,
    p0: Any = (1.0, 1.0),
    t_start: Any = 0.0,
    mode: str = "kalman",
) -> Estimator:
    """The estimator of the module docstring as a closed-loop :class:`Estimator`.

    ``window = M + 1`` samples (the paper's ``M = 50`` → 51), ``degree = N`` (4), spaced
    ``camera_period`` (0.1 s).  ``ValueError`` for an unknown ``mode``, ``window < degree + 1``,
    ``degree < 2`` (the filter needs an acceleration), non-positive noise levels or ``camera_period``,
    ``p0`` not of shape ``(2,)`` or a non-finite ``t_start``.
    """
    if mode not in MODES:
        raise ValueError(f"mode: expected one of {MODES}, got {mode!r}")
    if int(degree) < 2:
        raise ValueError(f"degree: must be at least 2 (the filter is driven by the fitted acceleration), got {degree}")
    check_positive("accel_psd", accel_psd)
    check_positive("meas_std", meas_std)
    check_shape("p0", p0, (2,))
    check_positive("p0", p0)
    check_positive("camera_period", camera_period)
    check_finite("t_start", t_start)
    weights = poly_window_weights(int(window), int(degree), camera_period)[:3]
    meas_cov = fit_covariance(weights, jnp.asarray(meas_std, dtype=float))  # differentiable in meas_std
    params = PredictorParams(
        weights,
        meas_cov,
        jnp.asarray(accel_psd, dtype=float),
        jnp.asarray(p0, dtype=float),
        jnp.asarray(t_start, dtype=float),
        mode,
    )
    return Estimator(params, _init, _predict, _update, _read, name=f"leader_predictor_{mode}")
