"""Robust objectives over Monte-Carlo samples.

:func:`robust_loss` builds ``params -> reducer(vmap(loss_fn)(params, samples))``; given a
:class:`~jaxsim.problem.Problem` it returns :meth:`Problem.robust` (the loss over ``n`` fixed draws of
the problem's uncertainty).  The reducers (:func:`mean`, :func:`worst_case`, :func:`cvar`) live in
:mod:`jaxsim.problem.reducers` and are re-exported here.
"""

from __future__ import annotations

from typing import Any, Callable

import jax
import jax.numpy as jnp

from jaxsim.problem import Problem
from jaxsim.problem.reducers import cvar, mean, worst_case

__all__ = ["cvar", "mean", "robust_loss", "worst_case"]


def robust_loss(
    loss_fn: Callable[[Any, Any], jax.Array] | Problem,
    samples: Any = None,
    reducer: Callable[[jax.Array], jax.Array] = mean,
    *,
    n: int | None = None,
    key: Any = 0,
) -> Callable[[Any], jax.Array] | Problem:
    """``params -> reducer(losses)`` with ``losses[s] = loss_fn(params, samples[s])``.

    ``samples`` is a pytree whose leaves share a leading sample axis (scenarios, plant-parameter
    draws, noise keys); the samples are evaluated in one ``vmap``.

    Given a :class:`~jaxsim.problem.Problem`, returns a Problem (which every tuner takes): with
    ``samples`` (a dict of draws), the problem over those scenarios; otherwise
    ``problem.robust(n, key, reducer)``, ``n`` fixed draws of its uncertainty.
    """
    if isinstance(loss_fn, Problem):
        if samples is not None:
            if not isinstance(samples, dict):
                raise ValueError("samples: for a Problem, a dict of draws with a leading scenario axis")
            return loss_fn.replace(scenarios=dict(samples), reduce=reducer)
        if n is None:
            raise ValueError("n: give the number of draws of the problem's uncertainty (or samples)")
        return loss_fn.robust(n, key, reducer)
    if samples is None:
        raise ValueError("samples: required for a loss function")
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
