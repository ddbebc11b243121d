"""Mergeable mean and variance (Chan, Golub & LeVeque), reproducible to the bit.

A :class:`Moments` triple ``(count, mean, m2)`` (``m2 = Σ(x − mean)²``) summarises a set of values;
two summaries merge exactly as if the sets had been pooled (Chan et al., 1979):

    n = na + nb,  δ = mean_b − mean_a,  mean = mean_a + δ·nb/n,  m2 = m2_a + m2_b + δ²·na·nb/n.

Reproducibility is by construction, not by luck:

* :func:`block_moments` summarises one fixed-size block of values on the device with a two-pass
  mean/m2 whose sums are :func:`pairwise_sum` — a fixed binary tree of element-wise additions, so
  XLA cannot reorder them, whatever the batch or device layout around it;
* :class:`PairwiseMerge` merges the blocks of a run, pushed in block order, along a binary tree
  that depends only on the number of blocks (a binary counter: O(log B) summaries held at a time),
  so a result depends only on the values, never on how blocks were grouped into chunks or devices.

The error of the merged variance grows like ``log₂(B)·ε`` rather than ``B·ε`` for a sequential merge.
"""

from __future__ import annotations

from typing import Any, Callable, Generic, NamedTuple, TypeVar

import jax.numpy as jnp
import numpy as np

T = TypeVar("T")


class Moments(NamedTuple):
    """``count`` (int), ``mean`` and ``m2 = Σ(x − mean)²``, element-wise over a metric's shape."""

    count: Any
    mean: Any
    m2: Any

    @property
    def variance(self) -> np.ndarray:
        """Unbiased sample variance ``m2/(count − 1)`` (``nan`` for fewer than two values)."""
        c = np.asarray(self.count)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(c > 1, np.asarray(self.m2) / np.maximum(c - 1, 1), np.nan)

    @property
    def std(self) -> np.ndarray:
        return np.sqrt(self.variance)


def pairwise_sum(x: jnp.ndarray, axis: int = 0) -> jnp.ndarray:
    """Sum over ``axis`` by a fixed binary tree of element-wise additions (zero-padded to 2^k).

    Bit-for-bit reproducible under any surrounding ``vmap``/``jit``/sharding: every addition is
    an explicit element-wise op of the program, so the compiler has no reduction to reorder.
    """
    x = jnp.moveaxis(x, axis, 0)
    n = x.shape[0]
    size = 1 << max(0, (n - 1).bit_length())
    if size != n:
        x = jnp.concatenate([x, jnp.zeros((size - n,) + x.shape[1:], x.dtype)])
    while x.shape[0] > 1:
        half = x.shape[0] // 2
        x = x[:half] + x[half:]
    return x[0]


def block_moments(x: jnp.ndarray, mask: jnp.ndarray) -> Moments:
    """Moments of the values ``x[i]`` with ``mask[i]`` true, over axis 0 (device side, jittable).

    ``x``: ``(L, *shape)`` float; ``mask``: broadcastable to ``x``.  Two passes: the mean, then
    ``Σ(x − mean)²`` — both with :func:`pairwise_sum`.  An empty block has ``count = 0, mean = m2 = 0``.
    """
    mask = jnp.broadcast_to(mask, x.shape)
    w = mask.astype(x.dtype)
    count = jnp.sum(mask, axis=0, dtype=jnp.int64 if x.dtype == jnp.float64 else jnp.int32)
    safe = jnp.maximum(count, 1).astype(x.dtype)
    xz = jnp.where(mask, x, 0.0)
    mean = pairwise_sum(xz) / safe
    m2 = pairwise_sum(w * (xz - mean) ** 2)
    return Moments(count, mean, m2)


def merge_moments(a: Moments, b: Moments) -> Moments:
    """Chan's merge of two summaries (host side, NumPy float64; element-wise)."""
    na = np.asarray(a.count, np.int64)
    nb = np.asarray(b.count, np.int64)
    n = na + nb
    ma, mb = np.asarray(a.mean, np.float64), np.asarray(b.mean, np.float64)
    delta = mb - ma
    with np.errstate(divide="ignore", invalid="ignore"):
        frac = np.where(n > 0, nb / np.maximum(n, 1), 0.0)
        mean = ma + delta * frac
        m2 = np.asarray(a.m2, np.float64) + np.asarray(b.m2, np.float64) + delta * delta * na * frac
    empty_a, empty_b = na == 0, nb == 0
    mean = np.where(empty_a, mb, np.where(empty_b, ma, mean))
    m2 = np.where(empty_a, b.m2, np.where(empty_b, a.m2, m2))
    return Moments(n, mean, m2)


def moments_of(x: np.ndarray, axis: int = 0) -> Moments:
    """Moments of a NumPy array over ``axis`` (two-pass; convenience for callers and tests)."""
    x = np.asarray(x, np.float64)
    mean = x.mean(axis=axis)
    m2 = ((x - np.expand_dims(mean, axis)) ** 2).sum(axis=axis)
    return Moments(np.full(mean.shape, x.shape[axis], np.int64), mean, m2)


class PairwiseMerge(Generic[T]):
    """Merge items pushed in order along a binary tree that depends only on how many were pushed.

    ``push`` keeps a stack of complete subtrees (sizes are the binary digits of the count, as in a
    binary counter); :meth:`result` folds the remaining subtrees from the right.  Holds O(log n) items.
    """

    def __init__(self, merge: Callable[[T, T], T]):
        self._merge = merge
        self._stack: list[tuple[int, T]] = []
        self.pushed = 0

    def push(self, item: T) -> None:
        level = 0
        while self._stack and self._stack[-1][0] == level:
            _, left = self._stack.pop()
            item = self._merge(left, item)
            level += 1
        self._stack.append((level, item))
        self.pushed += 1

    def result(self) -> T:
        if not self._stack:
            raise ValueError("PairwiseMerge.result: nothing was pushed")
        acc = self._stack[-1][1]
        for _, item in reversed(self._stack[:-1]):
            acc = self._merge(item, acc)
        return acc
