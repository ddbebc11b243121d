"""Second-order plants of the fuzzy-PID paper (seed 000, paper 1; spec section 1.1).

* static plant ``W(s) = K / ((T1 s + 1)(T2 s + 1))``, defaults ``K = 2, T1 = 0.1, T2 = 0.5``
  (paper lines 468–470);
* astatic plant ``W(s) = K / (s (T s + 1))``, defaults ``K = 2, T = 0.1`` (paper line 609).

State ``x = [y, ẏ]`` (output and its rate), one input ``u`` (the plant input after the
disturbance: the closed loop feeds ``u − f``, the sign that reproduces the paper's numbers), one
output ``y``.  Time in seconds (the paper gives no unit; seconds assumed).
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.pytree import pytree_dataclass
from jaxsim.core.system import Plant
from jaxsim.core.validation import check_finite, check_positive


@pytree_dataclass
class StaticParams:
    """``K/((T1 s+1)(T2 s+1))``; gain ``K`` (output unit per input unit), time constants in s."""

    K: Any = 2.0
    T1: Any = 0.1
    T2: Any = 0.5


@pytree_dataclass
class AstaticParams:
    """``K/(s(T s+1))``; gain ``K`` (output unit per input unit per s), time constant ``T`` in s."""

    K: Any = 2.0
    T: Any = 0.1


def static_dynamics(p: StaticParams, x: jax.Array, u: jax.Array, t: jax.Array) -> jax.Array:
    """``T1 T2 ÿ + (T1 + T2) ẏ + y = K u``; returns ``[ẏ, ÿ]``."""
    y, v = x[0], x[1]
    acc = (p.K * u[0] - y - (p.T1 + p.T2) * v) / (p.T1 * p.T2)
    return jnp.stack([v, acc])


def astatic_dynamics(p: AstaticParams, x: jax.Array, u: jax.Array, t: jax.Array) -> jax.Array:
    """``T ÿ + ẏ = K u``; returns ``[ẏ, ÿ]``."""
    v = x[1]
    return jnp.stack([v, (p.K * u[0] - v) / p.T])


def position_output(p: Any, x: jax.Array) -> jax.Array:
    """``y = x[0]``, shape ``(1,)``."""
    return x[:1]


def validate_static(p: StaticParams) -> None:
    check_finite("K", p.K)
    check_positive("T1", p.T1)
    check_positive("T2", p.T2)


def validate_astatic(p: AstaticParams) -> None:
    check_finite("K", p.K)
    check_positive("T", p.T)


def static_plant(params: StaticParams | None = None, **kwargs: Any) -> Plant:
    """The static plant as a :class:`~jaxsim.core.system.Plant` (``K``, ``T1``, ``T2`` as kwargs)."""
    p = params if params is not None else StaticParams(**kwargs)
    validate_static(p)
    return Plant(p, static_dynamics, position_output, n_states=2, n_inputs=1, n_outputs=1, name="static_second_order")


def astatic_plant(params: AstaticParams | None = None, **kwargs: Any) -> Plant:
    """The astatic plant as a :class:`~jaxsim.core.system.Plant` (``K``, ``T`` as kwargs)."""
    p = params if params is not None else AstaticParams(**kwargs)
    validate_astatic(p)
    return Plant(p, astatic_dynamics, position_output, n_states=2, n_inputs=1, n_outputs=1, name="astatic_second_order")


def static_transfer_function(p: StaticParams) -> tuple[jax.Array, jax.Array]:
    """``(num, den)`` in descending powers of s."""
    return jnp.stack([jnp.asarray(p.K, float)]), jnp.stack([p.T1 * p.T2, p.T1 + p.T2, jnp.ones_like(p.T1 * 1.0)])


def astatic_transfer_function(p: AstaticParams) -> tuple[jax.Array, jax.Array]:
    """``(num, den)`` in descending powers of s."""
    return jnp.stack([jnp.asarray(p.K, float)]), jnp.stack(
        [jnp.asarray(p.T, float), jnp.ones_like(p.T * 1.0), jnp.zeros_like(p.T * 1.0)]
    )
