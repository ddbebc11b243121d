"""Keep a long-lived test worker under Linux's limit on memory mappings per process.

XLA's CPU backend maps about three memory regions for every program it compiles and keeps them while
the program stays in a jit cache.  A pytest-xdist worker that runs half the suite compiles
thousands of programs.  Measured in a fresh-clone ``make test`` (2 workers): one worker held 12,000
mappings after 4 minutes, 57,000 after 22 and 65,340 after 25, and then died with a segmentation
fault inside ``backend_compile_and_load`` — the intermittent CI crash of earlier runs, in whichever
test compiled next.  A process filled to ``vm.max_map_count`` (65,530 by default) on purpose fails
its next compilation the same way (``LLVM ERROR: Unable to allocate section memory``).
:func:`release_compiled_programs_if_maps_run_high` empties JAX's caches and the tuners' caches when
the count passes a fraction of the limit.
"""

from __future__ import annotations

import gc
import os
from pathlib import Path

import jax

from optim.compile_cache import clear_all

_LIMIT_FILE = Path("/proc/sys/vm/max_map_count")


def map_count() -> int | None:
    """The number of memory mappings of this process, or ``None`` where ``/proc`` does not say."""
    try:
        with open(f"/proc/{os.getpid()}/maps", "rb") as f:
            return sum(1 for _ in f)
    except OSError:
        return None


def map_limit() -> int | None:
    """Linux's per-process mapping limit (``vm.max_map_count``), or ``None`` where unknown."""
    try:
        return int(_LIMIT_FILE.read_text())
    except (OSError, ValueError):
        return None


def release_compiled_programs_if_maps_run_high(fraction: float = 0.4) -> bool:
    """Clear JAX's compilation caches and :func:`optim.compile_cache.clear_all` when this process holds
    more than ``fraction`` of ``vm.max_map_count`` mappings; returns whether it cleared."""
    count, limit = map_count(), map_limit()
    if count is None or limit is None or count <= fraction * limit:
        return False
    jax.clear_caches()
    clear_all()
    gc.collect()
    return True
