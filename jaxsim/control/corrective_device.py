"""Nonlinear corrective device (NCD) against pilot-induced oscillation: ``y = k·|u|·sign(x)``, ``x = W(s) u``.

Zaitceva (seed 004, #9; spec seed004_part3.md §2.7, eq. (1)): the output has the magnitude of the input
(times ``k``) and the sign of a phase-lead filtered input, ``W(s) = (T2 s + 1)/(T1 s + 1)`` with
``T1 = 0.01 s``, ``T2 = 0.1 s`` (the paper's values; the standard lead arrangement, spec §2.7): phase
lead without amplitude gain (describing function ≈ ``k·e^{j arg W(jω)}``).  The filter in state form:
``ż = (u − z)/T1``, ``x = (T2/T1)·u + (1 − T2/T1)·z``.

Smooth surrogates (gradient path): ``sign(x) → tanh(x/ε_s)``, ``|u| → √(u² + ε_a²)``.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.pytree import pytree_dataclass


@pytree_dataclass
class NCDParams:
    """``k`` (gain), ``T1``, ``T2`` s (the paper: 0.01, 0.1)."""

    k: Any = 1.0
    T1: Any = 0.01
    T2: Any = 0.1


def filter_output(p: NCDParams, z: jax.Array, u: jax.Array) -> jax.Array:
    """``x = (T2/T1)·u + (1 − T2/T1)·z``."""
    r = p.T2 / p.T1
    return r * u + (1.0 - r) * z


def filter_rate(p: NCDParams, z: jax.Array, u: jax.Array) -> jax.Array:
    """``ż = (u − z)/T1``."""
    return (u - z) / p.T1


def output(p: NCDParams, z: jax.Array, u: jax.Array, eps: tuple[float, float] | None = None) -> jax.Array:
    """``y = k·|u|·sign(x)``; with ``eps = (ε_s, ε_a)`` the smooth ``k·√(u² + ε_a²)·tanh(x/ε_s)``."""
    x = filter_output(p, z, u)
    if eps is None:
        return p.k * jnp.abs(u) * jnp.sign(x)
    es, ea = eps
    return p.k * jnp.sqrt(u * u + ea * ea) * jnp.tanh(x / es)


def lead_phase(p: NCDParams, omega: Any) -> jax.Array:
    """``arg W(jω)`` rad: ``atan(ω T2) − atan(ω T1)`` (max ``asin((T2 − T1)/(T2 + T1))`` at ``1/√(T1 T2)``)."""
    omega = jnp.asarray(omega, dtype=float)
    return jnp.arctan(omega * p.T2) - jnp.arctan(omega * p.T1)
