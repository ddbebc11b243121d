"""Heading from a continuously rotated (carousel) gyro by least squares (seed 004 part 2, paper #27, spec §2.1).

A single gyro whose sensitive axis is horizontal and turned at the constant rate ``Ω`` about the
vertical measures (eq. 2)::

    ω(t) = Ω_E cos φ · cos(K0 + Ω t) + ω0 + ξ(t)

with ``K0`` the heading of the axis at ``t = 0``, ``φ`` the latitude, ``ω0`` the bias and ``ξ`` white
noise.  Stacking ``y_n = [cos Ω t_n, −sin Ω t_n, 1]·[A, B, ω0]ᵀ + ξ_n`` (``A = Ω_H cos K0``,
``B = Ω_H sin K0``, ``Ω_H = Ω_E cos φ``), the batch least-squares estimate gives
``K̂0 = atan2(B̂, Â)`` (eqs. 3–4, reconstructed).  For white noise of density ``N`` (per-sample
``σ = N√fs``, the paper's convention) over an integer number of turns,
``σ_K ≈ N·√(2/T)/Ω_H`` (:func:`closed_form_heading_std`).

:func:`heading_error_budget` gives the linearised heading variance of the same estimator from three
sources, as a differentiable function of ``(Ω, T)`` (for design by gradient): white noise, a rate
random walk of the bias (intensity ``K²``: it is not in the model, which has a constant bias) and a
relative error ``ε`` of the turntable rate (the model's phase ``Ω t`` is off by ``εΩt``).
Over whole turns it reduces to the closed form of :func:`whole_turn_budget`, which is smooth in
``(Ω, T)`` (the general budget ripples with the fractional turn) and so suits design by gradient.
Angles in rad, rates in rad/s unless a name says deg.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from jaxsim.core.validation import check_positive, check_positive_int, check_shape

__all__ = [
    "EARTH_RATE",
    "HeadingBudget",
    "HeadingEstimate",
    "carousel_rate",
    "closed_form_heading_std",
    "heading_error_budget",
    "heading_ls",
    "whole_turn_budget",
    "regressors",
]

EARTH_RATE = 7.292115e-5  # rad/s, WGS-84 (spec §2.1 of seed004_part2)


class HeadingEstimate(NamedTuple):
    """``heading`` (rad, in (−π, π]), ``heading_var`` (rad², linearised, from ``cov``), ``theta (3,)``
    = ``[A, B, ω0]``, ``cov (3, 3)`` = ``σ²(HᵀH)⁻¹``."""

    heading: jax.Array
    heading_var: jax.Array
    theta: jax.Array
    cov: jax.Array


class HeadingBudget(NamedTuple):
    """Heading variances (rad²) by source, averaged over the initial heading: ``white``,
    ``rate_random_walk``, ``table_rate``, and their sum ``total``."""

    white: jax.Array
    rate_random_walk: jax.Array
    table_rate: jax.Array
    total: jax.Array


def carousel_rate(t: Any, heading0: Any, rotation_rate: Any, latitude: Any, bias: Any = 0.0) -> jax.Array:
    """Noise-free gyro output of eq. (2) at times ``t`` (s): ``Ω_E cos φ cos(K0 + Ω t) + ω0`` (rad/s)."""
    t = jnp.asarray(t, float)
    return EARTH_RATE * jnp.cos(latitude) * jnp.cos(heading0 + rotation_rate * t) + bias


def regressors(t: Any, rotation_rate: Any) -> jax.Array:
    """``(n, 3)`` rows ``[cos Ω t, −sin Ω t, 1]``."""
    t = jnp.asarray(t, float)
    return jnp.stack([jnp.cos(rotation_rate * t), -jnp.sin(rotation_rate * t), jnp.ones_like(t)], axis=-1)


def _heading_gradient(theta: jax.Array) -> jax.Array:
    a, b = theta[0], theta[1]
    r2 = a * a + b * b
    return jnp.stack([-b / r2, a / r2, jnp.zeros_like(a)])


def heading_ls(t: Any, y: Any, rotation_rate: Any, sigma: Any) -> HeadingEstimate:
    """Batch least squares of eqs. (3–4) on samples ``y (n,)`` (rad/s) at times ``t (n,)`` (s), turning
    at ``rotation_rate`` (rad/s), with per-sample noise std ``sigma`` (rad/s) for the covariance.
    Pure JAX (jit/vmap over runs)."""
    t, y = jnp.asarray(t, float), jnp.asarray(y, float)
    check_shape("t", t, (None,))
    check_shape("y", y, t.shape)
    if t.shape[0] < 3:
        raise ValueError(f"t: need at least 3 samples for 3 unknowns, got {t.shape[0]}")
    check_positive("sigma", sigma)
    h = regressors(t, rotation_rate)
    info = h.T @ h
    theta = jnp.linalg.solve(info, h.T @ y)
    cov = sigma**2 * jnp.linalg.inv(info)
    g = _heading_gradient(theta)
    return HeadingEstimate(jnp.arctan2(theta[1], theta[0]), g @ cov @ g, theta, cov)


def closed_form_heading_std(noise_density: Any, duration: Any, latitude: Any) -> jax.Array:
    """``σ_K = N·√(2/T)/(Ω_E cos φ)`` (rad): white noise of density ``N`` (rad/s/√Hz, per-sample
    ``σ = N√fs``) over ``T`` (s) of an integer number of turns (spec §2.1, first order)."""
    return noise_density * jnp.sqrt(2.0 / jnp.asarray(duration, float)) / (EARTH_RATE * jnp.cos(latitude))


def heading_error_budget(
    rotation_rate: Any,
    duration: Any,
    latitude: Any,
    noise_density: Any,
    rate_random_walk: Any = 0.0,
    table_rate_error: Any = 0.0,
    *,
    n_quad: int = 4096,
) -> HeadingBudget:
    """Linearised heading variance of :func:`heading_ls` (continuous-time limit, ``fs → ∞`` at fixed
    ``N``) for a carousel turning at ``rotation_rate`` (rad/s) for ``duration`` ``T`` (s).

    Sources: white noise of density ``noise_density`` ``N`` (rad/s/√Hz, per-sample ``σ = N√fs``):
    ``N²·G⁻¹`` with ``G = ∫₀ᵀ h hᵀ dt``; a bias random walk ``ḃ = K·w`` (``rate_random_walk`` ``K``,
    rad/s/√s): ``G⁻¹ (K² ∫₀ᵀ H(s) H(s)ᵀ ds) G⁻¹`` with ``H(s) = ∫ₛᵀ h dt``; a random relative error
    of the table rate with std ``table_rate_error`` ``ε``: ``ε²·E_K0[(g·G⁻¹∫ h·∂y/∂ε dt)²]``.  Each is
    mapped to the heading by ``g = ∂K/∂(A, B) = (−sin K0, cos K0)/Ω_H`` and averaged over a uniform
    ``K0`` (in closed form).  ``G`` is analytic; the ``s``-integral uses
    ``n_quad`` midpoints (it needs ≳ 8 points per turn).  Differentiable in every argument.
    """
    n_quad = check_positive_int("n_quad", n_quad)
    w, T = jnp.asarray(rotation_rate, float), jnp.asarray(duration, float)
    omega_h = EARTH_RATE * jnp.cos(latitude)
    s2, c2 = jnp.sin(2 * w * T), jnp.cos(2 * w * T)
    sin_t, cos_t = jnp.sin(w * T), jnp.cos(w * T)
    # G = ∫ h hᵀ, h = [cos wt, −sin wt, 1]
    g_cc = T / 2 + s2 / (4 * w)
    g_ss = T / 2 - s2 / (4 * w)
    g_cs = -(1 - c2) / (4 * w)  # ∫ cos·(−sin)
    g_c1 = sin_t / w
    g_s1 = -(1 - cos_t) / w
    G = jnp.array([[g_cc, g_cs, g_c1], [g_cs, g_ss, g_s1], [g_c1, g_s1, T]])
    G_inv = jnp.linalg.inv(G)
    p_white = noise_density**2 * G_inv
    # H(s) = ∫_s^T h dt on midpoints
    s = (jnp.arange(n_quad) + 0.5) * T / n_quad
    H = jnp.stack([(sin_t - jnp.sin(w * s)) / w, (cos_t - jnp.cos(w * s)) / w, T - s], axis=-1)
    M = rate_random_walk**2 * (H.T @ H) * (T / n_quad)
    p_rw = G_inv @ M @ G_inv

    def ab_var(p):
        return (p[0, 0] + p[1, 1]) / (2 * omega_h**2)

    # table-rate error: ∂y/∂ε = −Ω_H w t sin(K0 + w t) = −Ω_H w t (sin K0 cos wt + cos K0 sin wt), so
    # δθ = −Ω_H w (sin K0·u + cos K0·v) with u = G⁻¹∫ t h cos wt, v = G⁻¹∫ t h sin wt, and
    # δK = (−sin K0 δθ_A + cos K0 δθ_B)/Ω_H = −w(a sin²K0 + b sinK0 cosK0 + c cos²K0); over a uniform K0
    # E[sin⁴] = E[cos⁴] = 3/8, E[sin²cos²] = 1/8
    h_mid = jnp.stack([jnp.cos(w * s), -jnp.sin(w * s), jnp.ones_like(s)], axis=-1)
    u = G_inv @ (h_mid.T @ (s * jnp.cos(w * s))) * (T / n_quad)
    v = G_inv @ (h_mid.T @ (s * jnp.sin(w * s))) * (T / n_quad)
    a, b, c = -u[0], u[1] - v[0], v[1]
    table = table_rate_error**2 * w**2 * (3 * a**2 + b**2 + 3 * c**2 + 2 * a * c) / 8
    white, rw = ab_var(p_white), ab_var(p_rw)
    return HeadingBudget(white, rw, table, white + rw + table)


def whole_turn_budget(
    rotation_rate: Any,
    duration: Any,
    latitude: Any,
    noise_density: Any,
    rate_random_walk: Any = 0.0,
    table_rate_error: Any = 0.0,
) -> HeadingBudget:
    """:func:`heading_error_budget` over a whole number of turns (``ΩT = 2πk``), in closed form::

        σ_K² = (2N²/T + 4K²/(T Ω²)) / Ω_H²  +  ε²(2Ω²T² + 1)/8

    (``G = diag(T/2, T/2, T)``; the random walk enters through ``∫ H Hᵀ`` = ``K²T/(2Ω²)`` and
    ``3K²T/(2Ω²)`` on the A and B diagonal; the table-rate error shifts the phase by about ``εΩT/2``).
    At fixed ``T`` the best rate is ``Ω*⁴ = 16K²/(ε² T³ Ω_H²)``.  Smooth in every argument."""
    w, T = jnp.asarray(rotation_rate, float), jnp.asarray(duration, float)
    omega_h2 = (EARTH_RATE * jnp.cos(latitude)) ** 2
    white = 2 * noise_density**2 / (T * omega_h2)
    rw = 4 * rate_random_walk**2 / (T * w**2 * omega_h2)
    table = table_rate_error**2 * (2 * w**2 * T**2 + 1) / 8
    return HeadingBudget(white, rw, table, white + rw + table)
