"""Particle swarm optimisation in JAX — the gradient-free baseline (TRMS paper's tuner).

Per iteration ``i`` (the order pyswarms uses, so the two compare setting for setting):

1. evaluate the whole swarm in one ``vmap``ped call (non-finite losses count as ``+inf``; a run in
   which every loss was non-finite raises ``ValueError``);
2. update personal bests, then each particle's neighbourhood best: the whole swarm
   (``topology="global"``, gbest) or the ``neighbors`` particles on either side by index on a ring
   (``"ring"``, lbest);
3. ``v ← w_i v + c1 r1 (p_best − x) + c2 r2 (n_best − x)``, ``r1, r2 ~ U(0, 1)`` per particle and
   dimension, then each component clamped to ``±velocity_clamp·(hi − lo)``;
4. ``x ← x + v``, with out-of-box components handled by ``bounds``: ``"reflect"`` (mirrored at the
   bound, repeatedly), ``"clip"`` (set to the nearest bound) or ``"absorb"`` (set to the bound and
   that velocity component zeroed).

Inertia: a constant, a callable ``w(i, n_iters)``, or ``(start, end)`` giving
``w_i = end + (start − end)(n_iters − i)/n_iters`` (pyswarms' ``lin_variation``).  Initial
positions are uniform in the box, initial velocities uniform in ``±velocity_clamp·(hi − lo)``
(or ``±(hi − lo)`` without clamp).

:func:`pso_init` / :func:`pso_step` are the pure pair; :func:`pso` drives them (a few iterations
per jitted call) and records the best loss, simulations and wall time per iteration.  Given a
:class:`~jaxsim.problem.Problem`, the swarm flies over the problem's box (``space.box``, search
coordinates) on its penalised loss.
"""

from __future__ import annotations

import functools
import time
from dataclasses import dataclass
from typing import Any, Callable, Literal, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.progress import postfix, progress_bar
from jaxsim.problem import Problem
from optim.results import History, TuneResult, as_box, check_int, check_some_loss_finite

Topology = Literal["global", "ring"]
BoundMode = Literal["reflect", "clip", "absorb"]


@dataclass(frozen=True)
class PSOConfig:
    """Static settings of the swarm (see the module docstring)."""

    n_particles: int = 64
    n_iters: int = 100
    topology: Topology = "global"
    neighbors: int = 1
    inertia: Any = (0.9, 0.4)
    c1: float = 1.5
    c2: float = 1.5
    bounds: BoundMode = "reflect"
    velocity_clamp: float | None = 0.5

    def __post_init__(self) -> None:
        check_int("n_particles", self.n_particles, 2)
        check_int("n_iters", self.n_iters, 1)
        check_int("neighbors", self.neighbors, 1)
        if self.topology not in ("global", "ring"):
            raise ValueError(f"topology: must be 'global' or 'ring', got {self.topology!r}")
        if self.bounds not in ("reflect", "clip", "absorb"):
            raise ValueError(f"bounds: must be 'reflect', 'clip' or 'absorb', got {self.bounds!r}")
        for name in ("c1", "c2"):
            v = getattr(self, name)
            if not np.isfinite(v) or v < 0:
                raise ValueError(f"{name}: must be finite and non-negative, got {v!r}")
        if self.velocity_clamp is not None and not (np.isfinite(self.velocity_clamp) and self.velocity_clamp > 0):
            raise ValueError(
                f"velocity_clamp: must be positive (a fraction of hi − lo) or None, got {self.velocity_clamp!r}"
            )
        inertia = self.inertia
        if isinstance(inertia, tuple):
            if len(inertia) != 2 or not all(np.isfinite(v) for v in inertia):
                raise ValueError(f"inertia: a schedule must be (start, end), got {inertia!r}")
        elif not callable(inertia) and not np.isfinite(inertia):
            raise ValueError(f"inertia: must be a number, (start, end) or a callable, got {inertia!r}")

    def inertia_at(self, i: jax.Array) -> jax.Array:
        """Inertia weight of iteration ``i`` (0-based)."""
        w = self.inertia
        if isinstance(w, tuple):
            start, end = w
            return end + (start - end) * (self.n_iters - i) / self.n_iters
        if callable(w):
            return w(i, self.n_iters)
        return jnp.asarray(w, float) + 0.0 * i


class SwarmState(NamedTuple):
    """Positions, velocities ``(n, d)``, personal bests and the iteration counter."""

    position: jax.Array
    velocity: jax.Array
    pbest_position: jax.Array
    pbest_loss: jax.Array
    key: jax.Array
    iteration: jax.Array


def _vmax(cfg: PSOConfig, lo: jax.Array, hi: jax.Array) -> jax.Array:
    frac = 1.0 if cfg.velocity_clamp is None else cfg.velocity_clamp
    return frac * (hi - lo)


@functools.partial(jax.jit, static_argnames="cfg")
def pso_init(key: jax.Array, lo: jax.Array, hi: jax.Array, cfg: PSOConfig) -> SwarmState:
    """A swarm spread uniformly over the box ``[lo, hi]`` (``(d,)`` each)."""
    k_pos, k_vel, k_run = jax.random.split(key, 3)
    n, d = cfg.n_particles, lo.shape[0]
    pos = jax.random.uniform(k_pos, (n, d), lo.dtype, lo, hi)
    vmax = _vmax(cfg, lo, hi)
    vel = jax.random.uniform(k_vel, (n, d), lo.dtype, -vmax, vmax)
    return SwarmState(pos, vel, pos, jnp.full((n,), jnp.inf, lo.dtype), k_run, jnp.asarray(0, jnp.int32))


def neighbourhood_best(pbest_position: jax.Array, pbest_loss: jax.Array, cfg: PSOConfig) -> jax.Array:
    """Best personal-best position in each particle's neighbourhood, ``(n, d)``."""
    n = pbest_loss.shape[0]
    if cfg.topology == "global":
        return jnp.broadcast_to(pbest_position[jnp.argmin(pbest_loss)], pbest_position.shape)
    offsets = jnp.arange(-cfg.neighbors, cfg.neighbors + 1)
    idx = (jnp.arange(n)[:, None] + offsets[None, :]) % n  # (n, 2k+1) ring neighbours, self included
    pick = jnp.take_along_axis(idx, jnp.argmin(pbest_loss[idx], axis=1)[:, None], axis=1)[:, 0]
    return pbest_position[pick]


def handle_bounds(pos: jax.Array, vel: jax.Array, lo: jax.Array, hi: jax.Array, mode: BoundMode):
    """Bring ``pos`` back into ``[lo, hi]``; returns ``(pos, vel)``."""
    if mode == "reflect":
        span = hi - lo
        y = jnp.mod(pos - lo, 2 * span)
        return lo + jnp.where(y > span, 2 * span - y, y), vel
    clipped = jnp.clip(pos, lo, hi)
    if mode == "clip":
        return clipped, vel
    return clipped, jnp.where(clipped != pos, 0.0, vel)


def pso_step(
    losses_of: Callable[[jax.Array], jax.Array], state: SwarmState, lo: jax.Array, hi: jax.Array, cfg: PSOConfig
) -> tuple[SwarmState, jax.Array]:
    """Evaluate the swarm (``losses_of(positions (n, d)) -> (n,)``), update bests, move.

    Returns the new state and the best loss found so far.
    """
    new, best, _ = _step(losses_of, state, lo, hi, cfg)
    return new, best


def _step(
    losses_of: Callable[[jax.Array], jax.Array], state: SwarmState, lo: jax.Array, hi: jax.Array, cfg: PSOConfig
) -> tuple[SwarmState, jax.Array, jax.Array]:
    """:func:`pso_step`, also returning the lowest loss of this iteration's positions."""
    losses = losses_of(state.position)
    losses = jnp.where(jnp.isfinite(losses), losses, jnp.inf)
    improved = losses < state.pbest_loss
    pbest_loss = jnp.where(improved, losses, state.pbest_loss)
    pbest_pos = jnp.where(improved[:, None], state.position, state.pbest_position)
    nbest = neighbourhood_best(pbest_pos, pbest_loss, cfg)
    key, k1, k2 = jax.random.split(state.key, 3)
    shape = state.position.shape
    r1 = jax.random.uniform(k1, shape, state.position.dtype)
    r2 = jax.random.uniform(k2, shape, state.position.dtype)
    w = cfg.inertia_at(state.iteration)
    vel = w * state.velocity + cfg.c1 * r1 * (pbest_pos - state.position) + cfg.c2 * r2 * (nbest - state.position)
    if cfg.velocity_clamp is not None:
        vmax = _vmax(cfg, lo, hi)
        vel = jnp.clip(vel, -vmax, vmax)
    pos, vel = handle_bounds(state.position + vel, vel, lo, hi, cfg.bounds)
    new = SwarmState(pos, vel, pbest_pos, pbest_loss, key, state.iteration + 1)
    return new, jnp.min(pbest_loss), jnp.min(losses)


@functools.partial(jax.jit, static_argnames=("loss", "batched", "cfg", "chunk"))
def _jitted_steps(
    state: SwarmState, lo: jax.Array, hi: jax.Array, *, loss: Callable, batched: bool, cfg: PSOConfig, chunk: int
) -> tuple[SwarmState, tuple[jax.Array, jax.Array]]:
    """``chunk`` iterations in one call (a scan); compiled once per (loss, settings), reused."""
    losses_of = loss if batched else jax.vmap(loss)

    def body(s, _):
        new, best, now = _step(losses_of, s, lo, hi, cfg)
        return new, (best, now)

    return jax.lax.scan(body, state, None, length=chunk)


def _chunk_size(n_iters: int, iters_per_call: int) -> int:
    """Largest divisor of ``n_iters`` not above ``iters_per_call`` (so every call has one shape)."""
    return max(c for c in range(1, min(iters_per_call, n_iters) + 1) if n_iters % c == 0)


def run_in_chunks(
    step: Callable[[Any], tuple[Any, tuple[jax.Array, jax.Array]]],
    state: Any,
    n_iters: int,
    chunk: int,
    bar: Any,
) -> tuple[Any, np.ndarray, np.ndarray, np.ndarray]:
    """The host loop of a population tuner: ``step(state) -> (state, (best, now_min))`` runs ``chunk``
    iterations on the device (each ``(chunk,)``: best loss so far, the iteration's minimum); called
    ``n_iters / chunk`` times.  Returns the final state and ``best, now_min, wall`` ``(n_iters,)``,
    ``wall`` (s) interpolated linearly inside each chunk; ``bar`` (a progress bar) is advanced per
    chunk and closed."""
    best, now_min, wall = np.empty(n_iters), np.empty(n_iters), np.empty(n_iters)
    start, last = time.perf_counter(), 0.0
    try:
        for i in range(0, n_iters, chunk):
            state, (best_i, now_i) = step(state)
            best[i : i + chunk] = np.asarray(best_i)
            now_min[i : i + chunk] = np.asarray(now_i)
            now = time.perf_counter() - start
            wall[i : i + chunk] = last + (now - last) * np.arange(1, chunk + 1) / chunk
            last = now
            bar.update(chunk)
            postfix(bar, f"best {best[i + chunk - 1]:.6g}")
    finally:
        bar.close()
    return state, best, now_min, wall


def swarm_convergence(
    state: SwarmState,
    best: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    tol: float,
    patience: int | None,
    rtol: float = 1e-12,
) -> tuple[bool, str]:
    """``(converged, why)``: the personal bests collapsed (spread ``max_i (max − min)/(hi − lo) < tol``
    over every dimension) or the best loss did not improve by more than ``rtol`` (relative) over
    the last ``patience`` iterations."""
    pb = np.asarray(state.pbest_position)
    spread = float(np.max((pb.max(axis=0) - pb.min(axis=0)) / (np.asarray(hi) - np.asarray(lo))))
    if spread < tol:
        return True, f"swarm collapsed (personal-best spread {spread:.3g} of the box < tol={tol:g})"
    if patience is not None and best.size > patience:
        before, now = float(best[-patience - 1]), float(best[-1])
        if not now < before - rtol * abs(before):
            return True, f"no improvement over the last {patience} iterations (spread {spread:.3g} of the box)"
    return False, f"not converged: personal-best spread {spread:.3g} of the box (tol={tol:g})"


def pso(
    loss: Problem | Callable[[jax.Array], jax.Array],
    lo: Any = None,
    hi: Any = None,
    *,
    n_particles: int = 64,
    n_iters: int = 100,
    key: jax.Array | None = None,
    topology: Topology = "global",
    neighbors: int = 1,
    inertia: Any = (0.9, 0.4),
    c1: float = 1.5,
    c2: float = 1.5,
    bounds: BoundMode = "reflect",
    velocity_clamp: float | None = 0.5,
    sims_per_eval: int | None = None,
    batched: bool = False,
    iters_per_call: int = 10,
    tol: float = 1e-6,
    patience: int | None = None,
    progress: Any = False,
) -> TuneResult:
    """Minimise a :class:`~jaxsim.problem.Problem` over its box, or ``loss(x)`` over ``lo ≤ x ≤ hi``
    (``(d,)`` each), with a particle swarm.

    A Problem is searched in its space's search coordinates (``space.box``) on its penalised loss
    (:meth:`~jaxsim.problem.Problem.search_loss`); the result's ``params`` is the params dict and
    ``u`` the search point.  A plain ``loss`` maps one point ``(d,)`` to a scalar and is ``vmap``ped
    over the swarm — one call per iteration (``batched=True``: ``loss`` already maps ``(n, d)`` to
    ``(n,)``).  ``key`` defaults to ``PRNGKey(0)``.  Simulations: ``n_particles·sims_per_eval`` per
    iteration (``sims_per_eval`` default 1, a Problem's number of scenarios).

    The host syncs every ``iters_per_call`` iterations (rounded down to a divisor of ``n_iters``);
    the wall time of the iterations inside one call is interpolated linearly (they cost the same).
    The swarm always runs ``n_iters`` iterations (equal budgets); ``converged`` reports
    :func:`swarm_convergence` (``tol``, ``patience``) at the end.  ``progress``: ``True`` for a tqdm
    bar, or a bar factory (:mod:`jaxsim.core.progress`).

    Raises ``ValueError`` ("loss: not finite (NaN/inf) at any evaluated point …", the error
    :func:`optim.tune.tune` raises too) when no particle ever saw a finite loss.
    """
    problem = loss if isinstance(loss, Problem) else None
    if problem is not None:
        if lo is not None or hi is not None:
            raise ValueError("lo/hi: a Problem brings its own box (problem.space.box)")
        lo, hi = problem.space.box
        loss = problem.search_loss
        sims_per_eval = problem.sims_per_eval if sims_per_eval is None else sims_per_eval
    elif lo is None or hi is None:
        raise ValueError("lo/hi: required for a plain loss function (a Problem brings space.box)")
    lo, hi = as_box(lo, hi)
    if isinstance(inertia, list):
        inertia = tuple(inertia)
    cfg = PSOConfig(
        n_particles=n_particles,
        n_iters=n_iters,
        topology=topology,
        neighbors=neighbors,
        inertia=inertia,
        c1=c1,
        c2=c2,
        bounds=bounds,
        velocity_clamp=velocity_clamp,
    )
    sims_per_eval = check_int("sims_per_eval", 1 if sims_per_eval is None else sims_per_eval)
    if patience is not None:
        patience = check_int("patience", patience)
    if not (np.isfinite(tol) and tol > 0):
        raise ValueError(f"tol: must be finite and positive, got {tol!r}")
    if not callable(loss):
        raise ValueError(f"loss: must be callable, got {type(loss).__name__}")
    chunk = _chunk_size(cfg.n_iters, check_int("iters_per_call", iters_per_call))
    static = dict(loss=loss, batched=batched, cfg=cfg, chunk=chunk)
    t0 = time.perf_counter()
    state = pso_init(jax.random.PRNGKey(0) if key is None else key, lo, hi, cfg)
    _jitted_steps.lower(state, lo, hi, **static).compile()  # cached by jit for the loop below
    compile_s = time.perf_counter() - t0
    name = problem.name if problem is not None else "loss"
    bar = progress_bar(progress, total=cfg.n_iters, desc=f"pso {name}", unit="iter")
    step = lambda s: _jitted_steps(s, lo, hi, **static)  # noqa: E731  (positional, as compiled above)
    state, best, now_min, wall = run_in_chunks(step, state, cfg.n_iters, chunk, bar)
    check_some_loss_finite(
        best[-1], f"{cfg.n_particles} particles × {cfg.n_iters} iterations", "check the loss over the box lo..hi"
    )
    i_best = int(jnp.argmin(state.pbest_loss))
    z_best = state.pbest_position[i_best]
    n_sims = cfg.n_particles * cfg.n_iters * sims_per_eval
    sims = cfg.n_particles * sims_per_eval * np.arange(1, cfg.n_iters + 1)
    converged, why = swarm_convergence(state, best, np.asarray(lo), np.asarray(hi), tol, patience)
    message = f"{cfg.n_iters} iterations of {cfg.n_particles} particles ({cfg.topology} topology); {why}"
    return TuneResult(
        params=problem.space.from_search(z_best) if problem is not None else z_best,
        loss=float(state.pbest_loss[i_best]),
        history=History(best, sims, wall, loss=now_min),
        n_sims=int(n_sims),
        wall_s=float(wall[-1]),
        compile_s=float(compile_s),
        converged=converged,
        message=message,
        u=z_best,
        n_steps=cfg.n_iters,
        mode="pso",
    )
