"""Map-aided correction of a navigation system by scalar field measurements (seed 004 #33, spec part 3
§2.3): the position error ``Δ ∈ R²`` of the navigation system (NS) is constant over the observation,
and ``F`` field sensors (gravimeter, echo sounder) measure, eq. (1),

    ỹ_{i,f} = φ_f(y_i^NS − Δ) + c_f + v_{i,f},   c_f ~ N(0, σ_c,f²),  v_{i,f} ~ N(0, σ_w,f²) white,

with ``φ`` a gridded map (:mod:`jaxsim.core.grid_interp`; synthetic maps in
:mod:`jaxsim.plants.geophysical_map`).  Two estimators of ``Δ``:

* :func:`rb_posterior` — the paper's Bayesian Monte-Carlo estimate: ``N`` particles drawn from the
  prior ``N(0, σ_Δ² I)``, weighted by the likelihood with the biases ``c_f`` integrated out
  analytically (Rao-Blackwellisation: per field the residuals are ``N(0, σ_w² I + σ_c² 11ᵀ)``), giving
  the posterior mean and covariance;
* :func:`linearised_covariance` — the linearised (Kalman / Fisher-information) posterior covariance
  ``(P0⁻¹ + Σ_f H_fᵀ R_f⁻¹ H_f)⁻¹`` with ``H_f`` the map gradients along the track.

A ``mask (F,)`` of 0/1 selects which fields are used (single- vs two-field runs share one
compilation).  Units: metres for positions, field units for ``φ``, ``σ_c``, ``σ_w``.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from jaxsim.core.grid_interp import bilinear
from jaxsim.core.validation import check_positive, is_concrete


class MapPosterior(NamedTuple):
    """Posterior of ``Δ``: ``mean (2,)`` m, ``cov (2, 2)`` m², ``ess`` effective sample size."""

    mean: Any
    cov: Any
    ess: Any


def _check(sigma_c: Any, sigma_w: Any) -> None:
    if is_concrete(sigma_w):
        check_positive("sigma_w", sigma_w)
    if is_concrete(sigma_c):
        check_positive("sigma_c", sigma_c, allow_zero=True)


def marginal_log_likelihood(residuals: Any, sigma_c: Any, sigma_w: Any, mask: Any) -> Any:
    """``Σ_f mask_f · log N(r_f; 0, σ_w,f² I + σ_c,f² 11ᵀ)`` for ``residuals (F, n)`` (closed form by
    Sherman–Morrison; the bias ``c_f`` integrated out).  Broadcasts over leading axes of
    ``residuals (..., F, n)``."""
    r = jnp.asarray(residuals)
    n = r.shape[-1]
    sw2, sc2 = jnp.asarray(sigma_w) ** 2, jnp.asarray(sigma_c) ** 2
    s = jnp.sum(r, -1)
    quad = (jnp.sum(r * r, -1) - sc2 * s**2 / (sw2 + n * sc2)) / sw2
    logdet = n * jnp.log(sw2) + jnp.log1p(n * sc2 / sw2)
    return jnp.sum(jnp.asarray(mask) * -0.5 * (quad + logdet + n * jnp.log(2 * jnp.pi)), -1)


def simulate_measurements(
    key: jax.Array, values: Any, origin: Any, spacing: float, track: Any, sigma_c: Any, sigma_w: Any
) -> Any:
    """Noisy field readings ``(F, n)`` along the true ``track (n, 2)``: map value + bias + white noise."""
    _check(sigma_c, sigma_w)
    kc, kv = jax.random.split(key)
    phi = bilinear(values, origin, spacing, track).T  # (F, n)
    c = jnp.asarray(sigma_c)[:, None] * jax.random.normal(kc, (phi.shape[0], 1))
    return phi + c + jnp.asarray(sigma_w)[:, None] * jax.random.normal(kv, phi.shape)


def rb_posterior(
    key: jax.Array,
    values: Any,
    origin: Any,
    spacing: float,
    track_ns: Any,
    measurements: Any,
    sigma_c: Any,
    sigma_w: Any,
    mask: Any,
    prior_sigma: Any,
    n_particles: int,
) -> MapPosterior:
    """Monte-Carlo (importance-sampling from the prior) posterior of ``Δ`` given NS readings
    ``track_ns (n, 2)`` and ``measurements (F, n)``; ``n_particles`` static."""
    _check(sigma_c, sigma_w)
    if is_concrete(prior_sigma):
        check_positive("prior_sigma", prior_sigma)
    if int(n_particles) < 2:
        raise ValueError(f"n_particles: need at least 2, got {n_particles}")
    d = jnp.asarray(prior_sigma) * jax.random.normal(key, (int(n_particles), 2))
    pts = jnp.asarray(track_ns)[None, :, :] - d[:, None, :]  # (N, n, 2): y^NS − Δ_j
    res = jnp.asarray(measurements)[None] - jnp.moveaxis(bilinear(values, origin, spacing, pts), -1, 1)
    logw = marginal_log_likelihood(res, sigma_c, sigma_w, mask)
    w = jax.nn.softmax(logw)
    mean = w @ d
    e = d - mean
    cov = (e * w[:, None]).T @ e
    return MapPosterior(mean, cov, 1.0 / jnp.sum(w**2))


def linearised_covariance(jacobian: Any, sigma_c: Any, sigma_w: Any, mask: Any, prior_cov: Any) -> Any:
    """``(P0⁻¹ + Σ_f mask_f H_fᵀ R_f⁻¹ H_f)⁻¹`` with ``H_f = jacobian[:, f, :] (n, 2)`` the map gradient
    (field units per m) at the track points and ``R_f = σ_w,f² I + σ_c,f² 11ᵀ``; ``(2, 2)`` m²."""
    _check(sigma_c, sigma_w)
    h = jnp.moveaxis(jnp.asarray(jacobian), 1, 0)  # (F, n, 2)
    n = h.shape[1]
    sw2, sc2 = jnp.asarray(sigma_w) ** 2, jnp.asarray(sigma_c) ** 2
    hs = jnp.sum(h, 1)  # (F, 2): 1ᵀH
    info_f = (
        jnp.einsum("fni,fnj->fij", h, h) - (sc2 / (sw2 + n * sc2))[:, None, None] * hs[:, :, None] * hs[:, None, :]
    ) / sw2[:, None, None]
    info = jnp.linalg.inv(prior_cov) + jnp.einsum("f,fij->ij", jnp.asarray(mask, float), info_f)
    return jnp.linalg.inv(info)


def ellipse_area(cov: Any) -> Any:
    """Area ``π√det P`` of the RMS (1σ) error ellipse of ``cov (..., 2, 2)``, m²."""
    return jnp.pi * jnp.sqrt(jnp.linalg.det(cov))


def radial_rms(cov: Any) -> Any:
    """Radial RMS error ``√tr P`` (m) of ``cov (..., 2, 2)``."""
    return jnp.sqrt(jnp.trace(cov, axis1=-2, axis2=-1))
