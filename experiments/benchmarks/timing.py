"""Helpers shared by the benchmarks: median wall time of repeated calls, JSON output."""

from __future__ import annotations

import json
import statistics
import time
from typing import Any, Callable


def median_time(fn: Callable[[], Any], repeats: int) -> float:
    """Median wall time in seconds of ``repeats`` calls of ``fn()`` (the caller blocks on results)."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def write_json(path: str | None, out: dict) -> None:
    """Write a benchmark's numbers to ``path`` (nothing when ``path`` is None); NumPy scalars as floats."""
    if path:
        with open(path, "w") as fh:
            json.dump(out, fh, indent=2, default=float)
