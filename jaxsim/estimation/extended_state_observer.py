"""Linear extended state observer (ESO) for a chain of ``n`` integrators with an input disturbance
(seed 004 #31, the ESO of both modes; spec seed004_part3 §2.10).

The disturbance is the extended state ``x_{n+1} = d``; from the measurement ``y = x1``::

    x̂̇_i = x̂_{i+1} + g_i (y − x̂1)          i = 1 … n−1
    x̂̇_n = x̂_{n+1} + u + g_n (y − x̂1)
    x̂̇_{n+1} = g_{n+1} (y − x̂1)

with bandwidth gains (all observer poles at ``−ω_o``): ``g_i = C(n+1, i) ω_oⁱ``.
"""

from __future__ import annotations

from math import comb

import jax
import jax.numpy as jnp


def bandwidth_gains(omega_o: jax.Array, n: int) -> jax.Array:
    """``(n+1,)`` gains putting the ``n+1`` observer poles at ``−omega_o`` (rad/s)."""
    if int(n) < 1:
        raise ValueError(f"n: must be a positive integer, got {n!r}")
    return jnp.stack([comb(n + 1, i) * omega_o**i for i in range(1, n + 2)])


def derivative(gains: jax.Array, xhat: jax.Array, y: jax.Array, u: jax.Array) -> jax.Array:
    """``x̂̇`` (shape ``(n+1,)``) from the estimate ``xhat`` ``(n+1,)``, the measurement ``y = x1``
    (scalar) and the applied (saturated) input ``u`` (scalar)."""
    e = y - xhat[0]
    drift = jnp.concatenate([xhat[1:], jnp.zeros(1)])
    drift = drift.at[-2].add(u)
    return drift + gains * e


def error_matrix(gains: jax.Array) -> jax.Array:
    """Estimation-error dynamics ``ė = (A_e − g c) e`` of the extended chain (for pole checks)."""
    m = gains.shape[0]
    return jnp.eye(m, k=1) - jnp.outer(gains, jnp.eye(m)[0])
