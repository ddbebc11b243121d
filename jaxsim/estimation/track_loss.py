"""Track loss at a circular gate ("strobe"): exact event and smooth surrogate.

A tracker predicts where the next plot will be; the plot is associated with the track only if it
falls inside a circle of radius ``gate`` around that one-scan prediction.  The *miss distance* of
scan ``t`` is ``d_t = ‖z_t − ẑ_{t|t−1}‖``.  The track is **lost** at the first scan with
``d_t > gate``.  Until that scan a gated tracker and an ungated one see the same plots, so running
the tracker without gating and asking whether any ``d_t`` exceeded the gate gives exactly the
probability of losing the track.

Smooth surrogate (for gradients): ``P(lost) ≈ 1 − Π_t (1 − σ((d_t − gate)/T))`` with the
temperature ``T`` in metres (the exact event as ``T → 0``).
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.safe_norm import safe_norm
from jaxsim.core.validation import check_positive


def miss_distances(measurements: Any, predictions: Any) -> jax.Array:
    """``‖z_t − ẑ_{t|t−1}‖`` ``(T,)`` from plots ``(T, 2)`` and the predictions made for them ``(T, 2)``."""
    return safe_norm(jnp.asarray(measurements) - jnp.asarray(predictions))


def _mask(distances: jax.Array, mask: Any) -> jax.Array:
    return (
        jnp.ones(distances.shape, bool) if mask is None else jnp.broadcast_to(jnp.asarray(mask, bool), distances.shape)
    )


def track_lost(distances: Any, gate: Any, mask: Any = None) -> jax.Array:
    """``True`` if any checked scan (``mask``, default all) has a miss distance above ``gate`` (m, > 0).

    ``distances`` ``(T,)`` with a scalar ``gate`` gives one event; a ``gate`` of shape ``(G,)``
    gives ``(G,)`` events (one per gate width, same plots).
    """
    check_positive("gate", gate)
    d = jnp.asarray(distances)
    return jnp.any((d > jnp.asarray(gate)[..., None]) & _mask(d, mask), axis=-1)


def first_miss(distances: Any, gate: Any, mask: Any = None) -> jax.Array:
    """Index of the first checked scan outside the gate, ``-1`` if none (``distances (T,)``); a ``gate``
    of shape ``(G,)`` gives ``(G,)`` indices, as in :func:`track_lost`."""
    check_positive("gate", gate)
    d = jnp.asarray(distances)
    out = (d > jnp.asarray(gate)[..., None]) & _mask(d, mask)
    return jnp.where(jnp.any(out, axis=-1), jnp.argmax(out, axis=-1), -1)


def soft_track_loss(distances: Any, gate: Any, temperature: Any, mask: Any = None) -> jax.Array:
    """Smooth probability of loss ``1 − Π_t (1 − σ((d_t − gate)/T))`` over the checked scans; a ``gate``
    of shape ``(G,)`` gives ``(G,)`` probabilities, as in :func:`track_lost`."""
    check_positive("gate", gate)
    check_positive("temperature", temperature)
    d = jnp.asarray(distances)
    log_keep = jax.nn.log_sigmoid(-(d - jnp.asarray(gate)[..., None]) / temperature)  # log(1 − σ(x)) = log σ(−x)
    return -jnp.expm1(jnp.sum(jnp.where(_mask(d, mask), log_keep, 0.0), axis=-1))
