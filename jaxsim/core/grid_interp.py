"""Bilinear interpolation on a regular 2-D grid, differentiable (maps of geophysical fields, look-up
tables).  ``values (F, ny, nx)``: ``F`` fields on one grid whose node ``(j, i)`` lies at
``(x, y) = origin + spacing·(i, j)``."""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp


def bilinear(values: Any, origin: Any, spacing: float, points: Any) -> Any:
    """Bilinear interpolation of ``values (F, ny, nx)`` at ``points (..., 2)`` (x, y in m) →
    ``(..., F)``.  Points outside the grid are clamped to its edge cells (extrapolated linearly from
    them).  Differentiable in ``points`` and ``values``."""
    values = jnp.asarray(values)
    ny, nx = values.shape[-2:]
    u = (points - jnp.asarray(origin)) / spacing
    i = jnp.clip(jnp.floor(u[..., 0]), 0, nx - 2).astype(int)
    j = jnp.clip(jnp.floor(u[..., 1]), 0, ny - 2).astype(int)
    a, b = u[..., 0] - i, u[..., 1] - j
    v = jnp.moveaxis(values, 0, -1)  # (ny, nx, F)
    f00, f10, f01, f11 = v[j, i], v[j, i + 1], v[j + 1, i], v[j + 1, i + 1]
    a, b = a[..., None], b[..., None]
    return (1 - a) * (1 - b) * f00 + a * (1 - b) * f10 + (1 - a) * b * f01 + a * b * f11


def bilinear_jacobian(values: Any, origin: Any, spacing: float, points: Any) -> Any:
    """``∂φ/∂(x, y)`` of :func:`bilinear` at ``points (n, 2)`` → ``(n, F, 2)`` (field units per m)."""
    one = lambda p: jax.jacfwd(lambda q: bilinear(values, origin, spacing, q))(p)  # noqa: E731
    return jax.vmap(one)(jnp.asarray(points))
