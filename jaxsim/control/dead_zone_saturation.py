"""Linear–relay law with three zones: dead zone, linear zone, saturation (seed 004 #6, the figure of
the control law; spec B11).

``u(σ) = clip(k·sign(σ)·max(|σ| − δ, 0), −u_max, u_max)``: zero for ``|σ| ≤ δ``, slope ``k`` after
the dead zone, ``±u_max`` from ``|σ| ≥ δ + u_max/k``.  Continuous in ``σ``; its derivative jumps at
the zone edges, so :func:`smooth_dead_zone_saturation` gives a surrogate with a temperature for a
gradient path (softplus for the dead zone, ``tanh``-free soft clip by softplus on both sides).
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.validation import check_positive


def dead_zone_saturation(sigma: jax.Array, dead_zone: Any, gain: Any, limit: Any) -> jax.Array:
    """Exact law (element-wise). ``dead_zone`` ≥ 0 (units of σ), ``gain`` > 0 (u per σ), ``limit`` > 0 (u)."""
    check_positive("dead_zone", dead_zone, allow_zero=True)
    check_positive("gain", gain)
    check_positive("limit", limit)
    s = jnp.asarray(sigma)
    lin = gain * jnp.sign(s) * jnp.maximum(jnp.abs(s) - dead_zone, 0.0)
    return jnp.clip(lin, -limit, limit)


def smooth_dead_zone_saturation(
    sigma: jax.Array, dead_zone: Any, gain: Any, limit: Any, temperature: Any = 1e-2
) -> jax.Array:
    """Smooth surrogate: the kinks replaced by softplus of width ``temperature·limit`` (in u units);
    tends to :func:`dead_zone_saturation` as ``temperature → 0``."""
    w = temperature * limit

    def sp(v: jax.Array) -> jax.Array:
        return w * jax.nn.softplus(v / w)

    s = jnp.asarray(sigma)
    lin = sp(gain * (s - dead_zone)) - sp(gain * (-s - dead_zone))  # soft dead zone, odd
    return lin - sp(lin - limit) + sp(-lin - limit)  # soft clip
