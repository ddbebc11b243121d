"""Test configuration: float64, JAX's persistent compilation cache, shared helpers."""

from __future__ import annotations

import os
from pathlib import Path

import jax
import pytest

ROOT = Path(__file__).resolve().parents[1]
CACHE_DIR = Path(os.environ.get("JAXSIM_TEST_CACHE", ROOT / ".jax_cache"))

jax.config.update("jax_enable_x64", True)
jax.config.update("jax_compilation_cache_dir", str(CACHE_DIR))
jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.5)
jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)

import jaxsim  # noqa: E402,F401  (precision set up in one place)


@pytest.fixture(autouse=True)
def _default_matmul_precision():
    """Importing dynamax (an oracle, imported when tests are collected) sets JAX's global
    ``jax_default_matmul_precision`` to ``"float32"``, which changes every traced ``dot_general`` and
    so the jaxpr hashes of sweeps; each test starts from JAX's default instead."""
    jax.config.update("jax_default_matmul_precision", None)
    yield
