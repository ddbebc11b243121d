"""``fori``: ``lax.fori_loop`` that leaves out the loop when its static trip count is 0 or 1.

``lax.fori_loop`` with static bounds still traces its body when it runs zero or one times, and a
loop nested in a rollout's scan is transformed again by every ``jvp``/``vmap`` over it and compiled
by XLA: on the fuzzy-PID tuning loss (4 × 3,000 ticks) a zero-trip loop per tick made the
forward-mode gradient compile 1.35–1.57 s instead of 1.12–1.23 s.  Use :func:`fori` where the trip
count is a Python int that is often 0 or 1 (decimation, substeps).
"""

from __future__ import annotations

from typing import Any, Callable

import jax


def fori(lower: int, upper: int, body: Callable[[Any, Any], Any], init: Any) -> Any:
    """``body(i, x)`` for ``i = lower … upper − 1`` from ``x = init`` (static int bounds): ``init``
    when the range is empty, ``body(lower, init)`` for one trip, else ``lax.fori_loop``."""
    trips = int(upper) - int(lower)
    if trips <= 0:
        return init
    if trips == 1:
        return body(lower, init)
    return jax.lax.fori_loop(lower, upper, body, init)
