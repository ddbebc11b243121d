"""The suite's guard against Linux's per-process mapping limit (:mod:`tests.process_maps`)."""

import jax
import jax.numpy as jnp
import pytest

from tests.process_maps import map_count, map_limit, release_compiled_programs_if_maps_run_high

pytestmark = pytest.mark.skipif(map_count() is None or map_limit() is None, reason="needs Linux /proc")


def test_compiled_programs_hold_mappings_until_the_caches_are_cleared():
    n = 60
    x = jnp.ones(3)
    functions = [jax.jit(lambda v, k=k: jnp.sin(v) * k + jnp.cumsum(v)) for k in range(n)]
    before = map_count()
    for f in functions:
        f(x).block_until_ready()
    grown = map_count()
    assert grown - before >= 2 * n  # ~3 mappings per compiled program on XLA's CPU backend
    assert not release_compiled_programs_if_maps_run_high(fraction=1.0)  # below the limit: kept
    assert map_count() >= grown - 10
    assert release_compiled_programs_if_maps_run_high(fraction=0.0)
    assert map_count() <= grown - 2 * n  # the programs' mappings were released (the jits still live)
    assert len(functions) == n
