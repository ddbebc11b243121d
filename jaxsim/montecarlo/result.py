"""Results of a Monte-Carlo run: per-metric statistics, event probabilities, optional raw runs."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import jax
import numpy as np

from jaxsim.montecarlo.events import wilson_interval
from jaxsim.montecarlo.moments import Moments
from jaxsim.montecarlo.sketch import QuantileSketch, quantile_error_bound, sketch_quantile


@dataclass(frozen=True)
class MetricStats:
    """Statistics of one numeric metric over the runs where it was finite (arrays: the metric's shape).

    ``count`` finite runs; ``nonfinite`` runs where it was nan/±inf (excluded from everything else);
    ``mean``; ``variance`` (unbiased, ``m2/(count−1)``); ``std``; exact ``minimum``/``maximum``;
    ``bucket_counts`` of the quantile sketch (``None`` if quantiles were switched off).
    """

    moments: Moments
    nonfinite: np.ndarray
    minimum: np.ndarray
    maximum: np.ndarray
    bucket_counts: np.ndarray | None = None
    sketch: QuantileSketch | None = None

    @property
    def count(self) -> np.ndarray:
        return np.asarray(self.moments.count)

    @property
    def mean(self) -> np.ndarray:
        return np.where(self.count > 0, self.moments.mean, np.nan)

    @property
    def variance(self) -> np.ndarray:
        return self.moments.variance

    @property
    def std(self) -> np.ndarray:
        return self.moments.std

    def quantile(self, q: float | np.ndarray) -> np.ndarray:
        """Sketch estimate of the quantile(s) ``q`` (shape ``q.shape + metric shape``); see ``sketch``."""
        if self.bucket_counts is None or self.sketch is None:
            raise ValueError("quantile: this run was made with quantiles switched off (sketch=None)")
        return sketch_quantile(self.sketch, self.bucket_counts, q, self.minimum, self.maximum)

    def quantile_bound(self, q: float | np.ndarray) -> np.ndarray:
        """Guaranteed bound on ``|quantile(q) − exact sample quantile|`` (``inf`` outside the sketch range)."""
        return quantile_error_bound(self.sketch, self.quantile(q))

    def arrays(self) -> dict[str, np.ndarray]:
        out = {
            "count": self.count,
            "nonfinite": np.asarray(self.nonfinite),
            "mean": np.asarray(self.moments.mean),
            "m2": np.asarray(self.moments.m2),
            "min": np.asarray(self.minimum),
            "max": np.asarray(self.maximum),
        }
        if self.bucket_counts is not None:
            out["buckets"] = np.asarray(self.bucket_counts)
        return out


@dataclass(frozen=True)
class EventStats:
    """Occurrences of a boolean metric: ``count`` out of ``runs``; ``probability = count/runs``."""

    count: np.ndarray
    runs: int

    @property
    def probability(self) -> np.ndarray:
        return np.asarray(self.count) / self.runs

    def interval(self, confidence: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
        """Wilson score interval of the probability."""
        return wilson_interval(self.count, self.runs, confidence)

    def arrays(self) -> dict[str, np.ndarray]:
        return {"count": np.asarray(self.count), "runs": np.asarray(self.runs)}


@dataclass(frozen=True)
class RawRuns:
    """The first runs kept verbatim (``keep_runs``): ``index (k,)``, ``params`` and ``metrics`` pytrees
    with a leading axis of length ``k``."""

    index: np.ndarray
    params: Any
    metrics: Any


@dataclass(frozen=True)
class MonteCarloResult:
    """Statistics of ``runs`` runs of one Monte Carlo (one point of a sweep).

    ``stats``: same pytree structure as ``fn``'s output, leaves :class:`MetricStats` /
    :class:`EventStats`; ``by_name``: the same leaves keyed by path (``"itae"``, ``"pos/0"``).
    ``point``: the sweep point's parameter values.  Bookkeeping: ``chunks_computed``,
    ``runs_computed`` (in those chunks, padding excluded), ``chunks_loaded`` (from a checkpoint folder),
    ``chunks_rejected`` (damaged files recomputed),
    ``devices``, ``processes``, ``wall_s``.
    """

    runs: int
    by_name: dict[str, MetricStats | EventStats]
    treedef: Any
    point: dict[str, float] = field(default_factory=dict)
    raw: RawRuns | None = None
    chunks_computed: int = 0
    runs_computed: int = 0
    chunks_loaded: int = 0
    chunks_rejected: int = 0
    devices: int = 1
    processes: int = 1
    wall_s: float = 0.0

    @property
    def stats(self) -> Any:
        return jax.tree_util.tree_unflatten(self.treedef, list(self.by_name.values()))

    def __getitem__(self, name: str) -> MetricStats | EventStats:
        return self.by_name[name]

    def arrays(self) -> dict[str, np.ndarray]:
        """Every statistic as a flat ``{"<metric>:<stat>": array}`` dict (e.g. for ``np.savez``)."""
        out = {}
        for name, s in self.by_name.items():
            for k, v in s.arrays().items():
                out[f"{name}:{k}"] = v
        return out

    def row(
        self, quantiles: tuple[float, ...] = (0.05, 0.5, 0.95), confidence: float = 0.95, max_elements: int = 8
    ) -> dict[str, Any]:
        """One flat table row: point values, then per metric element mean/std/min/max/quantiles
        (numeric) or probability and Wilson bounds (event).  Metrics with more than
        ``max_elements`` elements are left out of the row (see ``by_name``)."""
        row: dict[str, Any] = {**{k: float(v) for k, v in self.point.items()}, "runs": self.runs}
        for name, s in self.by_name.items():
            cols = _columns(s, quantiles, confidence)
            size = next(iter(cols.values())).size
            if size > max_elements:
                continue
            for col, arr in cols.items():
                flat = np.asarray(arr, np.float64).reshape(-1)
                for j, v in enumerate(flat):
                    suffix = "" if np.ndim(arr) == 0 else f"[{j}]"
                    row[f"{name}{suffix}:{col}"] = float(v)
        return row


def _pct(q: float) -> str:
    return f"p{100 * q:g}".replace(".", "_")


def _columns(s: MetricStats | EventStats, quantiles: tuple[float, ...], confidence: float) -> dict[str, Any]:
    if isinstance(s, EventStats):
        lo, hi = s.interval(confidence)
        return {"probability": s.probability, "wilson_low": lo, "wilson_high": hi, "count": s.count}
    cols: dict[str, Any] = {"mean": s.mean, "std": s.std, "min": s.minimum, "max": s.maximum}
    if s.bucket_counts is not None:
        for q in quantiles:
            cols[_pct(q)] = s.quantile(q)
    cols["nonfinite"] = s.nonfinite
    return cols
