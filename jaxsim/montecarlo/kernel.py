"""The device program of one chunk: blocks of runs, summarised where they are computed.

Run ``i`` (global index, ``0 ≤ i < n``) uses the key ``k_i = fold_in(key, i)``: its parameters are
``draw(space, fold_in(k_i, 0))`` (merged with the sweep point's values) and its metrics
``fn(fold_in(k_i, 1), params)``.  Runs are grouped in blocks of ``L`` consecutive indices (block
``b`` holds ``b·L … b·L + L − 1``; indices ≥ n are masked out).  A chunk is a list of block ids,
split evenly over the devices of a 1-D mesh with ``shard_map``; each device walks its blocks with
``lax.scan`` and, per block, evaluates ``vmap(fn)`` over exactly ``L`` runs — the same program
shape whatever the chunk size or device count — and reduces them to:

* per block: :class:`~jaxsim.montecarlo.moments.Moments` of every numeric metric element (finite
  values only), returned per block so the host can merge them in a fixed tree;
* per device: integer counts (non-finite values, events, quantile-sketch buckets) and min/max —
  exact and order-free, so they are summed as they come.

Block id ``-1`` is padding (to fill the last chunk or a device); ``lax.cond`` skips it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np
from jax.sharding import Mesh, NamedSharding
from jax.sharding import PartitionSpec as P

from jaxsim.montecarlo.distributions import draw
from jaxsim.montecarlo.moments import block_moments
from jaxsim.montecarlo.sketch import QuantileSketch


@dataclass(frozen=True)
class Leaf:
    """One leaf of ``fn``'s output: ``kind`` is ``"numeric"`` (statistics) or ``"event"`` (bool)."""

    name: str
    shape: tuple[int, ...]
    kind: str


def leaf_name(path: tuple[Any, ...]) -> str:
    parts = []
    for p in path:
        for attr in ("key", "name", "idx"):
            if hasattr(p, attr):
                parts.append(str(getattr(p, attr)))
                break
        else:  # pragma: no cover - other key types
            parts.append(str(p))
    return "/".join(parts) or "value"


def run_one(
    fn: Callable[[jax.Array, Any], Any], space: Any, point: dict[str, Any], key: jax.Array, index: jax.Array
) -> tuple[Any, Any]:
    """``(params, metrics)`` of run ``index`` (see module docstring for the key derivation)."""
    k = jax.random.fold_in(key, index.astype(jnp.uint32))
    params = draw(space, jax.random.fold_in(k, 0))
    if point:
        params = {**params, **point}
    return params, fn(jax.random.fold_in(k, 1), params)


def trace_run(fn: Callable, space: Any, point: dict[str, Any], key: jax.Array) -> tuple[Any, Any]:
    """The jaxpr of one run, ``(key, space, point, index) -> metrics``, and its output's shapes.

    Key, space, point and run index are all arguments, traced like the real runs (value checks
    inside ``fn`` see tracers, not zeros; the space's values are not baked in), so the jaxpr depends
    only on ``fn``, on what it closes over, and on the structure, shapes and dtypes of its inputs.
    Returns ``(ClosedJaxpr, pytree of ShapeDtypeStruct)``.
    """
    index = jnp.zeros((), jnp.result_type(int))
    one = lambda k, sp, pt, i: run_one(fn, sp, pt, k, i)[1]  # noqa: E731
    return jax.make_jaxpr(one, return_shape=True)(key, space, point, index)


def metric_layout(out: Any) -> tuple[list[Leaf], Any]:
    """Leaves of ``fn``'s output (shapes from :func:`trace_run`) and its treedef; ``ValueError`` on bad leaves."""
    flat, treedef = jax.tree_util.tree_flatten_with_path(out)
    if not flat:
        raise ValueError("fn: returned no arrays; it must return a pytree of metrics")
    leaves = []
    for path, sds in flat:
        name = leaf_name(path)
        kind = jnp.dtype(sds.dtype).kind
        if kind == "b":
            leaves.append(Leaf(name, tuple(sds.shape), "event"))
        elif kind in "iuf":
            leaves.append(Leaf(name, tuple(sds.shape), "numeric"))
        else:
            raise ValueError(
                f"fn: metric {name!r} has dtype {sds.dtype}; metrics must be real "
                "numbers (statistics) or booleans (events)"
            )
    return leaves, treedef


def _expand(mask: jax.Array, ndim: int) -> jax.Array:
    return mask.reshape(mask.shape + (1,) * (ndim - 1))


def build_chunk_kernel(
    fn: Callable,
    leaves: list[Leaf],
    block_size: int,
    sketch: QuantileSketch | None,
    mesh: Mesh,
) -> Callable:
    """``kernel(key_data, n, point, space, block_ids) -> (per_block, per_device)`` (jitted).

    ``block_ids``: ``(B,)`` int, ``B`` a multiple of the mesh size, sharded over axis ``"d"``.
    ``per_block`` maps ``count|mean|m2/<leaf>`` to ``(B, *shape)``; ``per_device`` maps
    ``runs``, ``nonfinite|min|max|hist/<leaf>`` and ``events/<leaf>`` to arrays with a leading
    device axis.
    """
    L = int(block_size)
    fdt = jnp.result_type(float)
    idt = jnp.result_type(int)

    def init_carry() -> dict[str, jax.Array]:
        c = {"runs": jnp.zeros((), idt)}
        for lf in leaves:
            if lf.kind == "event":
                c[f"events/{lf.name}"] = jnp.zeros(lf.shape, idt)
                continue
            c[f"nonfinite/{lf.name}"] = jnp.zeros(lf.shape, idt)
            c[f"min/{lf.name}"] = jnp.full(lf.shape, jnp.inf, fdt)
            c[f"max/{lf.name}"] = jnp.full(lf.shape, -jnp.inf, fdt)
            if sketch is not None:
                c[f"hist/{lf.name}"] = jnp.zeros((sketch.n_bins,) + lf.shape, idt)
        return c

    def empty_block() -> dict[str, jax.Array]:
        out = {}
        for lf in leaves:
            if lf.kind == "numeric":
                out[f"count/{lf.name}"] = jnp.zeros(lf.shape, idt)
                out[f"mean/{lf.name}"] = jnp.zeros(lf.shape, fdt)
                out[f"m2/{lf.name}"] = jnp.zeros(lf.shape, fdt)
        return out

    def per_device(key_data, n, point, space, block_ids):
        key = jax.random.wrap_key_data(key_data)

        def compute(carry: dict, b: jax.Array) -> tuple[dict, dict]:
            idx = b.astype(idt) * L + jnp.arange(L, dtype=idt)
            valid = idx < n
            _, metrics = jax.vmap(lambda i: run_one(fn, space, point, key, i))(idx)
            values = jax.tree_util.tree_leaves(metrics)
            new, out = dict(carry), {}
            new["runs"] = carry["runs"] + jnp.sum(valid, dtype=idt)
            for lf, v in zip(leaves, values):
                if lf.kind == "event":
                    hit = _expand(valid, v.ndim) & v.astype(bool)
                    new[f"events/{lf.name}"] = carry[f"events/{lf.name}"] + jnp.sum(hit, 0, dtype=idt)
                    continue
                x = v.astype(fdt)
                ok = _expand(valid, x.ndim) & jnp.isfinite(x)
                mom = block_moments(x, ok)
                out[f"count/{lf.name}"] = mom.count.astype(idt)
                out[f"mean/{lf.name}"] = mom.mean
                out[f"m2/{lf.name}"] = mom.m2
                bad = _expand(valid, x.ndim) & ~jnp.isfinite(x)
                new[f"nonfinite/{lf.name}"] = carry[f"nonfinite/{lf.name}"] + jnp.sum(bad, 0, dtype=idt)
                new[f"min/{lf.name}"] = jnp.minimum(carry[f"min/{lf.name}"], jnp.min(jnp.where(ok, x, jnp.inf), 0))
                new[f"max/{lf.name}"] = jnp.maximum(carry[f"max/{lf.name}"], jnp.max(jnp.where(ok, x, -jnp.inf), 0))
                if sketch is not None:
                    size = int(np.prod(lf.shape, dtype=np.int64))
                    bins = sketch.bucket(jnp.where(ok, x, 0.0)).reshape(L, size)
                    flat = (bins.astype(idt) * size + jnp.arange(size, dtype=idt)).reshape(-1)
                    hist = carry[f"hist/{lf.name}"].reshape(-1).at[flat].add(ok.reshape(-1).astype(idt))
                    new[f"hist/{lf.name}"] = hist.reshape(carry[f"hist/{lf.name}"].shape)
            return new, out

        def body(carry: dict, b: jax.Array) -> tuple[dict, dict]:
            return jax.lax.cond(b >= 0, compute, lambda c, _: (c, empty_block()), carry, b)

        carry, per_block = jax.lax.scan(body, init_carry(), block_ids)
        return per_block, {k: v[None] for k, v in carry.items()}

    sharded = jax.shard_map(
        per_device,
        mesh=mesh,
        in_specs=(P(), P(), P(), P(), P("d")),
        out_specs=(P("d"), P("d")),
        check_vma=False,
    )
    return jax.jit(sharded)


def to_global(x: Any, mesh: Mesh, spec: P) -> jax.Array:
    """A global array from a host value present on every process (works single- and multi-process)."""
    arr = np.asarray(x)
    sharding = NamedSharding(mesh, spec)
    return jax.make_array_from_callback(arr.shape, sharding, lambda idx: arr[idx])


def fetch(tree: Any) -> Any:
    """Host NumPy copies of (possibly multi-process) global arrays."""
    if jax.process_count() > 1:
        from jax.experimental import multihost_utils

        return multihost_utils.process_allgather(tree, tiled=True)
    return jax.tree_util.tree_map(np.asarray, tree)
