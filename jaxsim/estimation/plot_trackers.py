"""Position trackers on 2-D radar plots, started from one plot: a CV Kalman filter and a CV +
coordinated-turn IMM, each returning its estimates and the one-scan predictions a gate checks.

Both start from the first plot ``z_0`` alone: position ``z_0`` with the plot covariance ``R``, zero
velocity (and turn rate) with prior spreads; the filters then run on ``z[1:]`` from the one-scan
prediction of that belief, so ``z_0`` is used exactly once.  Scan 0's estimate is the plot itself
and its "prediction" too (miss distance 0: a track cannot be lost at its first plot).
Units: metres, seconds; ``dt`` is the scan period.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from jaxsim.estimation.imm import imm_estimate, imm_init, imm_predict, imm_update
from jaxsim.estimation.lgssm import LinearGaussianSSM, kalman_filter
from jaxsim.estimation.motion_models import POSITION_2D, cv_ct_imm, cv_process_noise, cv_transition


class Track(NamedTuple):
    """A tracker's ``positions (T, 2)`` and the ``predicted (T, 2)`` plot each scan is gated against."""

    positions: jax.Array
    predicted: jax.Array


def one_plot_start(
    z0: jax.Array, R: jax.Array, velocity_prior_std: float, extra_std: tuple[float, ...] = ()
) -> tuple[jax.Array, jax.Array]:
    """Mean ``(4 + k,)`` and covariance of the belief after the first plot ``z0 (2,)``: position
    ``z0`` with covariance ``R (2, 2)``, zero velocity (and the ``k`` states of ``extra_std``)
    with the given prior standard deviations."""
    stds = jnp.asarray([velocity_prior_std, velocity_prior_std, *extra_std], float)
    m0 = jnp.concatenate([z0, jnp.zeros(stds.shape[0])])
    P0 = jax.scipy.linalg.block_diag(R, jnp.diag(stds**2))
    return m0, P0


def _with_first_plot(z: jax.Array, positions: jax.Array, predicted: jax.Array) -> Track:
    return Track(jnp.concatenate([z[:1], positions]), jnp.concatenate([z[:1], predicted]))


def kalman_cv_track(z: jax.Array, R: jax.Array, dt: float, q: float, velocity_prior_std: float) -> Track:
    """CV Kalman filter (white-noise acceleration PSD ``q``, m²/s³) on plots ``z (T, 2)`` with
    covariance ``R (2, 2)``, from a one-plot start."""
    F, Q = jnp.asarray(cv_transition(dt)), jnp.asarray(cv_process_noise(dt, q))
    m0, P0 = one_plot_start(z[0], R, velocity_prior_std)
    m1, P1 = F @ m0, F @ P0 @ F.T + Q
    res = kalman_filter(LinearGaussianSSM(F, Q, jnp.asarray(POSITION_2D), R, m1, P1), z[1:])
    return _with_first_plot(z, res.means[:, :2], res.predicted_means[:, :2])


def imm_cv_ct_track(
    z: jax.Array,
    R: jax.Array,
    dt: float,
    *,
    q_cv: float,
    q_ct: float,
    q_turn_rate: float,
    switch_prob: float,
    velocity_prior_std: float,
    turn_rate_prior_std: float,
) -> Track:
    """CV + coordinated-turn IMM (:func:`~jaxsim.estimation.motion_models.cv_ct_imm`, equal initial
    mode probabilities) from a one-plot start; the prediction is the mixture's."""
    model = cv_ct_imm(dt, q_cv, q_ct, q_turn_rate, R, switch_prob)
    m0, P0 = one_plot_start(z[0], R, velocity_prior_std, (turn_rate_prior_std,))
    prior = imm_predict(model, imm_init(jnp.stack([m0, m0]), jnp.stack([P0, P0]), jnp.array([0.5, 0.5])))

    def step(state: Any, y: jax.Array) -> tuple[Any, tuple[jax.Array, jax.Array]]:
        post, _ = imm_update(model, state, y)
        return imm_predict(model, post), (imm_estimate(post).mean[:2], imm_estimate(state).mean[:2])

    _, (pos, pred) = jax.lax.scan(step, prior, z[1:])
    return _with_first_plot(z, pos, pred)
