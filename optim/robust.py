"""Robust objectives over Monte-Carlo samples: mean, worst case, conditional value-at-risk.

A reducer maps the losses of one parameter set over ``S`` samples, shape ``(S,)``, to a scalar;
:func:`robust_loss` builds ``params -> reducer(vmap(loss_fn)(params, samples))``.

CVaR at level ``alpha`` (Rockafellar–Uryasev) is the mean of the worst ``1 − alpha`` fraction of
the losses, ``min_t t + E[(L − t)₊]/(1 − alpha)``; for ``S`` samples the boundary sample enters with
a fractional weight, so the value is continuous in ``alpha``: ``alpha = 0`` gives the mean and
``alpha → 1`` the worst case.
"""

from __future__ import annotations

from typing import Any, Callable

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


def robust_loss(
    loss_fn: Callable[[Any, Any], jax.Array],
    samples: Any,
    reducer: Callable[[jax.Array], jax.Array] = mean,
) -> Callable[[Any], jax.Array]:
    """``params -> reducer(losses)`` with ``losses[s] = loss_fn(params, samples[s])``.

    ``samples`` is a pytree whose leaves share a leading sample axis (scenarios, plant-parameter
    draws, noise keys); the samples are evaluated in one ``vmap``.
    """
    leaves = jax.tree_util.tree_leaves(samples)
    if not leaves:
        raise ValueError("samples: must contain at least one array with a leading sample axis")
    sizes = {jnp.shape(leaf)[0] if jnp.ndim(leaf) else None for leaf in leaves}
    if None in sizes or len(sizes) != 1 or 0 in sizes:
        raise ValueError(f"samples: every leaf needs the same non-empty leading axis, got sizes {sizes}")
    batched = jax.vmap(loss_fn, in_axes=(None, 0))

    def objective(params: Any) -> jax.Array:
        return reducer(batched(params, samples))

    return objective
