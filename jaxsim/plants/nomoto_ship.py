"""Ship heading: first-order Nomoto model with a rudder servo, and its PID heading loop (seed 004 #4,
Tomilova; spec seed004_part1 B9).  The paper's matrices are lost (refs. [5, 6], Veremey/Sotnikova);
the Nomoto form stands in for them, with assumed constants.

    ψ̇ = r,   T ṙ + r = K δ,   T_r δ̇ + δ = δ_c        (state ``[ψ, r, δ]``, input ``δ_c``)

PID heading law ``δ_c = −(k_p ψ + k_d r + k_i ∫ψ)`` (heading error ψ for the command ψ* = 0; yaw rate
measured).  Units: rad, rad/s, s.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.pytree import pytree_dataclass
from jaxsim.lti.statespace import StateSpace, state_space


@pytree_dataclass
class Params:
    """Nomoto gain ``K`` (1/s), time constant ``T`` (s), rudder servo time constant ``T_r`` (s).
    Assumed values of a small cargo vessel (the paper's model is lost): K = 0.1 1/s, T = 20 s,
    T_r = 2 s."""

    K: Any = 0.1
    T: Any = 20.0
    T_r: Any = 2.0


def dynamics(p: Params, x: jax.Array, u: jax.Array, t: jax.Array) -> jax.Array:
    """``[ψ̇, ṙ, δ̇]`` of state ``[ψ, r, δ]`` under the rudder command ``u = [δ_c]``."""
    return jnp.stack([x[1], (p.K * x[2] - x[1]) / p.T, (u[0] - x[2]) / p.T_r])


def open_loop_matrices(p: Params) -> tuple[jax.Array, jax.Array]:
    """``(A, B)`` of ``[ψ, r, δ, ∫ψ]`` (the PID's integrator appended) from ``δ_c``."""
    z = jnp.zeros(())
    a = jnp.array(
        [
            [z, 1.0 + z, z, z],
            [z, -1.0 / p.T, p.K / p.T, z],
            [z, z, -1.0 / p.T_r, z],
            [1.0 + z, z, z, z],
        ]
    )
    b = jnp.stack([z, z, 1.0 / p.T_r, z])[:, None]
    return a, b


def pid_row(gains: jax.Array) -> jax.Array:
    """Row ``(4,)`` with ``δ_c = −row·[ψ, r, δ, ∫ψ]`` for ``gains = [k_p, k_d, k_i]``."""
    return jnp.stack([gains[0], gains[1], jnp.zeros_like(gains[0]), gains[2]])


def closed_loop_matrix(p: Params, gains: jax.Array) -> jax.Array:
    """``A − B·row`` (4×4)."""
    a, b = open_loop_matrices(p)
    return a - b @ pid_row(gains)[None, :]


def loop_transfer(p: Params, gains: jax.Array) -> StateSpace:
    """Loop ``L(s) = C(s)P(s)`` broken at the rudder command (negative-feedback convention):
    ``L = row·(sI − A)⁻¹B``."""
    a, b = open_loop_matrices(p)
    return state_space(a, b, pid_row(gains)[None, :], 0.0)


def complementary_sensitivity(p: Params, gains: jax.Array, w: jax.Array) -> jax.Array:
    """``|T(jω)| = |L/(1 + L)|`` on the frequencies ``w`` (rad/s), by the state-space resolvent."""
    a, b = open_loop_matrices(p)
    row = pid_row(gains)

    def one(wk: jax.Array) -> jax.Array:
        lval = row @ jnp.linalg.solve(1j * wk * jnp.eye(4) - a, b[:, 0])
        return jnp.abs(lval / (1.0 + lval))

    return jax.vmap(one)(w)


def sector_residuals(eigs: jax.Array, alpha: Any, beta: Any) -> jax.Array:
    """Pole region C = {x + jy: x ≤ −α, |y| ≤ |x| tan β} as ``g ≤ 0`` per eigenvalue: ``(2, n)``
    rows ``Re λ + α`` and ``|Im λ| + tan β · Re λ`` (differentiable for distinct eigenvalues)."""
    re, im = jnp.real(eigs), jnp.imag(eigs)
    return jnp.stack([re + alpha, jnp.abs(im) + jnp.tan(beta) * re])
