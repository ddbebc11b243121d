"""Linearisation of a plant around an operating point, and equilibrium search, with ``jacfwd``."""

from __future__ import annotations

from typing import Callable, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.system import Plant
from jaxsim.core.validation import check_finite


class Linearization(NamedTuple):
    """``δẋ = A δx + B δu``, ``δy = C δx + D δu`` around ``(x0, u0)``."""

    a: jax.Array  # (n, n)
    b: jax.Array  # (n, m)
    c: jax.Array  # (p, n)
    d: jax.Array  # (p, m)


def linearize(plant: Plant, x0: jax.Array, u0: jax.Array, t: float = 0.0) -> Linearization:
    """Jacobians of ``dynamics`` and ``output`` at ``(x0, u0, t)`` (``x0 (n,)``, ``u0 (m,)``); ``D`` is
    the Jacobian of the plant's ``feedthrough`` term (zero without one).  Runs as one jitted program,
    compiled once per plant structure (its functions) and shapes, reused for new parameters or points."""
    x0 = jnp.asarray(x0, dtype=float)
    u0 = jnp.asarray(u0, dtype=float)
    if x0.shape != (plant.n_states,):
        raise ValueError(f"x0: expected shape ({plant.n_states},), got {tuple(x0.shape)}")
    if u0.shape != (plant.n_inputs,):
        raise ValueError(f"u0: expected shape ({plant.n_inputs},), got {tuple(u0.shape)}")
    check_finite("x0", x0)
    check_finite("u0", u0)
    tt = jnp.asarray(t, dtype=x0.dtype)
    if all(isinstance(leaf, _ARRAY_TYPES) for leaf in jax.tree_util.tree_leaves(plant.params)):
        return _jacobians(plant, x0, u0, tt)
    return _jacobians.__wrapped__(plant, x0, u0, tt)  # parameters jit cannot take: run eagerly


_ARRAY_TYPES = (jax.Array, np.ndarray, np.generic, bool, int, float, complex)


@jax.jit
def _jacobians(plant: Plant, x0: jax.Array, u0: jax.Array, t: jax.Array) -> Linearization:
    # one compiled program (the plant is a pytree: its functions are the cache key, its parameters
    # arguments); run eagerly, every operation of the Jacobians was compiled on its own — 725
    # compilations, ~20 s, for the MJX TRMS's field
    a, b = jax.jacfwd(plant.f, argnums=(0, 1))(x0, u0, t)
    c = jax.jacfwd(plant.h)(x0, u0)
    if plant.feedthrough is None:
        d = jnp.zeros((c.shape[0], u0.shape[0]), dtype=x0.dtype)
    else:
        d = jax.jacfwd(plant.h, argnums=1)(x0, u0)
    return Linearization(a, b, c, d)


class Equilibrium(NamedTuple):
    z: jax.Array  # solution
    residual_norm: jax.Array  # ‖residual(z)‖₂ at the solution


def find_equilibrium(
    residual: Callable[[jax.Array], jax.Array],
    z0: jax.Array,
    n_iter: int = 50,
) -> Equilibrium:
    """Gauss–Newton on ``residual(z) = 0`` (least squares if over/under-determined).

    Typical use: ``residual = lambda x: plant.f(x, u_eq, 0.)`` for the state at a fixed input, or
    a residual that stacks ``f(x, u)`` with output constraints to solve for ``(x, u)`` together.
    Differentiable with respect to anything ``residual`` closes over.
    """
    z0 = jnp.asarray(z0, dtype=float)
    check_finite("z0", z0)

    def body(_, z):
        r = residual(z)
        jac = jax.jacfwd(residual)(z)
        step = jnp.linalg.lstsq(jac, -r)[0]
        return z + step

    z = jax.lax.fori_loop(0, n_iter, body, z0)
    return Equilibrium(z, jnp.linalg.norm(residual(z)))
