"""Loops in a traced program, for tests that check how many copies of a simulation a transform made."""

from __future__ import annotations

from typing import Any


def loop_depths(closed_jaxpr: Any) -> list[int]:
    """Nesting depth of every loop (``scan``/``while``) in a ``jax.make_jaxpr`` result and every
    jaxpr nested in it (loop bodies, branches, inner ``jit``s), outermost first."""
    depths: list[int] = []

    def walk(j: Any, depth: int) -> None:
        for e in j.eqns:
            loop = e.primitive.name in ("scan", "while")
            if loop:
                depths.append(depth)
            for v in e.params.values():
                for sub in v if isinstance(v, (tuple, list)) else (v,):
                    inner = getattr(sub, "jaxpr", sub)
                    if hasattr(inner, "eqns"):
                        walk(inner, depth + loop)

    walk(closed_jaxpr.jaxpr, 0)
    return depths
