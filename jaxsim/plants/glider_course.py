"""Underwater glider in the horizontal plane: course dynamics and the trajectory kinematics of seed 004
part 4 B7 (authors lost).

The paper gives the kinematics, eq. (1) (printed twice with the same left side; the second line is η)::

    ξ̇ = V (cos β cos ψ + sin β sin ψ) = V cos(ψ − β),    η̇ = V sin(ψ − β)

with the speed ``V``, the heading ``ψ`` and the drift angle ``β`` "taken from the model of the plant",
which it does not print.  Here the course model is the first-order Nomoto model with a rudder servo
(:mod:`jaxsim.plants.nomoto_ship`, reused) and the drift angle a first-order lag of the yaw rate::

    ψ̇ = r,   T ṙ + r = K δ,   T_r δ̇ + δ = δ_c,   T_β β̇ + β = K_β r

State ``[ψ, r, δ, β, ξ, η]`` (rad, rad/s, rad, rad, m, m), input ``[δ_c]`` (rad).  In a steady turn at
rudder ``δ``: ``r = K δ``, ``β = K_β K δ`` and the track is a circle of radius ``V / (K δ)``.
All constants are assumed (spec B7: V ≈ 0.2–0.5 m/s, Nomoto T ≈ 5–20 s).
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.pytree import pytree_dataclass
from jaxsim.plants import nomoto_ship

STATE = ("psi", "r", "delta", "beta", "xi", "eta")


@pytree_dataclass
class Params:
    """Nomoto gain ``K`` (1/s) and time constant ``T`` (s), rudder servo ``T_r`` (s), speed ``V`` (m/s),
    drift gain ``K_beta`` (s: rad of drift per rad/s of yaw rate) and lag ``T_beta`` (s).  Assumed: a
    slow glider (V = 0.3 m/s, T = 10 s within the spec's 5–20 s); K = 0.05 1/s gives a 20 m turning
    radius at 0.3 rad of rudder, where ``K_beta = 4 s`` gives a drift angle of 3.4°."""

    K: Any = 0.05
    T: Any = 10.0
    T_r: Any = 2.0
    V: Any = 0.3
    K_beta: Any = 4.0
    T_beta: Any = 5.0


def dynamics(p: Params, x: jax.Array, u: jax.Array, t: jax.Array) -> jax.Array:
    """``ẋ`` of ``x = [ψ, r, δ, β, ξ, η]`` under the rudder command ``u = [δ_c]`` (eq. (1) for ξ, η)."""
    course = nomoto_ship.dynamics(nomoto_ship.Params(K=p.K, T=p.T, T_r=p.T_r), x[:3], u, t)
    psi, r, beta = x[0], x[1], x[3]
    return jnp.concatenate(
        [course, jnp.stack([(p.K_beta * r - beta) / p.T_beta, p.V * jnp.cos(psi - beta), p.V * jnp.sin(psi - beta)])]
    )


def steady_turn(p: Params, delta: Any) -> dict[str, jax.Array]:
    """The steady turn at constant rudder ``delta`` (rad): yaw rate, drift angle, radius (m)."""
    r = p.K * jnp.asarray(delta)
    return {"r": r, "beta": p.K_beta * r, "radius": p.V / jnp.abs(r)}


__all__ = ["Params", "STATE", "dynamics", "steady_turn"]
