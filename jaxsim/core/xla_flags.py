"""XLA flags that cut CPU compile time for compile-bound work (tests, CI), and how to add them.

Most of a test's time on a CPU is XLA compiling closed-loop rollouts.  :data:`LOW_OPT` sets LLVM's
lowest optimisation level: measured with ``python -m experiments.benchmarks.compile_time``-style
programs (2-core CPU, jax 0.9.2), the TRMS loss compiles in 2.5 s instead of 2.9 s, its gradient
4.7 s instead of 5.7 s and the AUV formation's gradient 8.8 s instead of 11.7 s, while each call
runs 1.3–3.2× slower (TRMS loss 8 → 14 ms, AUV gradient 265 → 856 ms); ``pytest -n 2 tests/plants``
takes 87 s instead of 104 s.  Results agree with the default build to rounding
(``tests/core/test_xla_flags.py``).  The test suite uses it; the CLI does not (study runs are long
enough for the slower code to cost more than the compile time saved).

Tried and not used: ``--xla_cpu_use_fusion_emitters=false`` (XLA's older loop emitter) compiles
faster still (TRMS gradient 3.7 s, same run time) but duplicates shared subexpressions inside a
fusion: the 37-input sorting network of :mod:`jaxsim.control.fuzzy` then takes more than 8 GB to
compile (0.35 GB by default) — a test worker was killed for memory in a full run.

XLA reads ``XLA_FLAGS`` once, when JAX creates its CPU backend (the first computation), so
:func:`add_xla_flags` must run before that; afterwards it changes nothing in this process (child
processes still inherit the variable).
"""

from __future__ import annotations

import os
from collections.abc import MutableMapping

LOW_OPT: tuple[str, ...] = ("--xla_backend_optimization_level=0",)
"""Compile faster; compiled programs run 1.3–3.2× slower (for compile-bound work: tests)."""


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
