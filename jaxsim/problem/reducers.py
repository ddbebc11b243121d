"""Reducers of a loss over scenarios or Monte-Carlo samples: mean, worst case, conditional value-at-risk.

A reducer maps the losses of one parameter set over ``S`` samples, shape ``(S,)``, to a scalar.

CVaR at level ``alpha`` (Rockafellar–Uryasev) is the mean of the worst ``1 − alpha`` fraction of
the losses, ``min_t t + E[(L − t)₊]/(1 − alpha)``; for ``S`` samples the boundary sample enters with
a fractional weight, so the value is continuous in ``alpha``: ``alpha = 0`` gives the mean and
``alpha → 1`` the worst case.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp


def mean(losses: jax.Array) -> jax.Array:
    """Average loss over the samples (axis 0)."""
    return jnp.mean(losses, axis=0)


def worst_case(losses: jax.Array) -> jax.Array:
    """Largest loss over the samples (axis 0); its gradient is that of the worst sample."""
    return jnp.max(losses, axis=0)


def cvar(losses: jax.Array, alpha: float = 0.9) -> jax.Array:
    """Mean of the worst ``1 − alpha`` fraction of ``losses`` ``(S,)``; ``0 ≤ alpha < 1``."""
    a = float(alpha)
    if not 0.0 <= a < 1.0:
        raise ValueError(f"alpha: must satisfy 0 <= alpha < 1, got {alpha!r}")
    losses = jnp.asarray(losses)
    n = losses.shape[0]
    worst_first = -jnp.sort(-losses, axis=0)
    tail = (1.0 - a) * n  # number of samples, possibly fractional, in the tail
    # weight of the i-th worst sample: the part of [i, i+1) that lies inside [0, tail)
    idx = jnp.arange(n, dtype=losses.dtype)
    w = jnp.clip(tail - idx, 0.0, 1.0)
    w = w.reshape((n,) + (1,) * (losses.ndim - 1))
    return jnp.sum(w * worst_first, axis=0) / tail
