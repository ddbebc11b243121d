"""The one place where the toolkit's floating-point precision is set.

Riccati solutions, covariances and every validation against an oracle need float64, so importing
:mod:`jaxsim` turns on JAX's 64-bit mode (``jax_enable_x64``).  Arrays keep the dtype they are
given: a caller who passes float32 arrays gets the float32 fast path.  Set the environment variable
``JAXSIM_X64=0`` before the import to leave JAX's default (float32) untouched.
"""

from __future__ import annotations

import os

import jax

X64_ENV_VAR = "JAXSIM_X64"


def enable_x64_from_env() -> bool:
    """Enable float64 in JAX unless ``JAXSIM_X64=0``; returns whether float64 is on."""
    wanted = os.environ.get(X64_ENV_VAR, "1").strip().lower() not in ("0", "false", "no")
    if wanted:
        jax.config.update("jax_enable_x64", True)
    return bool(jax.config.jax_enable_x64)
