"""Course autopilot of an underwater glider with MEMS sensors (seed 004 part 4 B7): a heading
complementary filter (MEMS rate gyro + magnetic compass), dead reckoning with the modelled drift angle
(the paper's eq. (1) on the estimates), line-of-sight guidance to a straight line through the start
point, and a PD rudder law with a smooth rudder limit.

Units: rad, rad/s, m, s.  The filter ``ψ̂̇ = r_m + k_c (ψ_m − ψ̂)`` passes the gyro above the crossover
``k_c`` and the compass below it: a gyro bias ``b`` leaves a steady heading error ``b / k_c``; compass
noise is smoothed with bandwidth ``k_c``.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from jaxsim.core.pytree import pytree_dataclass
from jaxsim.core.rotations import wrap_angle
from jaxsim.plants.glider_course import Params


@pytree_dataclass
class Gains:
    """Rudder law ``δ_c = −k_p (ψ̂ − ψ_c) − k_d r_m`` (rad/rad, s), filter crossover ``k_c`` (1/s), LOS
    look-ahead distance (m), rudder limit ``delta_max`` (rad)."""

    kp: Any = 1.0
    kd: Any = 10.0
    kc: Any = 0.02
    lookahead: Any = 30.0
    delta_max: Any = 0.35


class NavState(NamedTuple):
    """Heading ``psi`` and drift ``beta`` estimates (rad), dead-reckoned position ``xi, eta`` (m)."""

    psi: jax.Array
    beta: jax.Array
    xi: jax.Array
    eta: jax.Array


def nav_step(nav: NavState, r_meas: jax.Array, psi_meas: jax.Array, gains: Gains, model: Params, dt: Any) -> NavState:
    """One step of the heading filter and the drift-angle model (Euler) and of dead reckoning (with the
    mid-step course); ``model``: the nominal plant the navigation believes in (``V``, ``K_beta``,
    ``T_beta``)."""
    dpsi = dt * (r_meas + gains.kc * wrap_angle(psi_meas - nav.psi))
    beta = nav.beta + dt * (model.K_beta * r_meas - nav.beta) / model.T_beta
    course = nav.psi + 0.5 * dpsi - 0.5 * (nav.beta + beta)  # mid-step course: second-order dead reckoning
    xi, eta = nav.xi + dt * model.V * jnp.cos(course), nav.eta + dt * model.V * jnp.sin(course)
    return NavState(wrap_angle(nav.psi + dpsi), beta, xi, eta)


def los_heading(nav: NavState, line_heading: jax.Array, lookahead: Any) -> jax.Array:
    """Heading command toward the line through the origin with direction ``line_heading``: the line
    direction minus ``atan(e / Δ)`` of the (left-positive) cross-track error ``e``."""
    e = -jnp.sin(line_heading) * nav.xi + jnp.cos(line_heading) * nav.eta
    return line_heading - jnp.arctan(e / lookahead)


def rudder_command(nav: NavState, r_meas: jax.Array, psi_cmd: jax.Array, gains: Gains) -> jax.Array:
    """``δ_c = δ_max tanh((−k_p wrap_angle(ψ̂ − ψ_c) − k_d r_m) / δ_max)``: PD with a smooth rudder limit."""
    raw = -gains.kp * wrap_angle(nav.psi - psi_cmd) - gains.kd * r_meas
    return gains.delta_max * jnp.tanh(raw / gains.delta_max)


__all__ = ["Gains", "NavState", "nav_step", "los_heading", "rudder_command"]
