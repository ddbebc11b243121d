"""Steady-state Kalman gains: Kalman–Bucy (continuous) and discrete, from the dual Riccati equations.

Continuous model ``ẋ = A x + B u + G w``, ``y = C x + v`` with white noises of intensities
(power spectral densities) ``E[w(t)w(s)ᵀ] = W δ(t−s)``, ``E[v(t)v(s)ᵀ] = V δ(t−s)``: the error
covariance ``P`` solves ``A P + P Aᵀ − P Cᵀ V⁻¹ C P + G W Gᵀ = 0`` (the CARE of ``(Aᵀ, Cᵀ)``) and the
observer ``x̂̇ = A x̂ + B u + L (y − C x̂)`` has ``L = P Cᵀ V⁻¹`` (python-control's ``lqe``).

Discrete model ``x⁺ = A x + B u + G w``, ``y = C x + v``, covariances ``Q``, ``R``: the prior
covariance solves the DARE of ``(Aᵀ, Cᵀ)``; the update gain is ``K = P⁻Cᵀ(CP⁻Cᵀ + R)⁻¹`` and the
posterior covariance is formed in Joseph form ``(I−KC)P⁻(I−KC)ᵀ + KRKᵀ``.  The predictor-form gain
of ``control.dlqe``-style observers ``x̂⁺ = A x̂ + B u + L (y − C x̂)`` is ``L = A K``.

Both need ``(A, C)`` detectable and no mode on the stability boundary uncontrollable from the
process noise (else ``ValueError`` on concrete inputs, judged on the balanced data after the solve;
NaN under tracing).  ``discrete_kalman`` accepts a singular measurement covariance ``R ⪰ 0`` when
``C P⁻ Cᵀ + R ≻ 0``.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
from jax.scipy.linalg import cho_factor, cho_solve

from jaxsim.control.riccati import (
    check_positive_semidefinite,
    check_stabilising,
    prepare_riccati_inputs,
    solve_continuous_are,
    solve_discrete_are,
)


class KalmanBucyGain(NamedTuple):
    """``l``: observer gain ``(n, p)``; ``p``: steady-state error covariance ``(n, n)``."""

    l: jax.Array  # noqa: E741
    p: jax.Array


class DiscreteKalmanGain(NamedTuple):
    """``k``: update gain ``(n, p)``; ``p_prior``, ``p_post``: steady-state covariances ``(n, n)``."""

    k: jax.Array
    p_prior: jax.Array
    p_post: jax.Array


def _noise_input(a, c, w, g):
    a = jnp.asarray(a)
    c = jnp.asarray(c)
    w = jnp.asarray(w)
    if c.ndim == 1:
        c = c.reshape(1, -1)
    if g is None:
        return a, c, w
    g = jnp.asarray(g)
    if g.ndim != 2 or g.shape[0] != a.shape[0] or w.shape != (g.shape[1], g.shape[1]):
        raise ValueError(f"g: expected shape ({a.shape[0]}, {w.shape[0]}) to match w, got {tuple(g.shape)}")
    return a, c, g @ w @ g.T


def _checked_dual(a, c, w, v, g, discrete: bool, names: tuple[str, str, str, str]):
    _, cn, wn, _ = names
    a, c, gwg = _noise_input(a, c, w, g)
    if c.ndim != 2 or (a.ndim == 2 and c.shape[1] != a.shape[0]):
        raise ValueError(f"{cn}: expected shape (p, {a.shape[0]}), got {tuple(c.shape)}")
    at, ct, gwg, v = prepare_riccati_inputs(a.T, c.T, gwg, v, names=names, r_definite=not discrete)
    check_positive_semidefinite(wn, gwg)
    return at, ct, gwg, v


def kalman_bucy(a, c, w, v, g=None, *, names: tuple[str, str, str, str] = ("a", "c", "w", "v")) -> KalmanBucyGain:
    """Steady-state Kalman–Bucy gain.

    Args:
        a: ``(n, n)``; c: ``(p, n)``; w: process-noise intensity ``(q, q)`` (``(n, n)`` without
            ``g``), symmetric ⪰ 0; v: measurement-noise intensity ``(p, p)``, symmetric ≻ 0;
        g: optional noise input matrix ``(n, q)``.
        names: the caller's names of ``(a, c, w, v)``, used in error messages.
    """
    at, ct, gwg, v = _checked_dual(a, c, w, v, g, discrete=False, names=names)
    p = solve_continuous_are(at, ct, gwg, v, names=names, dual=True)
    check_stabilising(p, at, ct, gwg, v, discrete=False, names=names, dual=True)
    return KalmanBucyGain(cho_solve(cho_factor(v), ct.T @ p).T, p)


def discrete_kalman(
    a, c, q, r, g=None, *, names: tuple[str, str, str, str] = ("a", "c", "q", "r")
) -> DiscreteKalmanGain:
    """Steady-state discrete Kalman filter gain and covariances (argument shapes as :func:`kalman_bucy`,
    with ``q``, ``r`` the process and measurement covariances per step)."""
    at, ct, gqg, r = _checked_dual(a, c, q, r, g, discrete=True, names=names)
    p_prior = solve_discrete_are(at, ct, gqg, r, names=names, dual=True)
    check_stabilising(p_prior, at, ct, gqg, r, discrete=True, names=names, dual=True)
    c = ct.T
    s = c @ p_prior @ c.T + r
    k = cho_solve(cho_factor(s), c @ p_prior).T
    ikc = jnp.eye(p_prior.shape[0], dtype=p_prior.dtype) - k @ c
    p_post = ikc @ p_prior @ ikc.T + k @ r @ k.T
    return DiscreteKalmanGain(k, p_prior, 0.5 * (p_post + p_post.T))
