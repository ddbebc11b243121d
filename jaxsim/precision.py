"""The one place where the toolkit's floating-point precision is set.

Riccati solutions, covariances and every validation against an oracle need float64, so importing
:mod:`jaxsim` turns on JAX's 64-bit mode (``jax_enable_x64``).  Arrays keep the dtype they are
given: a caller who passes float32 arrays gets the float32 fast path.  Set the environment variable
``JAXSIM_X64=0`` before the import to leave JAX's default (float32) untouched.

:func:`to_common_float` is the one rule by which a public entry point that mixes arrays (the
filters: model matrices, initial belief, measurements) brings them to one float dtype.
"""

from __future__ import annotations

import os
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

X64_ENV_VAR = "JAXSIM_X64"


def enable_x64_from_env() -> bool:
    """Enable float64 in JAX unless ``JAXSIM_X64=0``; returns whether float64 is on."""
    wanted = os.environ.get(X64_ENV_VAR, "1").strip().lower() not in ("0", "false", "no")
    if wanted:
        jax.config.update("jax_enable_x64", True)
    return bool(jax.config.jax_enable_x64)


def _kind(leaf: Any) -> str:
    """NumPy dtype kind of an array leaf; ``""`` for Python scalars and extended dtypes (PRNG keys)."""
    try:
        return np.dtype(leaf.dtype).kind
    except (AttributeError, TypeError):
        return ""


def _numeric_leaves(tree: Any, kinds: str) -> list[Any]:
    return [leaf for leaf in jax.tree_util.tree_leaves(tree) if _kind(leaf) and _kind(leaf) in kinds]


def _cast(tree: Any, dtype: Any, kinds: str) -> Any:
    def one(leaf):
        if _kind(leaf) and _kind(leaf) in kinds and leaf.dtype != dtype:
            return jnp.asarray(leaf).astype(dtype)
        return leaf

    return jax.tree_util.tree_map(one, tree)


def to_common_float(data: Any, params: Any = None) -> tuple[Any, Any]:
    """Cast a computation's arrays to one float dtype, ``jnp.result_type(*arrays, float)``.

    ``data`` (states, covariances, model matrices, measurements, inputs): every integer and float
    array leaf is cast.  ``params`` (a user model's parameter pytree): only float leaves are cast and
    take part in the choice, so integer parameters (indices, counts) keep their type.  Bool, complex
    and typed PRNG-key leaves and Python scalars (weakly typed) are left alone (pass raw ``uint32``
    keys outside both trees).

    The rule (JAX's type promotion): float64 when any array is float64, or when every array is an
    integer and float64 is enabled; float32 when the float arrays are all float32 (the measured
    fast path: integers next to float32 arrays do not widen it).  Returns ``(data, params)``.
    """
    leaves = _numeric_leaves(data, "iuf") + _numeric_leaves(params, "f")
    dtype = jnp.result_type(*leaves, float)
    return _cast(data, dtype, "iuf"), _cast(params, dtype, "f")
