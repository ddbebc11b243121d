"""Max/min reductions whose derivative never divides by a zero tie count.

JAX differentiates ``jnp.max(x, axis)`` as ``Σ t·[x = max] / #[x = max]`` (the mean tangent of the
maximisers).  XLA may recompute an elementwise ``x`` inside each fusion that uses it, and two copies
can round differently (seen with ``--xla_backend_optimization_level=0``): then no entry equals the
max, the count is 0 and the derivative is NaN/inf although the value is fine.  :func:`max_along`
keeps JAX's mean wherever the count is positive and otherwise reads the tangent at the ``argmax``
of the same array, so it is always finite.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp


@functools.partial(jax.custom_jvp, nondiff_argnums=(1,))
def max_along(x: jax.Array, axis: int) -> jax.Array:
    """``jnp.max(x, axis)`` (same units and dtype); its derivative is always finite (module docstring)."""
    return jnp.max(x, axis=axis)


@max_along.defjvp
def _max_along_jvp(axis: int, primals: tuple, tangents: tuple) -> tuple[jax.Array, jax.Array]:
    (x,), (t,) = primals, tangents
    top = jnp.max(x, axis=axis)
    at_top = x == jnp.expand_dims(top, axis)
    count = jnp.sum(at_top, axis=axis)
    mean = jnp.sum(jnp.where(at_top, t, 0.0), axis=axis) / jnp.maximum(count, 1)
    first = jnp.take_along_axis(t, jnp.expand_dims(jnp.argmax(x, axis=axis), axis), axis=axis).squeeze(axis)
    return top, jnp.where(count > 0, mean, first)


def min_along(x: jax.Array, axis: int) -> jax.Array:
    """``jnp.min(x, axis)``; its derivative is always finite (see :func:`max_along`)."""
    return -max_along(-x, axis)
