"""Plain random search and grid search over a box, evaluated in fixed-size ``vmap``ped batches.

Both evaluate ``loss(x)`` (``x`` of shape ``(d,)``) for every point in batches of ``batch_size``
with one compiled function (the last batch is padded and the padding masked), and record the best
loss, the simulations and the wall time after every batch.  Non-finite losses never win; if no
loss is finite, ``ValueError`` (the error :func:`optim.tune.tune` raises too).

* :func:`random_search` — ``n`` points uniform in ``[lo, hi]``; batch ``b`` draws its
  ``batch_size`` points from ``fold_in(key, b)`` (the same key and ``batch_size`` reproduce a run).
* :func:`grid_search` — the full factorial grid of ``points_per_dim`` points per axis, each axis
  ``linspace(lo, hi)`` (a single point sits at the centre); the points are generated from their
  flat index on the device, so large grids are never materialised.
"""

from __future__ import annotations

import functools
import time
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.problem import Problem
from optim.results import History, TuneResult, as_box, check_int, check_some_loss_finite


def grid_axes(lo: np.ndarray, hi: np.ndarray, counts: tuple[int, ...]) -> np.ndarray:
    """Axis values ``(d, max(counts))``: ``linspace(lo_i, hi_i, counts_i)`` (centre if 1), padded."""
    table = np.zeros((len(counts), max(counts)))
    for i, (a, b, c) in enumerate(zip(lo, hi, counts)):
        table[i, :c] = np.linspace(a, b, c) if c > 1 else (a + b) / 2
    return table


def grid_points(axes: jax.Array, counts: tuple[int, ...], flat_index: jax.Array) -> jax.Array:
    """Grid points of the given flat indices (C order, last axis fastest), shape ``(..., d)``."""
    counts_np = np.asarray(counts, dtype=np.int64)
    strides = np.concatenate([np.cumprod(counts_np[::-1])[::-1][1:], [1]])
    multi = (flat_index[..., None] // jnp.asarray(strides)) % jnp.asarray(counts_np)
    return axes[jnp.arange(len(counts)), multi]


@functools.partial(jax.jit, static_argnames=("loss", "grid", "batch_size", "n"))
def _best_of_batch(
    b: jax.Array,
    source: jax.Array,
    lo: jax.Array,
    hi: jax.Array,
    *,
    loss: Callable,
    grid: tuple[int, ...] | None,
    batch_size: int,
    n: int,
) -> tuple[jax.Array, jax.Array]:
    """Best ``(loss, x)`` of batch ``b``: random points (``grid=None``, ``source`` a PRNG key) or
    grid points (``source`` the axis values of :func:`grid_axes`)."""
    if grid is None:
        x = jax.random.uniform(jax.random.fold_in(source, b), (batch_size, lo.shape[0]), lo.dtype, lo, hi)
    else:
        x = grid_points(source, grid, jnp.minimum(b * batch_size + jnp.arange(batch_size), n - 1))
    vals = jax.vmap(loss)(x)
    valid = (b * batch_size + jnp.arange(batch_size)) < n
    vals = jnp.where(valid & jnp.isfinite(vals), vals, jnp.inf)
    i = jnp.argmin(vals)
    return vals[i], x[i]


def _run_batches(
    loss: Callable[[jax.Array], jax.Array],
    source: jax.Array,
    lo: jax.Array,
    hi: jax.Array,
    grid: tuple[int, ...] | None,
    n: int,
    batch_size: int,
    sims_per_eval: int,
    label: str,
    problem: Problem | None,
) -> TuneResult:
    """Evaluate ``ceil(n / batch_size)`` batches, keeping the best point."""
    n_batches = -(-n // batch_size)
    static = dict(loss=loss, grid=grid, batch_size=batch_size, n=n)
    b0 = jnp.asarray(0, jnp.int32)
    t0 = time.perf_counter()
    _best_of_batch.lower(b0, source, lo, hi, **static).compile()  # cached by jit for the loop below
    compile_s = time.perf_counter() - t0
    best_loss, best_x = np.inf, None
    hist_best, hist_wall, hist_batch = np.empty(n_batches), np.empty(n_batches), np.empty(n_batches)
    start = time.perf_counter()
    for b in range(n_batches):
        val, x = _best_of_batch(jnp.asarray(b, jnp.int32), source, lo, hi, **static)
        val = float(val)
        hist_batch[b] = val
        if val < best_loss or best_x is None:
            best_loss, best_x = val, x
        hist_best[b] = best_loss
        hist_wall[b] = time.perf_counter() - start
    check_some_loss_finite(best_loss, f"{label}: {n} points", "check the loss over the box lo..hi")
    sims = np.minimum(np.arange(1, n_batches + 1) * batch_size, n) * sims_per_eval
    message = f"{label}: {n} points in {n_batches} batch(es) (a search has no convergence test)"
    return TuneResult(
        params=problem.space.from_search(best_x) if problem is not None else best_x,
        loss=float(best_loss),
        history=History(hist_best, sims, hist_wall, loss=hist_batch),
        n_sims=int(n * sims_per_eval),
        wall_s=float(hist_wall[-1]),
        compile_s=float(compile_s),
        converged=False,
        message=message,
        u=best_x,
        n_steps=n_batches,
        mode=label,
    )


def _problem_box(loss: Any, lo: Any, hi: Any, sims_per_eval: int | None, what: str):
    """``(loss, lo, hi, sims_per_eval, problem)`` for a Problem (its box and penalised search loss)
    or a plain loss over ``[lo, hi]``."""
    if isinstance(loss, Problem):
        lo, hi = loss.space.box
        spe = loss.sims_per_eval if sims_per_eval is None else sims_per_eval
        return loss.search_loss, lo, hi, spe, loss
    if lo is None or hi is None:
        raise ValueError(f"lo/hi: required for a plain loss function in {what} (a Problem brings space.box)")
    if not callable(loss):
        raise ValueError(f"loss: must be a Problem or callable, got {type(loss).__name__}")
    return loss, lo, hi, 1 if sims_per_eval is None else sims_per_eval, None


def random_search(
    loss: Problem | Callable[[jax.Array], jax.Array],
    lo: Any = None,
    hi: Any = None,
    *,
    n: int | None = None,
    key: jax.Array | None = None,
    batch_size: int = 256,
    sims_per_eval: int | None = None,
) -> TuneResult:
    """Best of ``n`` points drawn uniformly in the box ``[lo, hi]`` (``(d,)`` each), or in a
    :class:`~jaxsim.problem.Problem`'s box (``random_search(problem, n)``; ``params`` of the result
    is the params dict, ``u`` the search point)."""
    if isinstance(loss, Problem) and lo is not None and hi is None and n is None:
        n, lo = lo, None  # random_search(problem, n)
    loss, lo, hi, sims_per_eval, problem = _problem_box(loss, lo, hi, sims_per_eval, "random_search")
    lo, hi = as_box(lo, hi)
    if n is None:
        raise ValueError("n: the number of points is required")
    n = check_int("n", n)
    batch_size = min(check_int("batch_size", batch_size), n)
    sims_per_eval = check_int("sims_per_eval", sims_per_eval)
    key = jax.random.PRNGKey(0) if key is None else key
    return _run_batches(loss, key, lo, hi, None, n, batch_size, sims_per_eval, "random search", problem)


def grid_search(
    loss: Problem | Callable[[jax.Array], jax.Array],
    lo: Any = None,
    hi: Any = None,
    *,
    points_per_dim: int | tuple[int, ...] | None = None,
    batch_size: int = 256,
    sims_per_eval: int | None = None,
) -> TuneResult:
    """Best point of the full factorial grid over ``[lo, hi]`` or a Problem's box
    (``grid_search(problem, points_per_dim)``); ``points_per_dim`` int or ``(d,)``."""
    if isinstance(loss, Problem) and lo is not None and hi is None and points_per_dim is None:
        points_per_dim, lo = lo, None  # grid_search(problem, points_per_dim)
    loss, lo, hi, sims_per_eval, problem = _problem_box(loss, lo, hi, sims_per_eval, "grid_search")
    lo, hi = as_box(lo, hi)
    if points_per_dim is None:
        raise ValueError("points_per_dim: required (an int or one int per dimension)")
    d = lo.shape[0]
    ppd = np.asarray(points_per_dim)
    ppd = np.broadcast_to(ppd, (d,)) if ppd.ndim == 0 else ppd
    if ppd.shape != (d,):
        raise ValueError(f"points_per_dim: need an int or {d} ints, got {points_per_dim!r}")
    for i, c in enumerate(ppd):
        check_int(f"points_per_dim[{i}]", c.item() if hasattr(c, "item") else c)
    counts = tuple(int(c) for c in ppd)
    n = int(np.prod(counts))
    batch_size = min(check_int("batch_size", batch_size), n)
    sims_per_eval = check_int("sims_per_eval", sims_per_eval)
    axes = jnp.asarray(grid_axes(np.asarray(lo), np.asarray(hi), counts))
    return _run_batches(loss, axes, lo, hi, counts, n, batch_size, sims_per_eval, "grid search", problem)
