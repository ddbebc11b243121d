"""A vessel seen by a surveillance radar: straight legs joined by a coordinated turn (seed 003).

The paper's target (seed 003, "Fuzzy tracking of a vessel's trajectory", section 4, Fig. 4)
"first moves straight and uniformly, then manoeuvres: a turn of radius 300 m", at 10 m/s and at
20 m/s.  The truth is kinematic (no dynamics): constant speed ``V`` throughout, heading ``ψ``
constant on the legs and changing at the constant rate ``ω = ±V/R`` on the arc (a coordinated
turn: the acceleration ``V²/R`` is normal to the velocity).  With the turn starting at
``t₀`` and lasting ``T = |Δψ|·R/V``::

    t ≤ t₀:          p = p₀ + V t (cos ψ₀, sin ψ₀)
    t₀ < t ≤ t₀ + T: p = p(t₀) + (V/ω) (sin(ψ₀ + ω s) − sin ψ₀, cos ψ₀ − cos(ψ₀ + ω s)),  s = t − t₀
    t > t₀ + T:      p = p(t₀ + T) + V (t − t₀ − T) (cos ψ₁, sin ψ₁),  ψ₁ = ψ₀ + Δψ

Angles in radians from the x axis (counter-clockwise), positions in metres, speeds in m/s.  A
positive ``turn_angle`` turns left.  Everything is a pure function of ``t`` (any shape) and of the
parameters (array leaves: vmap over speeds, radii, headings).
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from jaxsim.core.pytree import pytree_dataclass
from jaxsim.core.validation import check_finite, check_positive, check_shape


@pytree_dataclass
class VesselManoeuvre:
    """Straight leg, coordinated turn, straight leg.

    Defaults: the paper's 10 m/s run — speed 10 m/s and turn radius 300 m (seed 003, section 4);
    the turn from t = 45 s (its shaded manoeuvre interval [45, 90] s) through 90° (assumed: the
    paper does not state the angle; a 300 m arc flown for 45 s at 10 m/s is 86°).
    """

    speed: Any = 10.0  # m/s
    turn_radius: Any = 300.0  # m
    turn_start: Any = 45.0  # s
    turn_angle: Any = math.pi / 2  # rad, > 0 turns left
    heading: Any = 0.0  # rad, initial course from the x axis
    start: Any = (0.0, 0.0)  # m, position at t = 0

    @property
    def turn_rate(self) -> jax.Array:
        """Signed turn rate ``ω = sign(Δψ)·V/R`` on the arc (rad/s)."""
        return jnp.where(jnp.asarray(self.turn_angle) >= 0, 1.0, -1.0) * self.speed / self.turn_radius

    @property
    def turn_duration(self) -> jax.Array:
        """``T = |Δψ| R / V`` (s)."""
        return jnp.abs(self.turn_angle) * self.turn_radius / self.speed

    @property
    def turn_end(self) -> jax.Array:
        return self.turn_start + self.turn_duration


def vessel_manoeuvre(
    speed: Any = 10.0,
    turn_radius: Any = 300.0,
    turn_start: Any = 45.0,
    turn_angle: Any = math.pi / 2,
    heading: Any = 0.0,
    start: Any = (0.0, 0.0),
) -> VesselManoeuvre:
    """Validated :class:`VesselManoeuvre` (``ValueError`` for a non-positive speed or radius, a
    negative turn start, a non-finite value or a start position that is not ``(2,)``)."""
    check_positive("speed", speed)
    check_positive("turn_radius", turn_radius)
    check_positive("turn_start", turn_start, allow_zero=True)
    check_finite("turn_angle", turn_angle)
    check_finite("heading", heading)
    check_shape("start", start, (2,))
    check_finite("start", start)
    return VesselManoeuvre(
        jnp.asarray(speed, float),
        jnp.asarray(turn_radius, float),
        jnp.asarray(turn_start, float),
        jnp.asarray(turn_angle, float),
        jnp.asarray(heading, float),
        jnp.asarray(start, float),
    )


class VesselState(NamedTuple):
    """Truth at the requested times: ``position (…, 2)`` m, ``velocity (…, 2)`` m/s, ``heading (…)``
    rad and ``turning (…)`` (bool: on the arc)."""

    position: jax.Array
    velocity: jax.Array
    heading: jax.Array
    turning: jax.Array


def vessel_state(m: VesselManoeuvre, t: Any) -> VesselState:
    """Position, velocity and heading of the vessel at times ``t`` (s, any shape)."""
    t = jnp.asarray(t, float)
    v, psi0, omega = m.speed, m.heading, m.turn_rate
    t0, t1 = m.turn_start, m.turn_end
    s = jnp.clip(t - t0, 0.0, m.turn_duration)  # time spent on the arc
    before = jnp.minimum(t, t0)  # time on the first leg
    after = jnp.maximum(t - t1, 0.0)  # time on the last leg
    psi = psi0 + omega * s
    direction = lambda a: jnp.stack([jnp.cos(a), jnp.sin(a)], axis=-1)  # noqa: E731
    p_leg1 = v * before[..., None] * direction(psi0)
    arc = (v / omega) * jnp.stack([jnp.sin(psi) - jnp.sin(psi0), jnp.cos(psi0) - jnp.cos(psi)], axis=-1)
    pos = jnp.asarray(m.start) + p_leg1 + arc + v * after[..., None] * direction(psi)
    return VesselState(pos, v * direction(psi), psi, (t > t0) & (t < t1))
