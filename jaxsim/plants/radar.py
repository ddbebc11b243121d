"""2-D rotating surveillance radar: range and bearing plots once per scan, converted to Cartesian.

Seed 003 (section 4): a 2-D circular-scan radar ("e.g. Raytheon type") with a rotation period of
3 s and resolutions of 0.03° in bearing and 6 m in range; the tracker works on Cartesian plots.
The paper gives no error model (the plot is the centroid of an extended echo, Fig. 3, known "only
to an order of magnitude"), so a plot here is

    r̃ = r + σ_r n_r,   β̃ = β + σ_β n_β                      (n ~ N(0, 1), independent)
    r_q = Δr · round(r̃ / Δr),   β_q = Δβ · round(β̃ / Δβ)   (the resolution cell's centre)
    z = radar position + r_q (cos β_q, sin β_q)

with ``Δr = 6 m``, ``Δβ = 0.03°`` (a resolution of 0 switches the quantisation off) and the noise
levels ``σ_r``, ``σ_β`` chosen by the user.  Bearings are mathematical angles (from the x axis,
counter-clockwise), in radians.  :func:`cartesian_covariance` is the first-order covariance of the
converted plot (noise plus the uniform quantisation error ``Δ²/12``), for Kalman-type trackers.

:func:`radar_sensor` wraps the model as a :class:`~jaxsim.core.system.Sensor` for closed loops.
"""

from __future__ import annotations

import math
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.pytree import pytree_dataclass, static_field
from jaxsim.core.system import Sensor
from jaxsim.core.validation import check_finite, check_positive, check_shape

PAPER_SCAN_PERIOD = 3.0  # s, seed 003 section 4
PAPER_RANGE_RESOLUTION = 6.0  # m
PAPER_BEARING_RESOLUTION = math.radians(0.03)  # rad


@pytree_dataclass
class Radar2D:
    """Radar parameters: noise ``range_std`` (m), ``bearing_std`` (rad); resolutions (m, rad; 0 = no
    quantisation); ``position (2,)`` (m); static ``period`` (s, one plot per scan)."""

    range_std: Any = 0.0
    bearing_std: Any = 0.0
    range_resolution: Any = PAPER_RANGE_RESOLUTION
    bearing_resolution: Any = PAPER_BEARING_RESOLUTION
    position: Any = (0.0, 0.0)
    period: float = static_field(default=PAPER_SCAN_PERIOD)


def radar(
    range_std: Any = 0.0,
    bearing_std: Any = 0.0,
    *,
    period: float = PAPER_SCAN_PERIOD,
    range_resolution: Any = PAPER_RANGE_RESOLUTION,
    bearing_resolution: Any = PAPER_BEARING_RESOLUTION,
    position: Any = (0.0, 0.0),
) -> Radar2D:
    """Validated :class:`Radar2D`.

    Raises:
        ValueError: ``period ≤ 0`` (or not finite); negative noise levels or resolutions;
            ``position`` not ``(2,)`` or not finite.
    """
    period_np = np.asarray(period, dtype=float)
    if period_np.shape != () or not np.isfinite(period_np) or period_np <= 0:
        raise ValueError(f"period: the scan period must be a positive number of seconds, got {period!r}")
    for name, value in (
        ("range_std", range_std),
        ("bearing_std", bearing_std),
        ("range_resolution", range_resolution),
        ("bearing_resolution", bearing_resolution),
    ):
        check_positive(name, value, allow_zero=True)
    check_shape("position", position, (2,))
    check_finite("position", position)
    f = lambda v: jnp.asarray(v, float)  # noqa: E731
    return Radar2D(
        f(range_std), f(bearing_std), f(range_resolution), f(bearing_resolution), f(position), float(period_np)
    )


def scan_times(sensor: Radar2D, t_final: float) -> np.ndarray:
    """Scan instants ``0, τ, 2τ, … ≤ t_final`` (s), as a NumPy array (a static length)."""
    check_positive("t_final", t_final, allow_zero=True)
    n = int(math.floor(float(t_final) / sensor.period + 1e-9)) + 1
    return np.arange(n) * sensor.period


def polar(sensor: Radar2D, position: jax.Array) -> tuple[jax.Array, jax.Array]:
    """True range (m) and bearing (rad) of ``position (…, 2)`` from the radar."""
    d = jnp.asarray(position) - jnp.asarray(sensor.position)
    return jnp.hypot(d[..., 0], d[..., 1]), jnp.arctan2(d[..., 1], d[..., 0])


def _quantise(x: jax.Array, cell: jax.Array) -> jax.Array:
    on = cell > 0
    safe = jnp.where(on, cell, 1.0)
    return jnp.where(on, jnp.round(x / safe) * safe, x)


def measure(sensor: Radar2D, key: jax.Array, position: Any) -> jax.Array:
    """Cartesian plots ``(…, 2)`` of the true positions ``(…, 2)`` (one independent draw each)."""
    position = jnp.asarray(position, float)
    r, b = polar(sensor, position)
    n = jax.random.normal(key, position.shape, dtype=position.dtype)
    r_q = _quantise(r + sensor.range_std * n[..., 0], sensor.range_resolution)
    b_q = _quantise(b + sensor.bearing_std * n[..., 1], sensor.bearing_resolution)
    return jnp.asarray(sensor.position) + r_q[..., None] * jnp.stack([jnp.cos(b_q), jnp.sin(b_q)], axis=-1)


def cartesian_covariance(sensor: Radar2D, position: Any) -> jax.Array:
    """First-order covariance ``(…, 2, 2)`` of a converted plot at ``position (…, 2)``:
    ``G diag(σ_r² + Δr²/12, σ_β² + Δβ²/12) Gᵀ`` with ``G = ∂(x, y)/∂(r, β)``."""
    r, b = polar(sensor, position)
    var_r = sensor.range_std**2 + sensor.range_resolution**2 / 12.0
    var_b = sensor.bearing_std**2 + sensor.bearing_resolution**2 / 12.0
    c, s = jnp.cos(b), jnp.sin(b)
    g = jnp.stack([jnp.stack([c, -r * s], -1), jnp.stack([s, r * c], -1)], -2)  # (…, 2, 2)
    d = jnp.stack([jnp.broadcast_to(var_r, r.shape), jnp.broadcast_to(var_b, r.shape)], -1)
    return jnp.einsum("...ij,...j,...kj->...ik", g, d, g)


def _measure_as_sensor(params: Radar2D, key: jax.Array, y: jax.Array, t: jax.Array) -> jax.Array:
    return measure(params, key, y)


def radar_sensor(sensor: Radar2D) -> Sensor:
    """The radar as a closed-loop :class:`~jaxsim.core.system.Sensor` (the plant's output is the
    ``(2,)`` position; one plot every ``sensor.period``)."""
    return Sensor(params=sensor, measure=_measure_as_sensor, period=sensor.period, name="radar2d")
