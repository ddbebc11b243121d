"""JAX's own log messages (compilations, tracing) collected during a block, for tests that count
what was compiled."""

from __future__ import annotations

import contextlib
import logging
from typing import Iterator

import jax


@contextlib.contextmanager
def jax_messages() -> Iterator[list[str]]:
    """``with jax_messages() as messages:`` — every message JAX logs inside the block (with
    ``jax.log_compiles()`` on: ``"Compiling jit(name) …"``, ``"Finished tracing …"``), in order."""
    messages: list[str] = []

    class Collect(logging.Handler):
        def emit(self, record: logging.LogRecord) -> None:
            messages.append(record.getMessage())

    handler = Collect()
    logger = logging.getLogger("jax")
    logger.addHandler(handler)
    try:
        with jax.log_compiles():
            yield messages
    finally:
        logger.removeHandler(handler)
