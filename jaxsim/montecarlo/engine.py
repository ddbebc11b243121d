"""Monte Carlo and sweeps: chunks of runs on every device, merged into reproducible statistics.

:func:`monte_carlo` runs ``fn(key, params) -> metrics pytree`` for ``n`` runs whose ``params`` are
drawn from a parameter ``space``; :func:`sweep` does so at every point of a :class:`Design`.  The
result depends only on ``(fn, space, design, n, key, block_size, sketch)`` — never on
``chunk_size``, the number of devices or processes, or interruptions: see
:mod:`jaxsim.montecarlo.kernel` for the per-run keys and blocks, and
:mod:`jaxsim.montecarlo.moments` for the merge order.

Execution: chunks of ``chunk_size`` runs, one after the other; each chunk is one jitted call
sharded over ``devices`` (all of ``jax.devices()`` by default: several host devices with
``XLA_FLAGS=--xla_force_host_platform_device_count=K``, several processes/machines after
``jax.distributed.initialize``).  With ``out=DIR`` every finished chunk is written atomically to
a checkpoint folder (:mod:`jaxsim.montecarlo.store`) and ``resume=True`` continues from it — only if
the folder's fingerprint matches, which covers the computation itself (a hash of the jaxpr of one
run, :mod:`jaxsim.montecarlo.jaxpr_hash`), so chunks of an edited ``fn`` are never merged.  In a
multi-process run every process calls :func:`sweep` with the same arguments; process 0 alone reads
and writes ``out`` and broadcasts what it read, so every process returns the same result.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np
from jax.sharding import Mesh
from jax.sharding import PartitionSpec as P

from jaxsim.core.progress import progress_bar
from jaxsim.core.validation import check_int
from jaxsim.montecarlo.designs import Design, single_point
from jaxsim.montecarlo.distributions import describe_space, is_distribution, validate_space
from jaxsim.montecarlo.jaxpr_hash import jaxpr_hash
from jaxsim.montecarlo.kernel import Leaf, build_chunk_kernel, fetch, metric_layout, run_one, to_global, trace_run
from jaxsim.montecarlo.moments import Moments, PairwiseMerge, merge_moments
from jaxsim.montecarlo.result import EventStats, MetricStats, MonteCarloResult, RawRuns
from jaxsim.montecarlo.sketch import QuantileSketch
from jaxsim.montecarlo.store import MANIFEST, ChunkStore, fingerprint_of

DEFAULT_CHUNK = 100_000
MAX_KEEP_RUNS = 100_000
_PER_BLOCK = ("count", "mean", "m2")


@dataclass
class SweepResult:
    """One :class:`MonteCarloResult` per design point, plus the design and bookkeeping."""

    design: Design
    points: list[MonteCarloResult]
    fingerprint: str
    out: Path | None = None
    rejected_chunks: list[tuple[str, str]] = field(default_factory=list)

    def table(self, quantiles: tuple[float, ...] = (0.05, 0.5, 0.95), confidence: float = 0.95) -> list[dict]:
        """One row per point (see :meth:`MonteCarloResult.row`)."""
        return [r.row(quantiles, confidence) for r in self.points]

    @property
    def chunks_computed(self) -> int:
        return sum(r.chunks_computed for r in self.points)

    @property
    def chunks_loaded(self) -> int:
        return sum(r.chunks_loaded for r in self.points)


# ---------------------------------------------------------------------------------------------
# argument checks


def as_key(key: Any) -> jax.Array:
    """A typed PRNG key from an int seed, a typed key or a raw ``uint32[2]`` key."""
    if isinstance(key, (int, np.integer)) and not isinstance(key, bool):
        return jax.random.key(int(key))
    arr = key
    if hasattr(arr, "dtype") and jax.dtypes.issubdtype(arr.dtype, jax.dtypes.prng_key):
        if arr.shape != ():
            raise ValueError(f"key: expected a single key, got shape {arr.shape}")
        return arr
    arr = np.asarray(arr)
    if arr.dtype != np.uint32 or arr.shape != (2,):
        raise ValueError(f"key: expected an int seed or a PRNG key, got {key!r}")
    return jax.random.wrap_key_data(arr)


def resolve_devices(devices: Any) -> list:
    """``None`` → all of ``jax.devices()``; an int ``K`` → the first ``K``; or a list of devices."""
    every = jax.devices()
    if devices is None:
        return list(every)
    if isinstance(devices, (int, np.integer)) and not isinstance(devices, bool):
        k = check_int("devices", devices, 1, len(every))
        if jax.process_count() > 1 and k != len(every):
            raise ValueError(f"devices: a multi-process run uses all {len(every)} global devices, got {k}")
        return list(every[:k])
    devices = list(devices)
    if not devices:
        raise ValueError("devices: empty list")
    return devices


def _check_design(design: Design, space: Any) -> None:
    if not isinstance(design, Design):
        raise ValueError(f"design: expected a Design (grid, latin_hypercube, sobol, points), got {type(design)}")
    if not design.names:
        return
    if not isinstance(space, dict):
        raise ValueError("space: must be a dict of named parameters when a design sets parameters")
    for name in design.names:
        if name not in space:  # it would be added to every draw, read by nobody: identical points
            raise ValueError(
                f"design: parameter {name!r} is not in the space; the space's parameters: "
                f"{', '.join(sorted(map(str, space)))}"
            )
        if is_distribution(space.get(name)):
            raise ValueError(f"{name}: is drawn from a distribution in space; a sweep cannot also set it")


# ---------------------------------------------------------------------------------------------
# host side of a chunk


def _reduce_chunk(per_block: dict, per_device: dict, n_real: int) -> dict[str, np.ndarray]:
    """Device-count independent chunk data: real blocks only, device partials combined exactly."""
    out = {k: np.asarray(v)[:n_real] for k, v in per_block.items()}
    for k, v in per_device.items():
        v = np.asarray(v)
        kind = k.split("/", 1)[0]
        if kind == "min":
            out[k] = v.min(axis=0)
        elif kind == "max":
            out[k] = v.max(axis=0)
        else:
            out[k] = v.astype(np.int64).sum(axis=0)
    return out


def _template(leaves: list[Leaf], n_real: int, sketch: QuantileSketch | None) -> dict[str, np.ndarray]:
    """Zeros shaped like :func:`_reduce_chunk`'s output (for multi-process broadcasts)."""
    t: dict[str, np.ndarray] = {"runs": np.zeros((), np.int64)}
    for lf in leaves:
        if lf.kind == "event":
            t[f"events/{lf.name}"] = np.zeros(lf.shape, np.int64)
            continue
        t[f"count/{lf.name}"] = np.zeros((n_real,) + lf.shape, np.int64)
        t[f"mean/{lf.name}"] = np.zeros((n_real,) + lf.shape)
        t[f"m2/{lf.name}"] = np.zeros((n_real,) + lf.shape)
        t[f"nonfinite/{lf.name}"] = np.zeros(lf.shape, np.int64)
        t[f"min/{lf.name}"] = np.zeros(lf.shape)
        t[f"max/{lf.name}"] = np.zeros(lf.shape)
        if sketch is not None:
            t[f"hist/{lf.name}"] = np.zeros((sketch.n_bins,) + lf.shape, np.int64)
    return t


def _merge_named(a: dict[str, Moments], b: dict[str, Moments]) -> dict[str, Moments]:
    return {k: merge_moments(a[k], b[k]) for k in a}


class _PointAccumulator:
    """Merges the chunks of one point, in chunk order, into the point's statistics."""

    def __init__(self, leaves: list[Leaf], sketch: QuantileSketch | None):
        self.leaves = leaves
        self.numeric = [lf.name for lf in leaves if lf.kind == "numeric"]
        self.sketch = sketch
        self.moments: PairwiseMerge[dict[str, Moments]] = PairwiseMerge(_merge_named)
        self.totals: dict[str, np.ndarray] = {}

    def add(self, chunk: dict[str, np.ndarray]) -> None:
        if self.numeric:
            n_blocks = chunk[f"count/{self.numeric[0]}"].shape[0]
            for j in range(n_blocks):
                self.moments.push(
                    {
                        name: Moments(chunk[f"count/{name}"][j], chunk[f"mean/{name}"][j], chunk[f"m2/{name}"][j])
                        for name in self.numeric
                    }
                )
        for k, v in chunk.items():
            kind = k.split("/", 1)[0]
            if kind in _PER_BLOCK:
                continue
            if k not in self.totals:
                self.totals[k] = np.array(v)
            elif kind == "min":
                self.totals[k] = np.minimum(self.totals[k], v)
            elif kind == "max":
                self.totals[k] = np.maximum(self.totals[k], v)
            else:
                self.totals[k] = self.totals[k] + v

    def stats(self) -> tuple[int, dict[str, MetricStats | EventStats]]:
        runs = int(self.totals["runs"])
        merged = self.moments.result() if self.numeric else {}
        out: dict[str, MetricStats | EventStats] = {}
        for lf in self.leaves:
            if lf.kind == "event":
                out[lf.name] = EventStats(self.totals[f"events/{lf.name}"], runs)
            else:
                hist = self.totals.get(f"hist/{lf.name}")
                out[lf.name] = MetricStats(
                    merged[lf.name],
                    self.totals[f"nonfinite/{lf.name}"],
                    self.totals[f"min/{lf.name}"],
                    self.totals[f"max/{lf.name}"],
                    hist,
                    self.sketch if hist is not None else None,
                )
        return runs, out


# ---------------------------------------------------------------------------------------------
# the run


@dataclass(frozen=True)
class _Chunking:
    """How ``n`` runs are cut: blocks of ``block_size`` runs, chunks of ``per_chunk`` blocks, each
    chunk's block list padded to ``padded`` (a multiple of the device count) with id ``-1``."""

    n: int
    block_size: int
    per_chunk: int
    padded: int

    @property
    def n_blocks(self) -> int:
        return math.ceil(self.n / self.block_size)

    @property
    def n_chunks(self) -> int:
        return math.ceil(self.n_blocks / self.per_chunk)

    def real_blocks(self, c: int) -> int:
        return min(self.n_blocks, (c + 1) * self.per_chunk) - c * self.per_chunk

    def runs(self, c: int) -> int:
        first = c * self.per_chunk * self.block_size
        return min(self.n, first + self.per_chunk * self.block_size) - first

    def block_ids(self, c: int) -> np.ndarray:
        ids = np.full(self.padded, -1, np.int64)
        ids[: self.real_blocks(c)] = np.arange(c * self.per_chunk, c * self.per_chunk + self.real_blocks(c))
        return ids

    def meta(self, c: int) -> dict[str, int]:
        """What a chunk file must say about itself."""
        return {"first_block": c * self.per_chunk, "n_blocks": self.real_blocks(c)}


_KERNELS: dict[Any, Any] = {}


def _kernel(
    fn: Callable,
    space: Any,
    names: tuple[str, ...],
    leaves: list[Leaf],
    block_size: int,
    blocks: int,
    sketch: QuantileSketch | None,
    devices: list,
) -> tuple[Callable, Mesh]:
    """The jitted chunk kernel and its mesh, cached per (fn, shapes, layout, devices)."""
    cache_key = (
        fn,
        jax.tree_util.tree_structure(space),
        names,
        tuple(leaves),
        block_size,
        blocks,
        sketch,
        tuple(devices),
    )
    try:
        hit = _KERNELS.get(cache_key)
    except TypeError:  # unhashable fn or static metadata: no caching
        cache_key, hit = None, None
    if hit is None:
        mesh = Mesh(np.array(devices), ("d",))
        hit = (build_chunk_kernel(fn, leaves, block_size, sketch, mesh), mesh)
        if cache_key is not None:
            _KERNELS[cache_key] = hit
    return hit


class _ChunkSource:
    """Gives every chunk's data: from the checkpoint folder when it holds a valid copy, else computed
    (and saved).  Multi-process: process 0 alone touches the folder and broadcasts what it read."""

    def __init__(
        self,
        kernel: Callable,
        mesh: Mesh,
        chunking: _Chunking,
        leaves: list[Leaf],
        sketch: QuantileSketch | None,
        store: ChunkStore | None,
        n_points: int,
        key_data: np.ndarray,
        space: Any,
    ):
        self.kernel, self.mesh, self.chunking, self.leaves, self.sketch = kernel, mesh, chunking, leaves, sketch
        self.store = store
        self.multi = jax.process_count() > 1
        self.g_key = to_global(key_data, mesh, P())
        self.g_n = to_global(np.asarray(chunking.n, jnp.result_type(int)), mesh, P())
        self.g_space = jax.tree_util.tree_map(lambda v: to_global(v, mesh, P()), space)
        done = np.zeros((n_points, chunking.n_chunks), bool)
        if store is not None:
            for p in range(n_points):
                for c in range(chunking.n_chunks):
                    done[p, c] = store.load(p, c, chunking.meta(c)) is not None
        self.done = self._broadcast(done).astype(bool) if self.multi else done

    @staticmethod
    def _broadcast(tree: Any) -> Any:
        from jax.experimental import multihost_utils

        return jax.tree_util.tree_map(np.asarray, multihost_utils.broadcast_one_to_all(tree))

    def stored(self, p: int, c: int) -> dict[str, np.ndarray] | None:
        if not self.done[p, c]:
            return None
        chunk = self.store.load(p, c, self.chunking.meta(c)) if self.store is not None else None
        if self.multi:  # everyone gets process 0's copy (or learns it must be computed after all)
            template = _template(self.leaves, self.chunking.real_blocks(c), self.sketch)
            ok, data = self._broadcast((np.int32(chunk is not None), chunk if chunk is not None else template))
            chunk = data if int(ok) else None
        return chunk

    def compute(self, p: int, c: int, g_point: dict[str, jax.Array]) -> dict[str, np.ndarray]:
        g_ids = to_global(self.chunking.block_ids(c).astype(jnp.result_type(int)), self.mesh, P("d"))
        per_block, per_device = fetch(self.kernel(self.g_key, self.g_n, g_point, self.g_space, g_ids))
        chunk = _reduce_chunk(per_block, per_device, self.chunking.real_blocks(c))
        if self.store is not None:
            self.store.save(p, c, chunk, self.chunking.meta(c))
        return chunk


def _from_problem(fn: Any, space: Any, name: str | None) -> tuple[Callable, Any, str | None]:
    """A :class:`~jaxsim.problem.Problem` given as ``fn`` (with its params as ``space``): its per-run
    Breakdown terms over its ``{**nominal, **uncertainty}`` (duck-typed: the Problem layer sits above)."""
    spec = getattr(fn, "monte_carlo_spec", None)
    if spec is None:
        return fn, space, name
    metric, full_space = spec(space)
    return metric, full_space, name or f"problem:{fn.name}"


def sweep(
    fn: Callable[[jax.Array, Any], Any],
    space: Any,
    design: Design,
    n: int,
    key: Any,
    *,
    block_size: int = 1000,
    chunk_size: int | None = None,
    sketch: QuantileSketch | None = QuantileSketch(),  # noqa: B008  (an immutable default)
    keep_runs: int = 0,
    devices: Any = None,
    out: str | Path | None = None,
    resume: bool = False,
    name: str | None = None,
    extra: Any = None,
    progress: Callable[..., Any] | None = None,
) -> SweepResult:
    """Monte Carlo of ``n`` runs at every point of ``design``.

    Args:
        fn: ``fn(key, params) -> metrics``: pure JAX, vmappable; ``params`` is a draw of ``space``
            updated with the point's values; ``metrics`` a pytree of real arrays (statistics) and
            booleans (events).  Or a :class:`~jaxsim.problem.Problem`: the metrics are the per-run
            :class:`~jaxsim.core.costs.Breakdown` terms (and ``"total"``) at the parameters given
            as ``space``, drawn over the problem's ``{**nominal, **uncertainty}`` with fresh noise
            every run; a design then sets nominal values (``sweep(problem, params, grid(...), n, key)``).
        space: pytree (a dict when ``design`` sets parameters) of distributions and fixed values
            (for a Problem: the params pytree).
        design: points to visit (:func:`~jaxsim.montecarlo.designs.grid`, ``latin_hypercube``,
            ``sobol``, ``points``, ``single_point``); every point uses the same ``key`` (common
            random numbers: differences between points are not blurred by sampling noise).  Each
            design parameter must be a fixed (not random) entry of ``space``.
        n: runs per point, ``1 ≤ n < 2³²``.
        key: int seed or PRNG key.
        block_size: runs per block ``L`` — the unit of computation and of the merge; changing it
            changes the result in the last bits (it is part of the fingerprint).
        chunk_size: runs per jitted call and per checkpoint file; a multiple of ``block_size``
            (default: the folder's, else ``min(100_000, n)`` rounded up to a block).
        sketch: quantile sketch layout, or ``None`` for no quantiles.
        keep_runs: keep the first ``keep_runs`` runs' params and metrics (≤ 100,000).
        devices: ``None`` (all), a count, or a list of devices.
        out: checkpoint folder; ``resume``: continue the sweep already in it.  The folder must hold
            this very sweep: ``ValueError`` (nothing written) if it holds another one — in
            particular if ``fn``'s computation changed since the chunks were written (same name,
            edited body or closed-over configuration: the fingerprint includes the hash of one
            run's jaxpr, constants' values included).
        name, extra: identity of ``fn`` in the fingerprint (default ``module.qualname``) and any
            JSON-able configuration that changes what ``fn`` computes (recorded in the manifest;
            the jaxpr hash covers what ``fn`` closes over as well).
        progress: ``True`` for a tqdm bar, or ``progress(total=, initial=, unit=, unit_scale=, desc=)``
            returning a bar with ``update(k)``/``close()`` (tqdm, ``experiments.progress.bar``);
            default silent.
    """
    fn, space, name = _from_problem(fn, space, name)
    n = check_int("n", n, 1, 2**32 - 1)
    block_size = check_int("block_size", block_size, 1)
    keep_runs = check_int("keep_runs", keep_runs, 0, min(n, MAX_KEEP_RUNS))
    if sketch is not None and not isinstance(sketch, QuantileSketch):
        raise ValueError(f"sketch: expected a QuantileSketch or None, got {sketch!r}")
    validate_space(space)
    _check_design(design, space)
    key = as_key(key)
    key_data = np.asarray(jax.random.key_data(key))
    devices = resolve_devices(devices)
    main = jax.process_index() == 0
    space = jax.tree_util.tree_map(np.asarray, space)

    point0 = {nm: jnp.zeros((), jnp.result_type(float)) for nm in design.names}
    jaxpr, out_shapes = trace_run(fn, space, point0, key)
    leaves, treedef = metric_layout(out_shapes)
    fn_name = name or f"{getattr(fn, '__module__', '?')}.{getattr(fn, '__qualname__', repr(fn))}"
    description = {
        "format": 1,
        "name": fn_name,
        "computation": jaxpr_hash(jaxpr),
        "extra": extra,
        "space": describe_space(space),
        "design": design.describe(),
        "n": n,
        "key": key_data.tolist(),
        "key_impl": str(jax.random.key_impl(key)),
        "block_size": block_size,
        "sketch": None if sketch is None else sketch.describe(),
        "x64": bool(jax.config.jax_enable_x64),
        "metrics": [[lf.name, list(lf.shape), lf.kind] for lf in leaves],
    }
    fingerprint = fingerprint_of(description)
    chunk_size = _resolve_chunk_size(chunk_size, out, fingerprint, n, block_size)
    per_chunk = chunk_size // block_size
    chunking = _Chunking(n, block_size, per_chunk, math.ceil(per_chunk / len(devices)) * len(devices))
    store = None
    if out is not None and main:
        store = ChunkStore(out, fingerprint, description, {"chunk_size": chunk_size}, resume)
    kernel, mesh = _kernel(fn, space, design.names, leaves, block_size, chunking.padded, sketch, devices)
    source = _ChunkSource(kernel, mesh, chunking, leaves, sketch, store, len(design), key_data, space)

    initial = int(sum(chunking.runs(c) for _, c in zip(*np.nonzero(source.done))))
    bar = progress_bar(
        progress if main else None,
        total=len(design) * n,
        initial=initial,
        unit="run",
        unit_scale=True,
        desc=fn_name.rsplit(".", 1)[-1],
    )
    results = []
    try:
        for p in range(len(design)):
            start = time.perf_counter()
            point = design.point(p)
            g_point = {k: to_global(np.asarray(v, jnp.result_type(float)), mesh, P()) for k, v in point.items()}
            acc = _PointAccumulator(leaves, sketch)
            computed = loaded = runs_computed = 0
            for c in range(chunking.n_chunks):
                chunk = source.stored(p, c)
                if chunk is not None:
                    loaded += 1
                else:
                    chunk = source.compute(p, c, g_point)
                    computed += 1
                    runs_computed += chunking.runs(c)
                    bar.update(chunking.runs(c))
                acc.add(chunk)
            runs, by_name = acc.stats()
            raw = _raw_runs(fn, space, point, key, keep_runs) if keep_runs else None
            rejected = sum(1 for f, _ in (store.rejected if store else []) if f.startswith(f"p{p:05d}_"))
            results.append(
                MonteCarloResult(
                    runs=runs,
                    by_name=by_name,
                    treedef=treedef,
                    point=point,
                    raw=raw,
                    chunks_computed=computed,
                    runs_computed=runs_computed,
                    chunks_loaded=loaded,
                    chunks_rejected=rejected,
                    devices=len(devices),
                    processes=jax.process_count(),
                    wall_s=time.perf_counter() - start,
                )
            )
    finally:
        bar.close()
    return SweepResult(
        design, results, fingerprint, Path(out) if out is not None else None, list(store.rejected) if store else []
    )


def monte_carlo(fn: Callable[[jax.Array, Any], Any], space: Any, n: int, key: Any, **kwargs: Any) -> MonteCarloResult:
    """Monte Carlo of ``n`` runs of ``fn`` over ``space`` (a one-point :func:`sweep`; same options).

    ``monte_carlo(problem, params, n, key)``: a :class:`~jaxsim.problem.Problem`'s per-run cost terms
    at ``params`` over its uncertainty (see :func:`sweep`)."""
    return sweep(fn, space, single_point(), n, key, **kwargs).points[0]


def _resolve_chunk_size(
    chunk_size: int | None, out: str | Path | None, fingerprint: str, n: int, block_size: int
) -> int:
    if chunk_size is None:  # the folder's layout if it holds this sweep, else min(100k, n)
        chunk_size = _stored_chunk_size(out, fingerprint) or min(DEFAULT_CHUNK, n)
        chunk_size = math.ceil(chunk_size / block_size) * block_size
    chunk_size = check_int("chunk_size", chunk_size, 1)
    if chunk_size % block_size:
        raise ValueError(f"chunk_size: must be a multiple of block_size={block_size}, got {chunk_size}")
    return chunk_size


def _stored_chunk_size(out: str | Path | None, fingerprint: str) -> int | None:
    if out is None:
        return None
    import json

    path = Path(out) / MANIFEST
    try:
        manifest = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    if manifest.get("fingerprint") != fingerprint:
        return None
    return int(manifest.get("layout", {}).get("chunk_size", 0)) or None


_RAW: dict[Any, Callable] = {}


def _raw_runs(fn: Callable, space: Any, point: dict[str, float], key: jax.Array, k: int) -> RawRuns:
    """The first ``k`` runs recomputed verbatim (same keys, same parameters)."""
    names = tuple(point)

    def many(key_, space_, point_, idx):
        return jax.vmap(lambda i: run_one(fn, space_, point_, key_, i))(idx)

    try:
        jitted = _RAW.setdefault((fn, names), jax.jit(many))
    except TypeError:
        jitted = jax.jit(many)
    params, metrics = jitted(
        key, space, {k_: jnp.asarray(v) for k_, v in point.items()}, jnp.arange(k, dtype=jnp.result_type(int))
    )
    return RawRuns(
        np.arange(k), jax.tree_util.tree_map(np.asarray, params), jax.tree_util.tree_map(np.asarray, metrics)
    )
