"""Gridded geophysical field maps (gravity anomaly, sea depth) for map-aided navigation (seed 004 #33,
spec part 3 §2.3): a synthetic Gaussian random field scaled to a prescribed mean gradient modulus, and
differentiable bilinear look-up (:mod:`jaxsim.core.grid_interp`, re-exported).

A map is ``values (F, ny, nx)`` (``F`` fields on one grid) with the south-west node at ``origin`` (m)
and node ``spacing`` (m): node ``(j, i)`` lies at ``(x, y) = origin + spacing·(i, j)`` (x east, y north).

Field model (an assumption: the paper shows its maps only in a figure): white noise filtered in the
Fourier domain by a Gaussian spectrum, i.e. covariance ``K(r) ∝ exp(−r²/(2ℓ²))`` with correlation
length ``ℓ`` (m), then scaled so that the mean gradient modulus over the grid (central differences)
equals ``mean_gradient`` (field units per m).  Periodic, so ``ℓ`` should be well below the grid extent.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.grid_interp import bilinear, bilinear_jacobian
from jaxsim.core.validation import check_positive, is_concrete

__all__ = [
    "anisotropic_random_field",
    "bilinear",
    "bilinear_jacobian",
    "gaussian_random_field",
    "gradient_field",
    "mean_axis_gradients",
    "mean_gradient_modulus",
]


def gradient_field(values: Any, spacing: float) -> tuple[Any, Any]:
    """``(∂f/∂x, ∂f/∂y)`` of ``values (..., ny, nx)`` by central differences (one-sided at the edges), per m."""
    gy, gx = jnp.gradient(values, spacing, axis=(-2, -1))
    return gx, gy


def mean_gradient_modulus(values: Any, spacing: float) -> Any:
    """Mean of ``|∇f|`` over the grid (field units per m); shape ``values.shape[:-2]``."""
    gx, gy = gradient_field(values, spacing)
    return jnp.mean(jnp.hypot(gx, gy), axis=(-2, -1))


def gaussian_random_field(
    key: jax.Array, shape: tuple[int, int], spacing: float, corr_length: Any, mean_gradient: Any
) -> Any:
    """One realisation ``(ny, nx)`` with Gaussian covariance of length ``corr_length`` (m), zero mean,
    scaled to mean ``|∇f| = mean_gradient`` (units/m).  ``corr_length`` and ``mean_gradient`` may be
    traced (vmap over them or over ``key``); ``shape`` and ``spacing`` are static."""
    ny, nx = shape
    if is_concrete(corr_length):
        check_positive("corr_length", corr_length)
    if is_concrete(mean_gradient):
        check_positive("mean_gradient", mean_gradient)
    check_positive("spacing", spacing)
    if ny < 3 or nx < 3:
        raise ValueError(f"shape: need at least 3×3 nodes, got {shape}")
    kx = 2 * jnp.pi * jnp.fft.fftfreq(nx, spacing)
    ky = 2 * jnp.pi * jnp.fft.fftfreq(ny, spacing)
    k2 = ky[:, None] ** 2 + kx[None, :] ** 2
    amp = jnp.exp(-0.25 * k2 * corr_length**2)  # √S(k) of the Gaussian covariance
    f = jnp.fft.ifft2(jnp.fft.fft2(jax.random.normal(key, shape)) * amp).real
    f = f - jnp.mean(f)
    return f * (mean_gradient / mean_gradient_modulus(f, spacing))


def mean_axis_gradients(values: Any, spacing: float) -> tuple[Any, Any]:
    """``(mean |∂f/∂x|, mean |∂f/∂y|)`` over the grid (field units per m, or per the unit of ``spacing``)."""
    gx, gy = gradient_field(values, spacing)
    return jnp.mean(jnp.abs(gx), axis=(-2, -1)), jnp.mean(jnp.abs(gy), axis=(-2, -1))


def anisotropic_random_field(
    key: jax.Array, shape: tuple[int, int], spacing: float, corr_length: Any, mean_gradients: Any
) -> Any:
    """One zero-mean realisation ``(ny, nx)`` with mean ``|∂f/∂x| ≈ g_x`` and ``|∂f/∂y| ≈ g_y``
    (``mean_gradients = (g_x, g_y)``, units per unit of ``spacing``).

    Gaussian covariance with lengths ``ℓ_x = ℓ√(g_y/g_x)``, ``ℓ_y = ℓ√(g_x/g_y)`` (geometric mean
    ``ℓ = corr_length``), so that the expected ratio of the mean axis gradients is ``g_x/g_y``; then one
    scale factor makes ``mean|∂f/∂x| + mean|∂f/∂y| = g_x + g_y`` exactly (each axis alone only up to the
    realisation's scatter: report :func:`mean_axis_gradients`)."""
    ny, nx = shape
    check_positive("spacing", spacing)
    if is_concrete(corr_length):
        check_positive("corr_length", corr_length)
    g = jnp.asarray(mean_gradients, dtype=float)
    if g.shape != (2,):
        raise ValueError(f"mean_gradients: expected (g_x, g_y), got shape {tuple(g.shape)}")
    if is_concrete(g):
        check_positive("mean_gradients", g)
    if ny < 3 or nx < 3:
        raise ValueError(f"shape: need at least 3×3 nodes, got {shape}")
    lx = corr_length * jnp.sqrt(g[1] / g[0])
    ly = corr_length * jnp.sqrt(g[0] / g[1])
    kx = 2 * jnp.pi * jnp.fft.fftfreq(nx, spacing)
    ky = 2 * jnp.pi * jnp.fft.fftfreq(ny, spacing)
    amp = jnp.exp(-0.25 * ((ky[:, None] * ly) ** 2 + (kx[None, :] * lx) ** 2))
    f = jnp.fft.ifft2(jnp.fft.fft2(jax.random.normal(key, shape)) * amp).real
    f = f - jnp.mean(f)
    ax, ay = mean_axis_gradients(f, spacing)
    return f * ((g[0] + g[1]) / (ax + ay))
