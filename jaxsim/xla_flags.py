"""XLA's CPU backend compiles a simulation's time loop as one function (set once, at import).

XLA's CPU runtime runs a ``while`` loop (a ``lax.scan``, ``fori_loop``, ``while_loop``) kernel by
kernel: each small fusion of the body is a separate dispatched "thunk", ~0.1–1 µs each, per time
step.  Its ``SmallWhileLoopHoistingPass`` instead compiles a whole loop into one function, but only
when one iteration touches fewer bytes than ``xla_cpu_small_while_loop_byte_threshold`` (a backend
option, 1,024 bytes by default).  A closed-loop rollout is just above that line once a tangent rides
along: measured on the PID tuning loss (jax 0.9.2, 2-core CPU), one forward-mode derivative cost
**8× the loss** by default and **1.7×** with a 64 KiB threshold (334 → 53 µs), a reverse-mode
gradient 1,147 → 162 µs, the loss itself 40 → 32 µs — and the first call compiled faster
(0.63 → 0.42 s for the derivative).  Loops with a custom call in the body (a LAPACK solve or
Cholesky) are never hoisted, so the threshold leaves them as they were.

Importing :mod:`jaxsim` therefore adds ``xla_cpu_small_while_loop_byte_threshold=65536`` to
``XLA_FLAGS`` (inside ``--xla_backend_extra_options``, merged with any options already there).
XLA reads ``XLA_FLAGS`` when JAX starts its first backend, so the import must come before the first
JAX computation of the process; otherwise a warning says the setting came too late.  A value the
user already gave in ``XLA_FLAGS`` is left as it is (``...=1024`` restores XLA's default; ``0``
turns the pass off).
"""

from __future__ import annotations

import os
import re
import warnings

SMALL_LOOP_OPTION = "xla_cpu_small_while_loop_byte_threshold"
SMALL_LOOP_BYTES = 65536
_EXTRA_OPTIONS = "--xla_backend_extra_options"


def with_small_loop_threshold(flags: str, n_bytes: int = SMALL_LOOP_BYTES) -> str:
    """``flags`` (an ``XLA_FLAGS`` string) with the small-loop threshold set to ``n_bytes``, unless
    it already names one.  Merged into an existing ``--xla_backend_extra_options=k=v,...``.
    ``n_bytes``: a non-negative integer (``0`` turns XLA's pass off), else ``ValueError``."""
    if isinstance(n_bytes, bool) or not isinstance(n_bytes, int) or n_bytes < 0:
        raise ValueError(f"n_bytes: must be a non-negative integer (bytes per loop iteration), got {n_bytes!r}")
    if SMALL_LOOP_OPTION in flags:
        return flags
    option = f"{SMALL_LOOP_OPTION}={n_bytes}"
    pattern = re.compile(rf"{_EXTRA_OPTIONS}=(\S+)")
    if pattern.search(flags):
        return pattern.sub(lambda m: f"{_EXTRA_OPTIONS}={m.group(1)},{option}", flags, count=1)
    return f"{flags} {_EXTRA_OPTIONS}={option}".strip()


def _backends_started() -> bool:
    try:
        from jax._src.xla_bridge import backends_are_initialized
    except ImportError:  # a JAX without it: assume not started, as at a normal import
        return False
    return backends_are_initialized()


def compile_small_loops_whole() -> bool:
    """Put the small-loop threshold into ``os.environ["XLA_FLAGS"]`` (see the module docstring).

    Returns whether JAX will compile with a threshold the flags name (``False``, with a warning, when
    a backend had already started without it)."""
    current = os.environ.get("XLA_FLAGS", "")
    if SMALL_LOOP_OPTION in current:
        return True
    if _backends_started():
        warnings.warn(
            "jaxsim was imported after JAX started its backend, so XLA_FLAGS cannot set "
            f"{SMALL_LOOP_OPTION} any more: loops in this process run kernel by kernel (up to ~7x slower "
            "derivatives of rollouts on CPU). Import jaxsim before the first JAX computation, or set "
            f"XLA_FLAGS='{with_small_loop_threshold('')}' before starting Python.",
            stacklevel=3,
        )
        return False
    os.environ["XLA_FLAGS"] = with_small_loop_threshold(current)
    return True
