"""XLA flags that cut CPU compile time, and how to add them before JAX starts.

Most of a study's or a test's time on a CPU is XLA compiling closed-loop rollouts.  Measured with
``python -m experiments.benchmarks.compile_time`` and the suite (2-core CPU, jax 0.9.2):

* :data:`FAST_COMPILE` — XLA's CPU *fusion emitters* off (the older loop emitter generates each
  fusion): TRMS loss compile 2.9 → 2.6 s, its gradient 5.7 → 3.7 s, the PID gradient 0.55 → 0.22 s;
  run times 8.2 → 5.5 ms, 53 → 50 ms, 0.8 → 0.7 ms, but the AUV formation's gradient runs 265 →
  324 ms.  The CLI uses it (:func:`experiments.cli.main`).
* :data:`FAST_COMPILE_LOW_OPT` — also LLVM's lowest optimisation level: compile roughly halves
  (TRMS gradient 5.7 → 2.2 s, AUV gradient 11.7 → 6.0 s) while programs run 1.3–2.3× slower.  The
  test suite uses it (compilation is most of its time; ``tests/plants`` 104 → 68 s); results agree
  with the default build to ~1e-12 relative.

XLA reads ``XLA_FLAGS`` once, when JAX creates its CPU backend (the first computation), so
:func:`add_xla_flags` must run before that; afterwards it changes nothing in this process (child
processes still inherit the variable).
"""

from __future__ import annotations

import os
from collections.abc import MutableMapping

FAST_COMPILE: tuple[str, ...] = ("--xla_cpu_use_fusion_emitters=false",)
"""Compile faster at about the same run time (see the module docstring for measurements)."""

FAST_COMPILE_LOW_OPT: tuple[str, ...] = FAST_COMPILE + ("--xla_backend_optimization_level=0",)
"""Compile about twice as fast; programs run 1.3–2.3× slower (for compile-bound work: tests)."""


def add_xla_flags(flags: tuple[str, ...] | list[str], environ: MutableMapping[str, str] | None = None) -> str:
    """Append each ``--name=value`` of ``flags`` to ``XLA_FLAGS`` in ``environ`` (default
    ``os.environ``) unless that variable already sets ``name`` — a user's own choice wins.  Returns
    the new value.  Call before JAX's first computation (XLA reads the variable once)."""
    env = os.environ if environ is None else environ
    current = env.get("XLA_FLAGS", "").split()
    named = {f.split("=", 1)[0] for f in current}
    for flag in flags:
        if not flag.startswith("--") or "=" not in flag:
            raise ValueError(f"flags: each must read --name=value, got {flag!r}")
        if flag.split("=", 1)[0] not in named:
            current.append(flag)
    env["XLA_FLAGS"] = " ".join(current)
    return env["XLA_FLAGS"]
