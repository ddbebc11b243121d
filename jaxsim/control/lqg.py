"""LQG: an LQR state feedback on the estimate of a steady-state Kalman–Bucy observer.

Plant ``ẋ = A x + B u + G w``, ``y = C x + v``.  The compensator from ``y`` to ``u`` is

    x̂̇ = (A − B K − L C) x̂ + L y,      u = −K x̂,

with ``K`` from :func:`~jaxsim.control.lqr.lqr` and ``L`` from
:func:`~jaxsim.control.kalman_gain.kalman_bucy`.  By the separation principle the closed loop's
eigenvalues are those of ``A − B K`` together with those of ``A − L C``.  Differentiable in every
weight and noise intensity.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from jaxsim.control.kalman_gain import KalmanBucyGain, kalman_bucy
from jaxsim.control.lqr import LQRGain, lqr


class StateSpace(NamedTuple):
    """``ẋ = a x + b u``, ``y = c x + d u``."""

    a: jax.Array
    b: jax.Array
    c: jax.Array
    d: jax.Array


class LQG(NamedTuple):
    controller: StateSpace  # from y (p,) to u (m,)
    regulator: LQRGain
    observer: KalmanBucyGain


def lqg_compensator(a, b, c, k, l) -> StateSpace:  # noqa: E741
    """Observer-based compensator ``(A − BK − LC, L, −K, 0)`` for gains ``k (m, n)``, ``l (n, p)``."""
    a, b, c, k, l = (jnp.asarray(v) for v in (a, b, c, k, l))  # noqa: E741
    return StateSpace(a - b @ k - l @ c, l, -k, jnp.zeros((k.shape[0], c.shape[0]), a.dtype))


def lqg(a, b, c, q, r, w, v, g=None) -> LQG:
    """LQR weights ``q (n, n)``, ``r (m, m)``; noise intensities ``w``, ``v`` (and ``g``) as
    :func:`~jaxsim.control.kalman_gain.kalman_bucy`."""
    reg = lqr(a, b, q, r)
    obs = kalman_bucy(a, c, w, v, g)
    return LQG(lqg_compensator(a, b, c, reg.k, obs.l), reg, obs)


def feedback_matrix(a, b, c, controller: StateSpace) -> jax.Array:
    """State matrix ``(n + n_c, n + n_c)`` of plant ``(a, b, c)`` in negative-free feedback with
    ``controller`` (``u = controller(y)``; the controller already carries its sign)."""
    a, b, c = (jnp.asarray(v) for v in (a, b, c))
    ac, bc, cc, dc = controller
    top = jnp.concatenate([a + b @ dc @ c, b @ cc], axis=1)
    bottom = jnp.concatenate([bc @ c, ac], axis=1)
    return jnp.concatenate([top, bottom], axis=0)
