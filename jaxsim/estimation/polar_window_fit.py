"""Range/azimuth trajectory fitting for a secondary-radar indicator channel (seed 004 part 4 §B5, RSBN):
polar measurements with a quantised azimuth, and a sliding-window Gauss–Newton (Levenberg–Marquardt)
fit of a constant-velocity track to the last ``W`` scans.

Geometry: ``x`` east, ``y`` north (m); azimuth ``θ = atan2(x, y)`` clockwise from north (rad), range
``r = √(x² + y²)``.  Indicator azimuth, spec §B5: ``θ_m = q·round(θ/q) + n`` (``q = 2°``).
Azimuth residuals are wrapped to ``(−π, π]`` (:func:`wrap_angle`).
"""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp

from jaxsim.core.least_squares import levenberg_marquardt_solve


def polar(xy: Any) -> Any:
    """``(..., 2)`` east/north position (m) → ``(..., 2)`` (range m, azimuth rad from north)."""
    return jnp.stack([jnp.hypot(xy[..., 0], xy[..., 1]), jnp.arctan2(xy[..., 0], xy[..., 1])], -1)


def from_polar(z: Any) -> Any:
    """Inverse of :func:`polar`: ``(..., 2)`` (range, azimuth) → east/north (m)."""
    return jnp.stack([z[..., 0] * jnp.sin(z[..., 1]), z[..., 0] * jnp.cos(z[..., 1])], -1)


def wrap_angle(a: Any) -> Any:
    """``a`` wrapped to ``(−π, π]`` (rad)."""
    return jnp.pi - jnp.mod(jnp.pi - a, 2 * jnp.pi)


def quantise(theta: Any, step: Any) -> Any:
    """``step·round(θ/step)`` (the indicator's azimuth quantiser; rad)."""
    return step * jnp.round(theta / step)


def cv_positions(state: Any, dts: Any) -> Any:
    """Positions ``(W, 2)`` at times ``dts (W,)`` (s, relative to the state's time) of the
    constant-velocity ``state = (x, y, vx, vy)``."""
    return state[:2] + dts[:, None] * state[2:]


def window_fit(z: Any, dts: Any, sigma: Any, *, max_steps: int = 8) -> Any:
    """Weighted nonlinear least-squares CV fit ``(x, y, vx, vy)`` at ``dts = 0`` to the polar
    measurements ``z (W, 2)`` taken at ``dts (W,)`` (s), weights ``1/sigma (2,)`` (m, rad).  Started
    from the linear fit to the converted positions; ``max_steps`` LM steps (no second derivatives).
    Pure: jit/vmap over ``z`` and ``dts``."""
    if z.shape[0] < 2:
        raise ValueError(f"z: need at least 2 scans in the window, got {z.shape[0]}")
    xy = from_polar(z)
    A = jnp.stack([jnp.ones_like(dts), dts], 1)
    coef = jnp.linalg.lstsq(A, xy)[0]  # (2, 2): rows (position, velocity)
    u0 = jnp.concatenate([coef[0], coef[1]])
    sigma = jnp.asarray(sigma)

    def residuals(u):
        d = polar(cv_positions(u, dts)) - z
        return (jnp.stack([d[:, 0], wrap_angle(d[:, 1])], 1) / sigma).reshape(-1)

    return levenberg_marquardt_solve(residuals, u0, max_steps=max_steps).u
