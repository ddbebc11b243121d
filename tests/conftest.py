"""Test configuration: float64, the compilation cache, shared helpers.

JAX's persistent compilation cache is off unless ``JAXSIM_TEST_CACHE=DIR`` names a folder (for this
process and every interpreter a test spawns): in a cold run of the suite it was read back for 43 of
its 764 entries, and writing an entry once crashed a worker in CI (a segmentation fault inside
``executable.serialize()``, jax 0.9.2).  For repeated local runs,
``JAXSIM_TEST_CACHE=.jax_cache make test`` reuses what the last run compiled.

The suite compiles with XLA's default flags plus the small-loop threshold that importing jaxsim adds
(:mod:`jaxsim.xla_flags`).  Tried for speed and rejected (fresh-clone runs, jax 0.9.2):
``--xla_cpu_use_fusion_emitters=false`` (compiles 11–60 % faster, but XLA's older loop emitter needs
> 8 GB to compile the 37-input sorting network of :mod:`jaxsim.control.fuzzy`, 0.35 GB by default: a
worker was OOM-killed); ``--xla_backend_optimization_level=0`` alone (pytest 32:33 → 30:20 on a quiet machine, but the
Misra1a Levenberg–Marquardt run stops without its convergence flag, and the fuzzy-PID studies' Mamdani
gradients were non-finite — since fixed by :func:`jaxsim.core.robust_extrema.max_along` and tested at
that level in ``tests/control/fuzzy/test_gradient_under_other_rounding.py``).
"""

from __future__ import annotations

import os
from pathlib import Path

import jax
import pytest

ROOT = Path(__file__).resolve().parents[1]
CACHE_DIR = Path(os.environ["JAXSIM_TEST_CACHE"]).resolve() if os.environ.get("JAXSIM_TEST_CACHE") else None

# The CLI run in-process by some tests (``experiments.cli.main``) turns on its own cache from this
# variable; without it, that worker would go on writing every compilation to ~/.cache/jaxsim.
os.environ["JAXSIM_CACHE_DIR"] = "" if CACHE_DIR is None else str(CACHE_DIR)

jax.config.update("jax_enable_x64", True)
if CACHE_DIR is not None:
    jax.config.update("jax_compilation_cache_dir", str(CACHE_DIR))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.5)
    jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)


def child_env(**extra: str) -> dict[str, str]:
    """The environment for an interpreter a test spawns (a CLI run, a README block, a worker): this
    one's (so ``JAXSIM_CACHE_DIR`` as set above, for a CLI), the repository on ``PYTHONPATH``, JAX's
    own cache folder only when the suite has one (for plain scripts), then ``extra``."""
    env = {k: v for k, v in os.environ.items() if k != "JAX_COMPILATION_CACHE_DIR"}
    env["PYTHONPATH"] = str(ROOT)
    if CACHE_DIR is not None:
        env["JAX_COMPILATION_CACHE_DIR"] = str(CACHE_DIR)
    return {**env, **extra}


import jaxsim  # noqa: E402,F401  (precision set up in one place)
from tests.process_maps import release_compiled_programs_if_maps_run_high  # noqa: E402


@pytest.fixture(autouse=True, scope="module")
def _stay_under_the_map_limit():
    """After each test file, empty the compilation caches if this worker's memory mappings run high
    (see :mod:`tests.process_maps`: at Linux's limit XLA crashes while compiling)."""
    yield
    release_compiled_programs_if_maps_run_high()


@pytest.fixture(autouse=True)
def _default_matmul_precision():
    """Importing dynamax (an oracle, imported when tests are collected) sets JAX's global
    ``jax_default_matmul_precision`` to ``"float32"``, which changes every traced ``dot_general`` and
    so the jaxpr hashes of sweeps; each test starts from JAX's default instead."""
    jax.config.update("jax_default_matmul_precision", None)
    yield
