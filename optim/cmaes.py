"""CMA-ES over a box, on the device — a further gradient-free baseline (evosax's ``CMA_ES``).

The search runs in the *unit box*: a point ``x`` of ``[lo, hi]`` (``(d,)`` each) is
``z = (x − lo)/(hi − lo)`` in ``[0, 1]^d``, so one step size ``sigma0`` (a fraction of the box,
default 0.3) suits every axis.  Per generation ``g``, with ``key_g`` the carried key:

1. ``key, k_ask, k_tell = split(key_g, 3)``; evosax's ``ask(k_ask, ...)`` samples ``popsize``
   candidates ``z ~ N(mean, sigma² C)``;
2. candidates outside ``[0, 1]`` are *repaired* — set to the nearest bound (``bounds="clip"``, the
   default) or mirrored at it (``"reflect"``, repeatedly) — and the repaired points are both
   evaluated and told to the strategy (so every evaluated point, and the best one, lies in the box).
   Clipping reaches optima on a bound or corner; mirroring keeps candidates off the bounds, but when
   the optimum lies on one the strategy's mean drifts outside and its step size grows without bound;
3. losses (non-finite ones count as ``+inf``) go to ``tell(k_tell, ...)``, which updates the mean,
   the step size and the covariance (evosax 0.3's CMA-ES: rank weights with negative weights,
   cumulative step-size adaptation).

``chunk`` generations run in one compiled ``lax.scan`` (the host syncs once per chunk, as
:func:`optim.pso`'s ``iters_per_call``); the compiled chunk is cached by ``jit`` across calls with
the same loss, sizes and settings.  ``evosax`` is an optional extra (``pip install -e ".[cmaes]"``),
imported when :func:`cmaes` is first called.
"""

from __future__ import annotations

import functools
import time
from typing import Any, Callable, Literal, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.progress import progress_bar
from jaxsim.problem import Problem
from optim.pso import _chunk_size, handle_bounds, run_in_chunks
from optim.results import History, TuneResult, as_box, check_int, check_some_loss_finite

RepairMode = Literal["reflect", "clip"]


def default_popsize(dim: int) -> int:
    """Hansen's default population ``4 + ⌊3 ln d⌋`` for ``d`` dimensions."""
    return 4 + int(np.floor(3 * np.log(dim)))


def _strategy(popsize: int, dim: int):
    from evosax.algorithms import CMA_ES

    return CMA_ES(population_size=popsize, solution=jnp.zeros(dim))


class CMAState(NamedTuple):
    """evosax's strategy state (mean in unit-box coordinates), its params, and the carried key."""

    es_state: Any
    es_params: Any
    key: jax.Array


def repair(z: jax.Array, mode: RepairMode) -> jax.Array:
    """Bring unit-box points ``z (..., d)`` back into ``[0, 1]`` (mirror or clip)."""
    zeros, ones = jnp.zeros(z.shape[-1], z.dtype), jnp.ones(z.shape[-1], z.dtype)
    return handle_bounds(z, z, zeros, ones, mode)[0]


def cma_generation(
    losses_of: Callable[[jax.Array], jax.Array],
    state: CMAState,
    lo: jax.Array,
    hi: jax.Array,
    popsize: int,
    mode: RepairMode,
) -> tuple[CMAState, jax.Array, jax.Array]:
    """One ask–repair–evaluate–tell generation; ``losses_of`` maps box points ``(n, d)`` to ``(n,)``.

    Returns the new state, the best loss so far and this generation's lowest loss.
    """
    es = _strategy(popsize, lo.shape[0])
    key, k_ask, k_tell = jax.random.split(state.key, 3)
    z, es_state = es.ask(k_ask, state.es_state, state.es_params)
    z = repair(z, mode)
    losses = losses_of(lo + (hi - lo) * z)
    losses = jnp.where(jnp.isfinite(losses), losses, jnp.inf)
    es_state, _ = es.tell(k_tell, z, losses, es_state, state.es_params)
    return CMAState(es_state, state.es_params, key), es_state.best_fitness, jnp.min(losses)


@functools.partial(jax.jit, static_argnames="popsize")
def cma_init(key: jax.Array, z0: jax.Array, sigma0: jax.Array, popsize: int) -> CMAState:
    """Strategy state with mean ``z0 (d,)`` (unit-box coordinates) and step size ``sigma0``."""
    es = _strategy(popsize, z0.shape[0])
    params = es.default_params.replace(std_init=jnp.asarray(sigma0, z0.dtype))
    k_init, key = jax.random.split(key)
    state = CMAState(es.init(k_init, z0, params), params, key)
    # strong types: evosax starts some fields as weakly typed Python scalars, which the scan's carry
    # would turn strong, so the second chunk would see new input types and compile again
    return jax.tree_util.tree_map(lambda a: jnp.asarray(a, dtype=jnp.result_type(a)), state)


@functools.partial(jax.jit, static_argnames=("loss", "batched", "popsize", "mode", "chunk"))
def _jitted_generations(
    state: CMAState,
    lo: jax.Array,
    hi: jax.Array,
    *,
    loss: Callable,
    batched: bool,
    popsize: int,
    mode: RepairMode,
    chunk: int,
) -> tuple[CMAState, tuple[jax.Array, jax.Array]]:
    """``chunk`` generations in one ``lax.scan``; compiled once per (loss, sizes, settings)."""
    losses_of = loss if batched else jax.vmap(loss)

    def body(s, _):
        new, best, now = cma_generation(losses_of, s, lo, hi, popsize, mode)
        return new, (best, now)

    return jax.lax.scan(body, state, None, length=chunk)


def _spread(es_state: Any) -> float:
    """Largest standard deviation of the search distribution, in unit-box coordinates."""
    eig = np.linalg.eigvalsh(np.asarray(es_state.C))
    return float(np.asarray(es_state.std) * np.sqrt(max(float(eig.max()), 0.0)))


def _convergence(es_state: Any, best: np.ndarray, tol: float, patience: int | None) -> tuple[bool, str]:
    spread = _spread(es_state)
    if spread < tol:
        return True, f"distribution collapsed (largest std {spread:.3g} of the box < tol={tol:g})"
    if patience is not None and best.size > patience:
        before, now = float(best[-patience - 1]), float(best[-1])
        if not now < before - 1e-12 * abs(before):
            return True, f"no improvement over the last {patience} generations (largest std {spread:.3g} of the box)"
    return False, f"not converged: largest std {spread:.3g} of the box (tol={tol:g})"


def cmaes(
    loss: Problem | Callable[[jax.Array], jax.Array],
    lo: Any = None,
    hi: Any = None,
    *,
    popsize: int | None = None,
    iters: int = 100,
    key: jax.Array | None = None,
    x0: Any = None,
    sigma0: float = 0.3,
    bounds: RepairMode = "clip",
    sims_per_eval: int | None = None,
    batched: bool = False,
    iters_per_call: int = 10,
    tol: float = 1e-8,
    patience: int | None = None,
    progress: Any = False,
) -> TuneResult:
    """Minimise a :class:`~jaxsim.problem.Problem` over its box, or ``loss(x)`` over ``lo ≤ x ≤ hi``
    (``(d,)`` each), with CMA-ES (module docstring).

    A Problem is searched in its search coordinates (``space.box``) on its penalised loss
    (:meth:`~jaxsim.problem.Problem.search_loss`), starting at ``space.init``; the result's ``params``
    is the params dict and ``u`` the search point.  A plain loss maps ``(d,)`` to a scalar and is
    ``vmap``ped over the population (``batched=True``: it maps ``(n, d)`` to ``(n,)``) and starts at
    the box centre.  ``x0``: another starting mean (a point of the box, search coordinates);
    ``sigma0``: initial step size as a fraction of the box (in ``(0, 1]``); ``popsize`` default
    ``4 + ⌊3 ln d⌋`` (at least 2); ``key`` default ``PRNGKey(0)``.  Simulations:
    ``popsize·iters·sims_per_eval``.  Always runs ``iters`` generations (equal budgets); ``converged``
    says whether the distribution collapsed below ``tol`` (largest std, fraction of the box) or the
    best loss stalled for ``patience`` generations.  Wall time within a chunk of
    ``iters_per_call`` generations is interpolated linearly.

    Raises ``ValueError`` naming the argument for bad settings (``popsize < 2``, non-finite or empty
    box, ``x0`` outside the box, ...) and, like every tuner, when no evaluated loss was finite.
    """
    problem = loss if isinstance(loss, Problem) else None
    if problem is not None:
        if lo is not None or hi is not None:
            raise ValueError("lo/hi: a Problem brings its own box (problem.space.box)")
        lo, hi = problem.space.box
        if x0 is None:
            x0 = np.asarray(problem.space.to_search(problem.space.init))
        loss = problem.search_loss
        sims_per_eval = problem.sims_per_eval if sims_per_eval is None else sims_per_eval
    elif lo is None or hi is None:
        raise ValueError("lo/hi: required for a plain loss function (a Problem brings space.box)")
    if not callable(loss):
        raise ValueError(f"loss: must be a Problem or callable, got {type(loss).__name__}")
    lo, hi = as_box(lo, hi)
    dim = lo.shape[0]
    popsize = check_int("popsize", default_popsize(dim) if popsize is None else popsize, 2)
    iters = check_int("iters", iters)
    sims_per_eval = check_int("sims_per_eval", 1 if sims_per_eval is None else sims_per_eval)
    if patience is not None:
        patience = check_int("patience", patience)
    if bounds not in ("clip", "reflect"):
        raise ValueError(f"bounds: must be 'clip' or 'reflect', got {bounds!r}")
    if isinstance(sigma0, bool) or not (np.isfinite(sigma0) and 0 < sigma0 <= 1):
        raise ValueError(f"sigma0: must be a fraction of the box in (0, 1], got {sigma0!r}")
    if not (np.isfinite(tol) and tol > 0):
        raise ValueError(f"tol: must be finite and positive, got {tol!r}")
    lo_np, hi_np = np.asarray(lo), np.asarray(hi)
    if x0 is None:
        z0 = np.full(dim, 0.5)
    else:
        x0 = np.asarray(x0, float)
        if x0.shape != (dim,):
            raise ValueError(f"x0: expected shape ({dim},), got {x0.shape}")
        if not (np.all(np.isfinite(x0)) and np.all(x0 >= lo_np) and np.all(x0 <= hi_np)):
            raise ValueError(f"x0: must be finite and inside the box lo..hi, got {x0}")
        z0 = (x0 - lo_np) / (hi_np - lo_np)
    chunk = _chunk_size(iters, check_int("iters_per_call", iters_per_call))
    static = dict(loss=loss, batched=batched, popsize=popsize, mode=bounds, chunk=chunk)

    t0 = time.perf_counter()
    state = cma_init(
        jax.random.PRNGKey(0) if key is None else key, jnp.asarray(z0, lo.dtype), jnp.asarray(sigma0, lo.dtype), popsize
    )
    _jitted_generations.lower(state, lo, hi, **static).compile()  # cached by jit for the loop below
    compile_s = time.perf_counter() - t0

    bar = progress_bar(progress, total=iters, desc=f"cmaes {problem.name if problem else 'loss'}", unit="gen")
    step = lambda s: _jitted_generations(s, lo, hi, **static)  # noqa: E731  (positional, as compiled above)
    state, best, now_min, wall = run_in_chunks(step, state, iters, chunk, bar)
    check_some_loss_finite(
        best[-1], f"{popsize} candidates × {iters} generations", "check the loss over the box lo..hi"
    )
    x_best = lo + (hi - lo) * state.es_state.best_solution
    sims = popsize * sims_per_eval * np.arange(1, iters + 1)
    converged, why = _convergence(state.es_state, best, tol, patience)
    return TuneResult(
        params=problem.space.from_search(x_best) if problem is not None else x_best,
        loss=float(state.es_state.best_fitness),
        history=History(best, sims, wall, loss=now_min),
        n_sims=int(sims[-1]),
        wall_s=float(wall[-1]),
        compile_s=float(compile_s),
        converged=converged,
        message=f"CMA-ES: {iters} generations of {popsize} candidates; {why}",
        u=x_best,
        n_steps=iters,
        mode="cmaes",
    )
