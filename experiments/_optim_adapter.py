"""Private stand-in for the tuning layer (``optim``, issue 5) while it is not on main.

Implements the few names of ``OPTIM_CONTRACT.md`` that the ``trms_lqr_tuning`` study uses —
``tune`` (optax, forward- or reverse-mode gradient, optional ``Interval`` reparametrisation,
vmapped multi-start), ``pso`` (global-best swarm, one vmapped loss call per iteration),
``random_search``, ``compare`` and ``plot_comparison`` — with the contract's signatures and result
types, so that the study runs unchanged on the real ``optim`` once it is merged (the study imports
``optim`` first and falls back to this module only on ``ImportError``).  Delete this file then.
"""

from __future__ import annotations

import functools
import time
from typing import Any, Callable, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import optax


class History(NamedTuple):
    loss: np.ndarray
    best_loss: np.ndarray
    grad_norm: np.ndarray
    sims: np.ndarray
    wall_s: np.ndarray


class TuneResult(NamedTuple):
    params: Any
    loss: float
    history: History
    n_sims: int
    wall_s: float
    message: str
    start_index: int


class SearchHistory(NamedTuple):
    best_loss: np.ndarray
    sims: np.ndarray
    wall_s: np.ndarray


class SearchResult(NamedTuple):
    x: Any
    loss: float
    history: SearchHistory
    n_sims: int
    wall_s: float
    compile_s: float = 0.0
    message: str = ""


class Interval(NamedTuple):
    """``x = lo + (hi − lo)·sigmoid(u)``."""

    lo: Any
    hi: Any

    def forward(self, u):
        return self.lo + (self.hi - self.lo) * jax.nn.sigmoid(u)

    def inverse(self, x):
        p = (x - self.lo) / (self.hi - self.lo)
        return jnp.log(p) - jnp.log1p(-p)


def tune(loss: Callable, params0: jax.Array, *, optimizer=None, steps: int = 200, reparam=None,
         n_starts: int = 1, key=None, init_spread: float = 0.5, mode: str = "auto",
         sims_per_eval: int = 1) -> TuneResult:
    """Gradient descent with ``optimizer`` on a flat parameter vector (contract subset)."""
    opt = optax.adam(1e-2) if optimizer is None else optimizer
    fwd = jnp.asarray if reparam is None else reparam.forward
    inv = (lambda x: x) if reparam is None else reparam.inverse
    u0 = inv(jnp.asarray(params0, float))
    f = lambda u: loss(fwd(u))  # noqa: E731
    forward_mode = mode == "forward" or (mode == "auto" and u0.size <= 32)
    vg = (lambda u: (f(u), jax.jacfwd(f)(u))) if forward_mode else jax.value_and_grad(f)
    if n_starts > 1:
        noise = init_spread * jax.random.normal(key, (n_starts,) + u0.shape, u0.dtype)
        starts = jnp.concatenate([u0[None], u0 + noise[1:]])
    else:
        starts = u0[None]

    @jax.jit
    def step(u, state):
        val, g = jax.vmap(vg)(u)
        upd, state = jax.vmap(opt.update)(g, state, u)
        return optax.apply_updates(u, upd), state, val, jnp.linalg.norm(g, axis=-1)

    u, state = starts, jax.vmap(opt.init)(starts)
    step.lower(u, state).compile()
    best_u, best_f = starts, jnp.full((starts.shape[0],), jnp.inf)
    hist = {k: [] for k in ("loss", "best", "gnorm", "wall")}
    t0 = time.perf_counter()
    message = f"completed {steps} steps"
    for _ in range(steps):
        new_u, state, val, gn = step(u, state)
        better = jnp.isfinite(val) & (val < best_f)
        best_u = jnp.where(better[:, None], u, best_u)
        best_f = jnp.where(better, val, best_f)
        hist["loss"].append(float(jnp.min(val)))
        hist["best"].append(float(jnp.min(best_f)))
        hist["gnorm"].append(float(gn[jnp.argmin(val)]))
        hist["wall"].append(time.perf_counter() - t0)
        if not bool(jnp.all(jnp.isfinite(val))):
            message = "stopped: non-finite loss; kept the best finite point"
            break
        u = new_u
    i = int(jnp.argmin(best_f))
    n = len(hist["loss"])
    sims = np.arange(1, n + 1) * starts.shape[0] * sims_per_eval
    history = History(np.array(hist["loss"]), np.array(hist["best"]), np.array(hist["gnorm"]), sims,
                      np.array(hist["wall"]))
    return TuneResult(fwd(best_u[i]), float(best_f[i]), history, int(sims[-1]), float(hist["wall"][-1]),
                      message, i)


@functools.partial(jax.jit, static_argnames=("loss", "c1", "c2"))
def _pso_step(k, x, v, pb, pbf, w, lo, hi, vmax, *, loss, c1, c2):
    gb = pb[jnp.argmin(pbf)]
    r1, r2 = jax.random.uniform(k, (2,) + x.shape)
    v = jnp.clip(w * v + c1 * r1 * (pb - x) + c2 * r2 * (gb - x), -vmax, vmax)
    x = x + v
    x = jnp.where(x < lo, 2 * lo - x, x)
    x = jnp.where(x > hi, 2 * hi - x, x)
    x = jnp.clip(x, lo, hi)
    f = _finite_or_inf(jax.vmap(loss)(x))
    better = f < pbf
    return x, v, jnp.where(better[:, None], x, pb), jnp.where(better, f, pbf)


def _finite_or_inf(v):
    return jnp.where(jnp.isfinite(v), v, jnp.inf)


@functools.partial(jax.jit, static_argnames=("loss",))
def _evaluate(x, *, loss):
    return _finite_or_inf(jax.vmap(loss)(x))


def pso(loss: Callable, lo, hi, *, n_particles: int = 64, n_iters: int = 100, key, inertia=(0.9, 0.4),
        c1: float = 1.5, c2: float = 1.5, velocity_clamp: float = 0.5, sims_per_eval: int = 1) -> SearchResult:
    """Global-best particle swarm, reflecting bounds, linear inertia schedule (contract subset).

    The step is jitted once per ``loss`` (static), so repeated runs (seeds) reuse the compilation."""
    lo, hi = jnp.asarray(lo, float), jnp.asarray(hi, float)
    span = hi - lo
    vmax = velocity_clamp * span
    k0, k1, key = jax.random.split(key, 3)
    x = lo + span * jax.random.uniform(k0, (n_particles, lo.size))
    v = vmax * jax.random.uniform(k1, x.shape, minval=-1.0, maxval=1.0)
    statics = dict(loss=loss, c1=float(c1), c2=float(c2))
    t_c = time.perf_counter()
    _pso_step.lower(key, x, v, x, jnp.zeros(n_particles), 0.5, lo, hi, vmax, **statics).compile()
    _evaluate.lower(x, loss=loss).compile()
    compile_s = time.perf_counter() - t_c
    t0 = time.perf_counter()
    f = _evaluate(x, loss=loss)
    pb, pbf = x, f
    best, wall = [float(jnp.min(f))], [time.perf_counter() - t0]
    w0, w1 = inertia
    for it in range(1, n_iters):
        w = w0 + (w1 - w0) * it / max(n_iters - 1, 1)
        x, v, pb, pbf = _pso_step(jax.random.fold_in(key, it), x, v, pb, pbf, w, lo, hi, vmax, **statics)
        best.append(float(jnp.min(pbf)))
        wall.append(time.perf_counter() - t0)
    i = int(jnp.argmin(pbf))
    sims = np.arange(1, n_iters + 1) * n_particles * sims_per_eval
    return SearchResult(pb[i], float(pbf[i]), SearchHistory(np.array(best), sims, np.array(wall)), int(sims[-1]),
                        wall[-1], compile_s, f"{n_iters} iterations of {n_particles} particles (global)")


def random_search(loss: Callable, lo, hi, *, n: int, key, batch_size: int = 128) -> SearchResult:
    """Uniform random points in the box, evaluated in vmapped batches (contract subset)."""
    lo, hi = jnp.asarray(lo, float), jnp.asarray(hi, float)
    batches = -(-n // batch_size)

    def points(b):
        return jax.random.uniform(jax.random.fold_in(key, b), (batch_size, lo.size), minval=lo, maxval=hi)

    t_c = time.perf_counter()
    _evaluate.lower(points(0), loss=loss).compile()
    compile_s = time.perf_counter() - t_c
    t0 = time.perf_counter()
    best_f, best_x, hist, wall = np.inf, None, [], []
    for b in range(batches):
        x = points(b)
        f = np.asarray(_evaluate(x, loss=loss))[: n - b * batch_size]
        if f.min() < best_f:
            best_f, best_x = float(f.min()), x[int(f.argmin())]
        hist.append(best_f)
        wall.append(time.perf_counter() - t0)
    sims = np.minimum(np.arange(1, batches + 1) * batch_size, n)
    return SearchResult(best_x, best_f, SearchHistory(np.array(hist), sims, np.array(wall)), int(n), wall[-1],
                        compile_s, f"random search: {n} points in {batches} batch(es)")


class Curve(NamedTuple):
    sims: np.ndarray
    seconds: np.ndarray
    best_loss: np.ndarray


class Comparison(NamedTuple):
    rows: list[dict[str, Any]]
    curves: dict[str, Curve]
    results: dict[str, Any]


def compare(runs: dict[str, Callable[[], Any]]) -> Comparison:
    """Run each tuner and record its best-so-far curve against simulations and seconds."""
    rows, curves, results = [], {}, {}
    for name, run in runs.items():
        res = run()
        h = res.history
        best = np.asarray(h.best_loss)
        curves[name] = Curve(np.asarray(h.sims, float), np.asarray(h.wall_s, float), best)
        results[name] = res
        rows.append({"tuner": name, "best_loss": float(res.loss), "sims": int(res.n_sims),
                     "wall_s": float(res.wall_s), "message": res.message})
    return Comparison(rows, curves, results)


def plot_comparison(comparison: Comparison, *, title: str | None = None):
    """Best loss vs simulations and vs seconds, one line per tuner."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for name, c in comparison.curves.items():
        axes[0].step(c.sims, c.best_loss, where="post", label=name)
        axes[1].step(c.seconds, c.best_loss, where="post", label=name)
    for ax, xl in zip(axes, ("simulations", "seconds (compilation excluded)")):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel(xl)
        ax.set_ylabel("best loss so far")
        ax.grid(alpha=0.3, which="both")
    axes[0].legend()
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig
