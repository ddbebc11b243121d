"""Chain of integrators with a bounded input and a bounded input disturbance (seed 004 #31, Ahi,
Adelipour, Haeri; spec seed004_part3 §2.10, eq. (1))::

    ẋ1 = x2, …, ẋ_{n−1} = x_n, ẋ_n = sat_{u_m}(u) + d,   |d| ≤ d_m

The paper simulates n = 3 and prints no numbers; ``u_m = 1`` and ``d_m = 0.2`` are the spec's
suggested values (assumed).  State ``x`` of shape ``(n,)``; input ``[u, d]`` (command, disturbance).
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.pytree import pytree_dataclass
from jaxsim.core.validation import is_concrete


@pytree_dataclass
class Params:
    """``u_m``: input bound (actuator saturation); ``d_m``: disturbance bound (``d_m < u_m``)."""

    u_m: Any = 1.0  # assumed (spec §2.10: "e.g. u_m = 1, d_m = 0.2")
    d_m: Any = 0.2


def validate(p: Params) -> None:
    """ValueError naming the field unless ``0 ≤ d_m < u_m`` (concrete values)."""
    if is_concrete(p.u_m) and not np.all(np.asarray(p.u_m) > 0):
        raise ValueError(f"u_m: must be positive, got {p.u_m!r}")
    if is_concrete(p.d_m) and is_concrete(p.u_m):
        if not np.all((np.asarray(p.d_m) >= 0) & (np.asarray(p.d_m) < np.asarray(p.u_m))):
            raise ValueError(f"d_m: must satisfy 0 ≤ d_m < u_m, got {p.d_m!r}")


def dynamics(p: Params, x: jax.Array, u: jax.Array, t: jax.Array) -> jax.Array:
    """``ẋ`` of the chain; ``u = [command, disturbance]`` (the command saturated at ``u_m``)."""
    drive = jnp.clip(u[0], -p.u_m, p.u_m) + u[1]
    return jnp.concatenate([x[1:], drive[None]])


def matrices(n: int) -> tuple[jax.Array, jax.Array]:
    """``(A, B)`` of the unsaturated chain of ``n`` integrators."""
    return jnp.eye(n, k=1), jnp.zeros((n, 1)).at[n - 1, 0].set(1.0)
