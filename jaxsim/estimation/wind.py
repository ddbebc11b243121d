"""Wind in the longitudinal plane from air data + INS (seed 004 part 3, #11, Chechulina; spec
``seed004_part3.md`` §2.6), and a Kalman filter for it.

The algebraic estimator, eqs. (1)–(2) (signs reconstructed, spec §2.6)::

    α_k = ϑ − arcsin(Ḣ/V_k)                      (angle of attack "including the disturbance")
    W_x = V_k cos(ϑ − α_k) − V cos(ϑ − α)        (horizontal wind, along the flight direction)
    W_y = V_k sin(ϑ − α_k) − V sin(ϑ − α)        (vertical wind)

with ``V_k`` the ground speed and ``Ḣ`` the vertical rate (INS), ``ϑ`` the pitch (INS), ``V`` the true
airspeed and ``α`` the angle of attack (air data).  With ideal sensors it is exact: ``V_k cos(ϑ − α_k)``
is the horizontal ground speed and ``V cos(ϑ − α)`` the horizontal air speed.  Units: m/s and rad.

The filter: the wind is a slowly varying mean (random walk) plus turbulence (first-order Gauss–Markov
per component, intensity ``σ_t`` m/s and correlation time ``τ`` s); the algebraic estimate is its
measurement, with a time-varying covariance ``R_t = J Σ Jᵀ`` from the sensor noise ``Σ`` through the
Jacobian ``J`` of eqs. (1)–(2) (:func:`measurement_cov`).  State ``[W̄_x, W̄_y, w_x, w_y]``, wind
``W = W̄ + w``.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from jaxsim.estimation.lgssm import LinearGaussianSSM, lgssm

__all__ = [
    "AirData",
    "flight_path_alpha",
    "measurement_cov",
    "wind_components",
    "wind_filter_model",
    "wind_from_air_data",
]


class AirData(NamedTuple):
    """One sample (or a ``(T,)`` series) of the estimator's inputs: ground speed ``v_ground`` (m/s),
    vertical rate ``h_dot`` (m/s, up), pitch (rad), true airspeed ``v_air`` (m/s), angle of attack
    ``alpha`` (rad)."""

    v_ground: jax.Array
    h_dot: jax.Array
    pitch: jax.Array
    v_air: jax.Array
    alpha: jax.Array


def flight_path_alpha(pitch: jax.Array, h_dot: jax.Array, v_ground: jax.Array) -> jax.Array:
    """Eq. (2): ``α_k = ϑ − arcsin(Ḣ/V_k)`` (rad)."""
    return pitch - jnp.arcsin(h_dot / v_ground)


def wind_from_air_data(d: AirData) -> jax.Array:
    """Eq. (1): ``[W_x, W_y]`` (m/s) from one sample; ``(..., 2)`` for series (broadcasts)."""
    alpha_k = flight_path_alpha(d.pitch, d.h_dot, d.v_ground)
    wx = d.v_ground * jnp.cos(d.pitch - alpha_k) - d.v_air * jnp.cos(d.pitch - d.alpha)
    wy = d.v_ground * jnp.sin(d.pitch - alpha_k) - d.v_air * jnp.sin(d.pitch - d.alpha)
    return jnp.stack([wx, wy], axis=-1)


def wind_components(speed: jax.Array, azimuth: jax.Array, inclination: jax.Array) -> jax.Array:
    """Eq. (3) in the flight plane: ``[W cos δ_w cos K_w, W sin δ_w]`` (m/s) for the wind speed ``W``,
    azimuth ``K_w`` relative to the flight direction and inclination ``δ_w`` (rad)."""
    return jnp.stack([speed * jnp.cos(inclination) * jnp.cos(azimuth), speed * jnp.sin(inclination)], axis=-1)


def measurement_cov(d: AirData, sensor_std: jax.Array) -> jax.Array:
    """``R = J diag(σ²) Jᵀ`` ``(2, 2)`` of the algebraic estimate for sensor errors of standard deviations
    ``sensor_std (5,)`` in the order of :class:`AirData` (first-order propagation at the sample ``d``)."""
    x = jnp.stack(d)
    jac = jax.jacfwd(lambda z: wind_from_air_data(AirData(*z)))(x)
    return (jac * jnp.asarray(sensor_std) ** 2) @ jac.T


def wind_filter_model(
    dt: float,
    tau: jax.Array,
    sigma_turbulence: jax.Array,
    q_mean: jax.Array,
    r: jax.Array,
    sigma_mean0: float = 10.0,
) -> LinearGaussianSSM:
    """The 4-state wind model: mean ``W̄`` a random walk of intensity ``q_mean`` ((m/s)²/s), turbulence
    ``w`` Gauss–Markov with ``φ = e^{−dt/τ}``, stationary variance ``σ_t²``; ``H = [I I]``; ``r (T, 2, 2)``
    the measurement covariances (:func:`measurement_cov` per sample); prior: mean wind unknown
    (``σ = sigma_mean0`` m/s), turbulence stationary."""
    phi = jnp.exp(-dt / tau)
    eye = jnp.eye(2)
    zero = jnp.zeros((2, 2))
    f = jnp.block([[eye, zero], [zero, phi * eye]])
    q = jnp.block([[q_mean * dt * eye, zero], [zero, sigma_turbulence**2 * (1 - phi**2) * eye]])
    p0 = jnp.block([[sigma_mean0**2 * eye, zero], [zero, sigma_turbulence**2 * eye]])
    return lgssm(f, q, jnp.concatenate([eye, eye], axis=1), r, jnp.zeros(4), p0)
