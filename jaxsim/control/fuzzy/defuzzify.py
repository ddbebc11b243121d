"""Output fuzzy sets on a grid and their defuzzification.

The output set of a Mamdani-type system is the union (max) of its output terms, each implied by
its activation level ``α_t`` (the accumulated strength of the rules that fire it):

* min implication (Mamdani): ``μ(x) = max_t min(α_t, μ_t(x))``;
* product implication (Larsen): ``μ(x) = max_t α_t·μ_t(x)``.

The output terms are sampled on a grid ``x_1 < … < x_N`` and read as piecewise linear between the
samples.  Clipping a linear segment at ``α_t`` creates a corner where the segment crosses ``α_t``;
:func:`clipped_points` inserts these *cut points* (the universe scikit-fuzzy's control API builds),
so the areas below are exact for the clipped piecewise-linear terms.  For unimodal terms (every MF
kind but piecewise-linear) each term has at most two cut points, found directly by
:func:`unimodal_cuts`; :func:`clipped_points_unimodal` merges them into the grid and
:func:`centroid_clipped_unimodal` integrates without building the merged set (the fast path
``evaluate`` takes for Mamdani centroids).  A product keeps segments linear, so
:func:`scaled_points` needs no extra points.

The bisector is solved as ``s = 2A/(y1 + sqrt(y1² + 2mA))`` inside its segment, which stays exact
for nearly flat segments; scikit-fuzzy's ``x1 − (y1 − sqrt(y1² + 2mA))/m`` cancels catastrophically
when the slope ``m`` is a rounding error (seen as ~3e-2 differences on clipped plateaus).

Defuzzifiers take such a piecewise-linear set given by points ``(xs, mu)`` (``xs`` non-decreasing;
repeated abscissae are zero-width segments and change nothing):

* :func:`centroid` — ``∫x μ dx / ∫μ dx``, exact for piecewise-linear ``μ``;
* :func:`bisector` — the abscissa splitting the area in two equal halves (exact, solving the
  quadratic inside the segment where it falls);
* :func:`mean_of_maximum`, :func:`smallest_of_maximum`, :func:`largest_of_maximum` — over the
  distinct points where ``μ`` attains its maximum (within a relative ``1e-9``, so that the cut
  points bounding a clipped plateau, which rounding may leave a hair below the level, count;
  scikit-fuzzy tests exact equality and so drops or keeps them by rounding luck).

An empty output set (every activation 0) has no centroid or bisector; these return ``fallback``
(the middle of the grid by default, MATLAB's convention) instead of NaN, with zero gradient.
"""

from __future__ import annotations

import functools
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.robust_extrema import max_along


def clipped_points(grid: jax.Array, term_mf: jax.Array, levels: jax.Array) -> tuple[jax.Array, jax.Array]:
    """Points of ``max_t min(α_t, μ_t)`` with every cut point inserted (any term shapes).

    Args:
        grid: ``(N,)`` increasing output grid.
        term_mf: ``(T, N)`` output-term memberships on the grid.
        levels: ``(T,)`` activation levels ``α_t``.

    Returns:
        ``(xs, mu)`` of length ``(N − 1)(T + 1) + 1``, ``xs`` non-decreasing: every grid interval
        holds its left node and one slot per term (the term's cut there, or a repeat of the node).
    """
    alpha = levels[:, None]
    m0, m1 = term_mf[:, :-1], term_mf[:, 1:]
    x0, x1 = grid[:-1], grid[1:]
    crosses = _above(m0, alpha) != _above(m1, alpha)
    den = jnp.where(crosses, m1 - m0, 1.0)
    cut = jnp.where(crosses, x0 + (alpha - m0) * (x1 - x0) / den, x0)
    pts = jnp.concatenate([x0[None, :], sort_along_first_axis(cut)[0]], axis=0)  # (T+1, N-1)
    # Every term, linearly interpolated inside each interval: (T, T+1, N-1).
    values = _interp_in_interval(pts[None], x0, x1, m0[:, None, :], m1[:, None, :])
    mu = max_along(jnp.minimum(levels[:, None, None], values), 0)  # (T+1, N-1)
    last = max_along(jnp.minimum(levels, term_mf[:, -1]), 0)
    xs = jnp.concatenate([pts.T.reshape(-1), grid[-1:]])
    mus = jnp.concatenate([mu.T.reshape(-1), last[None]])
    return xs, mus


@functools.lru_cache(maxsize=None)
def _batcher_layers(n: int) -> tuple[tuple[np.ndarray, np.ndarray], ...]:
    """Batcher's odd–even merge sort for ``n`` (a power of two) keys, one layer of disjoint
    comparators per entry: ``(partner (n,), low (n,))`` — key ``i`` is compared with
    ``partner[i]`` (itself when idle) and keeps the smaller of the two where ``low[i]``."""
    layers, p = [], 1
    while p < n:
        k = p
        while k >= 1:
            partner, low = np.arange(n), np.zeros(n, bool)
            for j in range(k % p, n - k, 2 * k):
                for i in range(min(k, n - j - k)):
                    a, b = i + j, i + j + k
                    if a // (2 * p) == b // (2 * p):
                        partner[a], partner[b], low[a] = b, a, True
            layers.append((partner, low))
            k //= 2
        p *= 2
    return tuple(layers)


SORTING_NETWORK_MAX = 64  # keys; above this use lax.sort
RANK_SORT_MAX = 16  # keys; above this Batcher's network, layer by layer


def sort_along_first_axis(keys: jax.Array, *payloads: jax.Array) -> tuple[jax.Array, ...]:
    """Sort ``keys`` ``(n, ...)`` along axis 0 (ascending), permuting ``payloads`` alike.

    Small ``n`` avoids XLA's sort, which inside ``vmap`` on CPU is tens of times slower for the
    handful of cut points per evaluation.  Up to :data:`RANK_SORT_MAX` keys each key's rank is
    counted from all ``n²`` pairwise comparisons (ties broken by position) and every output row
    gathers the key of its rank: flat, so XLA fuses it without duplicating work.  An unrolled
    sorting network of 16 keys ran as fast, but XLA copied its comparator chain into each output's
    fusion: the 7-term Mamdani characteristic on 251 inputs compiled in 2.3–2.7 s with it, in
    0.7–0.9 s with the ranks.  Above, up to
    :data:`SORTING_NETWORK_MAX`, Batcher's network runs layer by layer (``log₂²`` layers, one
    gather and one select per array each).  The order of equal keys is unspecified (they are the
    same abscissa here).
    """
    n = keys.shape[0]
    if n > SORTING_NETWORK_MAX:
        return jax.lax.sort((keys, *payloads), dimension=0, num_keys=1)
    if n <= RANK_SORT_MAX:
        return _rank_sort(keys, *payloads)
    size = 1 << max(n - 1, 0).bit_length()
    pad = lambda a, v: jnp.concatenate([a, jnp.full((size - n, *a.shape[1:]), v, a.dtype)])  # noqa: E731
    cols = [pad(keys, jnp.inf)] + [pad(p, 0) for p in payloads]
    trailing = (1,) * (keys.ndim - 1)
    for partner, low in _batcher_layers(size):
        other = cols[0][partner]
        is_low = jnp.asarray(low).reshape(size, *trailing)
        swap = jnp.where(is_low, cols[0] > other, other > cols[0])  # the same decision on both ends
        cols = [jnp.where(swap, c[partner], c) for c in cols]
    return tuple(c[:n] for c in cols)


def _rank_sort(keys: jax.Array, *payloads: jax.Array) -> tuple[jax.Array, ...]:
    """:func:`sort_along_first_axis` by ranks: key ``j`` goes to row ``#{i: k_i < k_j} + #{i < j: k_i = k_j}``."""
    n = keys.shape[0]
    trailing = (1,) * (keys.ndim - 1)
    ki, kj = keys[:, None], keys[None, :]  # (n, n, ...): [i, j] compares key i with key j
    earlier = jnp.asarray(np.tri(n, k=-1, dtype=bool).T).reshape(n, n, *trailing)  # i < j
    rank = jnp.sum((ki < kj) | ((ki == kj) & earlier), axis=0)  # (n, ...): a permutation of 0..n-1
    # NaN keys compare false everywhere: their ranks collide and the output is unspecified
    lands = rank[None, :] == jnp.arange(n).reshape(n, 1, *trailing)  # [r, j]: key j lands in row r
    picked = (jnp.sum(jnp.where(lands, a[None, :], jnp.zeros((), a.dtype)), axis=1) for a in (keys, *payloads))
    return tuple(p.astype(a.dtype) for p, a in zip(picked, (keys, *payloads)))  # sums widen small ints


def _above(m: jax.Array, alpha: jax.Array) -> jax.Array:
    """Where "μ ≥ α" (for α = 0: "μ > 0"): a cut lies where this changes between samples."""
    return jnp.where(alpha == 0, m > alpha, m >= alpha)


def _interp_in_interval(x, x0, x1, y0, y1):
    """numpy.interp's arithmetic inside ``[x0, x1]``: ``slope·(x − x0) + y0``, exact at the ends."""
    v = (y1 - y0) / (x1 - x0) * (x - x0) + y0
    return jnp.where(x == x1, y1, v)


def unimodal_cuts(grid: jax.Array, term_mf: jax.Array, levels: jax.Array) -> tuple[jax.Array, jax.Array, jax.Array]:
    """Sorted cut points ``q`` ``(2T,)`` of unimodal sampled terms, the output set's value there and
    the grid interval ``k`` holding each (``grid[k] ≤ q ≤ grid[k + 1]``).

    A unimodal term crosses a level at most twice (rising, falling), so the cut points are found
    directly, without a per-interval sort; absent ones are repeats of ``grid[0]`` (zero width).
    """
    n, n_terms = grid.shape[0], term_mf.shape[0]
    alpha = levels[:, None]
    above = _above(term_mf, alpha) & (alpha > 0)  # (T, N): one contiguous run per unimodal term
    idx = jnp.arange(n)
    first = n - jnp.max(jnp.where(above, n - idx, 0), axis=1)  # plain max-reductions: faster than argmax
    last = jnp.max(jnp.where(above, idx, -1), axis=1)
    has = last >= 0
    # Rising cut in interval first−1, falling cut in interval last (when those intervals exist).
    valid = jnp.concatenate([has & (first > 0), has & (last < n - 1)])
    k = jnp.where(valid, jnp.clip(jnp.concatenate([first - 1, last]), 0, n - 2), 0)
    rows = jnp.tile(jnp.arange(n_terms), 2)
    m0, m1 = term_mf[rows, k], term_mf[rows, k + 1]
    x0, x1 = grid[k], grid[k + 1]
    lv = jnp.concatenate([levels, levels])
    den = jnp.where(valid, m1 - m0, 1.0)
    q = jnp.where(valid, x0 + (lv - m0) * (x1 - x0) / den, grid[0])
    q, k = sort_along_first_axis(q, k)
    values = _interp_in_interval(q[None], grid[k], grid[k + 1], term_mf[:, k], term_mf[:, k + 1])
    return q, max_along(jnp.minimum(alpha, values), 0), k


def clipped_points_unimodal(grid: jax.Array, term_mf: jax.Array, levels: jax.Array) -> tuple[jax.Array, jax.Array]:
    """:func:`clipped_points` for unimodal sampled terms (every kind but piecewise-linear).

    Same point multiset (hence the same centroid, bisector and maxima) as :func:`clipped_points`,
    ``N + 2T`` points long: the cut points of :func:`unimodal_cuts` merged into the grid.
    """
    n = grid.shape[0]
    q, mu_q, _ = unimodal_cuts(grid, term_mf, levels)
    mu_g = max_along(jnp.minimum(levels[:, None], term_mf), 0)
    # Merge: cut j goes to slot j + #(nodes ≤ q_j), node i to slot i + #(cuts < node i).
    m = q.shape[0]
    slot_q = jnp.arange(m) + jnp.searchsorted(grid, q, side="right")
    slots = jnp.arange(n + m)
    hit = slot_q[:, None] == slots[None, :]  # (2T, N+2T)
    is_cut = jnp.any(hit, axis=0)
    j = jnp.argmax(hit, axis=0)
    i = jnp.clip(slots - jnp.sum(slot_q[:, None] < slots[None, :], axis=0), 0, n - 1)
    return jnp.where(is_cut, q[j], grid[i]), jnp.where(is_cut, mu_q[j], mu_g[i])


def centroid_clipped_unimodal(
    grid: jax.Array, term_mf: jax.Array, levels: jax.Array, fallback: Any = None
) -> jax.Array:
    """``centroid(*clipped_points_unimodal(...))`` without building the merged points.

    Start from the trapezoids on the grid; inserting the cut ``p`` (value ``v``) between its
    current neighbours ``l < p < r`` adds a hat of height ``v − L(p)`` (``L``: the chord from ``l``
    to ``r``): area ``(v − L)(r − l)/2`` and first moment ``area·(l + p + r)/3``.  Inserting the
    sorted cuts left to right, cut ``j``'s neighbours are the previous cut (or its interval's left
    node) and its interval's right node.
    """
    q, mu_q, k = unimodal_cuts(grid, term_mf, levels)
    mu_g = max_along(jnp.minimum(levels[:, None], term_mf), 0)
    x1, x2, y1, y2, dx, area = _segments(grid, mu_g)
    moment = dx / 6.0 * (y1 * (2.0 * x1 + x2) + y2 * (x1 + 2.0 * x2))
    left_node, right_node = grid[k], grid[k + 1]
    prev_q = jnp.concatenate([grid[:1], q[:-1]])
    prev_mu = jnp.concatenate([mu_g[:1], mu_q[:-1]])
    from_cut = prev_q > left_node  # the previous cut lies inside the same interval
    l = jnp.where(from_cut, prev_q, left_node)
    vl = jnp.where(from_cut, prev_mu, mu_g[k])
    r, vr = right_node, mu_g[k + 1]
    width = r - l  # 0 when cuts coincide with each other or with a node (then nothing is added)
    chord = vl + (vr - vl) * (q - l) / jnp.where(width > 0, width, 1.0)
    d_area = jnp.where(width > 0, (mu_q - chord) * width / 2.0, 0.0)
    total = jnp.sum(area) + jnp.sum(d_area)
    first = jnp.sum(moment) + jnp.sum(d_area * (l + q + r) / 3.0)
    ok = total > 0
    return jnp.where(ok, first / jnp.where(ok, total, 1.0), _default_fallback(grid, fallback))


def scaled_points(grid: jax.Array, term_mf: jax.Array, levels: jax.Array) -> tuple[jax.Array, jax.Array]:
    """Points of ``max_t α_t·μ_t`` (no new corners: the grid itself)."""
    return grid, jnp.max(levels[:, None] * term_mf, axis=0)


def _segments(xs: jax.Array, mu: jax.Array):
    x1, x2, y1, y2 = xs[:-1], xs[1:], mu[:-1], mu[1:]
    dx = x2 - x1
    return x1, x2, y1, y2, dx, 0.5 * dx * (y1 + y2)


def _default_fallback(xs: jax.Array, fallback: Any) -> jax.Array:
    return 0.5 * (xs[0] + xs[-1]) if fallback is None else jnp.asarray(fallback, xs.dtype)


def centroid(xs: jax.Array, mu: jax.Array, fallback: Any = None) -> jax.Array:
    """Centre of area of the piecewise-linear set ``(xs, mu)``."""
    x1, x2, y1, y2, dx, area = _segments(xs, mu)
    moment = dx / 6.0 * (y1 * (2.0 * x1 + x2) + y2 * (x1 + 2.0 * x2))  # ∫ x μ dx per segment
    total = jnp.sum(area)
    ok = total > 0
    return jnp.where(ok, jnp.sum(moment) / jnp.where(ok, total, 1.0), _default_fallback(xs, fallback))


def bisector(xs: jax.Array, mu: jax.Array, fallback: Any = None) -> jax.Array:
    """Abscissa that splits the area of ``(xs, mu)`` into two equal halves."""
    x1, _, y1, y2, dx, area = _segments(xs, mu)
    cum = jnp.cumsum(area)
    total = cum[-1]
    half = 0.5 * total
    k = jnp.argmax(cum >= half)  # first segment reaching half the area
    need = half - (cum[k] - area[k])
    slope = jnp.where(dx[k] > 0, (y2[k] - y1[k]) / jnp.where(dx[k] > 0, dx[k], 1.0), 0.0)
    root = jnp.sqrt(jnp.maximum(y1[k] ** 2 + 2.0 * slope * need, 0.0))
    den = y1[k] + root
    # ∫_0^s (y1 + slope·τ) dτ = need  ⇒  s = 2·need / (y1 + sqrt(y1² + 2·slope·need)).
    s = jnp.where(den > 0, 2.0 * need / jnp.where(den > 0, den, 1.0), 0.0)
    ok = total > 0
    return jnp.where(ok, x1[k] + s, _default_fallback(xs, fallback))


MAX_RTOL = 1e-9  # points within this fraction of the maximum count as maximal


def _maximum_mask(xs: jax.Array, mu: jax.Array) -> jax.Array:
    distinct = jnp.concatenate([jnp.ones((1,), bool), xs[1:] != xs[:-1]])
    top = jnp.max(mu)
    return distinct & (mu >= top - MAX_RTOL * top)


def mean_of_maximum(xs: jax.Array, mu: jax.Array, fallback: Any = None) -> jax.Array:
    """Mean of the distinct abscissae where ``mu`` is maximal (``fallback`` unused)."""
    sel = _maximum_mask(xs, mu)
    return jnp.sum(jnp.where(sel, xs, 0.0)) / jnp.sum(sel)


def smallest_of_maximum(xs: jax.Array, mu: jax.Array, fallback: Any = None) -> jax.Array:
    """Smallest abscissa where ``mu`` is maximal (``fallback`` unused)."""
    return jnp.min(jnp.where(_maximum_mask(xs, mu), xs, jnp.inf))


def largest_of_maximum(xs: jax.Array, mu: jax.Array, fallback: Any = None) -> jax.Array:
    """Largest abscissa where ``mu`` is maximal (``fallback`` unused)."""
    return jnp.max(jnp.where(_maximum_mask(xs, mu), xs, -jnp.inf))


DEFUZZIFIERS: dict[str, Callable[..., jax.Array]] = {
    "centroid": centroid,
    "bisector": bisector,
    "mom": mean_of_maximum,
    "som": smallest_of_maximum,
    "lom": largest_of_maximum,
}
IMPLICATIONS = ("min", "product")


def implied_set(
    implication: str, grid: jax.Array, term_mf: jax.Array, levels: jax.Array, unimodal: bool = False
) -> tuple[jax.Array, jax.Array]:
    """The output set as points: ``"min"`` → cut points inserted (the faster unimodal variant when
    every term is unimodal), ``"product"`` → the grid."""
    if implication == "product":
        return scaled_points(grid, term_mf, levels)
    if implication == "min":
        return (clipped_points_unimodal if unimodal else clipped_points)(grid, term_mf, levels)
    raise ValueError(f"implication: must be one of {IMPLICATIONS}, got {implication!r}")
