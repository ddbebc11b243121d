"""Solar-sail illuminator satellite in the Hill frame (seed 004 #6, Boger & Timakov, lines 2168–2267;
spec seed004_part1 B11), plus the light-pressure scale of the polar-point sail of #18 (spec part2 §2.10).

Relative motion about a point of a circular reference orbit (mean motion ``n``), Hill–Clohessy–
Wiltshire equations, ``x`` radial, ``y`` along the orbital velocity, ``z`` along the orbit normal:

    ẍ = 3n²x + 2nẏ + a_x,   ÿ = −2nẋ + a_y,   z̈ = −n²z + a_z.

Light pressure on the mirror, paper eq. (1) (reconstructed in the spec): ``a = (2CA/(cm))·cos²θ·n̂``
with ``θ`` the angle between the sun direction ``ŝ`` and the mirror normal ``n̂``; the factor 2 is the
perfect reflection (photon momentum returned).  Paper values: ``C = 1370 W/m²``, ``A = 7.85·10³ m²``
(``πR²``, ``R = 50 m``), ``c = 3·10⁸ m/s``, ``m = 500 kg``.

Geometry (**assumed**, the paper gives none): a dawn–dusk sun-synchronous reference orbit at 800 km,
the sun along the orbit normal ``+z``, the mirror normal turned by the pitch ``α`` in the ``y–z``
plane: ``n̂ = (0, sin α, cos α)``, so ``cos θ = cos α`` and the tangential acceleration
``a_max·cos²α·sin α`` is at most ``(2/(3√3))·a_max`` at ``tan α = 1/√2``.  J2 is left out of the
relative dynamics (the reference point precesses with the satellites; the differential terms are
``O(J2)``).  The plant input is ``u = [α, d_x, d_y, d_z]``: the pitch (rad) and a random disturbance
acceleration (m/s², lunar/solar gravity, residual atmosphere, modelling errors).
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.pytree import pytree_dataclass
from jaxsim.core.system import Plant
from jaxsim.core.validation import check_positive

MU_EARTH = 3.986004418e14  # m³/s²
R_EARTH = 6378.137e3  # m, equatorial radius
ALPHA_TANGENTIAL = float(np.arctan(1 / np.sqrt(2)))  # pitch of the largest tangential push (rad)


@pytree_dataclass
class SailParams:
    """Paper #6: ``solar_constant`` W/m², ``area`` m² (printed 7.85e3), ``light_speed`` m/s (printed
    3e8), ``mass`` kg; assumed: ``altitude`` m of the reference orbit (800 km), ``reflection`` 2
    (perfect mirror; 1 for an absorbing sail)."""

    solar_constant: Any = 1370.0
    area: Any = 7.85e3
    light_speed: Any = 3e8
    mass: Any = 500.0
    altitude: Any = 800e3
    reflection: Any = 2.0


def acceleration_scale(p: SailParams) -> jax.Array:
    """``a_max = reflection·C·A/(c·m)`` (m/s²): the light-pressure acceleration with the sun on the normal."""
    return p.reflection * p.solar_constant * p.area / (p.light_speed * p.mass)


def srp_acceleration(p: SailParams, normal: jax.Array, sun: jax.Array) -> jax.Array:
    """Eq. (1): ``a_max·cos²θ·n̂`` for unit ``normal`` and ``sun`` (3,); no force when lit from behind."""
    c = jnp.maximum(jnp.dot(normal, sun), 0.0)
    return acceleration_scale(p) * c * c * normal


def pitch_normal(alpha: jax.Array) -> jax.Array:
    """Mirror normal ``(0, sin α, cos α)`` in the Hill frame."""
    return jnp.stack([jnp.zeros_like(alpha), jnp.sin(alpha), jnp.cos(alpha)])


def mean_motion(p: SailParams) -> jax.Array:
    """``n = √(μ/r³)`` (rad/s) of the circular reference orbit."""
    return jnp.sqrt(MU_EARTH / (R_EARTH + p.altitude) ** 3)


def tangential_acceleration(p: SailParams, alpha: jax.Array) -> jax.Array:
    """``a_y = a_max·cos²α·sin α`` (sun along ``+z``)."""
    return acceleration_scale(p) * jnp.cos(alpha) ** 2 * jnp.sin(alpha)


def pitch_for(p: SailParams, a_y: jax.Array, iters: int = 50) -> jax.Array:
    """The pitch ``|α| ≤ atan(1/√2)`` giving tangential acceleration ``a_y`` (clipped to what the sail
    can give), by bisection on the monotone ``cos²α sin α``."""
    target = jnp.clip(a_y / acceleration_scale(p), -2 / (3 * np.sqrt(3)), 2 / (3 * np.sqrt(3)))

    def body(_: int, lohi: tuple[jax.Array, jax.Array]) -> tuple[jax.Array, jax.Array]:
        lo, hi = lohi
        mid = 0.5 * (lo + hi)
        low = jnp.cos(mid) ** 2 * jnp.sin(mid) < target
        return jnp.where(low, mid, lo), jnp.where(low, hi, mid)

    a0 = jnp.full_like(target, ALPHA_TANGENTIAL)
    lo, hi = jax.lax.fori_loop(0, iters, body, (-a0, a0))
    return 0.5 * (lo + hi)


def hill_dynamics(p: SailParams, x: jax.Array, u: jax.Array, t: jax.Array) -> jax.Array:
    """``ẋ`` of the HCW equations with the sail at pitch ``u[0]`` and disturbance ``u[1:4]``."""
    n = mean_motion(p)
    a = srp_acceleration(p, pitch_normal(u[0]), jnp.array([0.0, 0.0, 1.0])) + u[1:4]
    acc = jnp.stack([3 * n**2 * x[0] + 2 * n * x[4] + a[0], -2 * n * x[3] + a[1], -(n**2) * x[2] + a[2]])
    return jnp.concatenate([x[3:6], acc])


def centre(p: SailParams, x: jax.Array) -> jax.Array:
    """Relative-ellipse parameters ``[x_c, y_c, ρ]`` (m) of the unforced motion through state ``x``:
    radial centre ``4x + 2ẏ/n`` (drives the along-track drift ``ẏ_c = −(3/2)n·x_c``), along-track
    centre ``y − 2ẋ/n`` and radial semi-amplitude ``ρ = √((3x + 2ẏ/n)² + (ẋ/n)²)``."""
    n = mean_motion(p)
    xc = 4 * x[0] + 2 * x[4] / n
    yc = x[1] - 2 * x[3] / n
    rho = jnp.hypot(3 * x[0] + 2 * x[4] / n, x[3] / n)
    return jnp.stack([xc, yc, rho])


def _state(p: SailParams, x: jax.Array) -> jax.Array:
    return x


def sail_hill(params: SailParams | None = None, **kwargs: Any) -> Plant:
    """The illuminator in the Hill frame: state ``[x, y, z, ẋ, ẏ, ż]`` (m, m/s), input ``[α, d_x, d_y, d_z]``,
    output the full state (relative navigation assumed exact)."""
    p = params if params is not None else SailParams(**kwargs)
    for name in ("solar_constant", "area", "light_speed", "mass", "altitude", "reflection"):
        check_positive(name, getattr(p, name))
    return Plant(p, hill_dynamics, _state, n_states=6, n_inputs=4, n_outputs=6, name="sail_hill")


# --- #18: the polar-point sail (spec part2 §2.10) -----------------------------------------------


def light_pressure(solar_constant: Any = 1370.0, light_speed: Any = 3e8) -> jax.Array:
    """Radiation pressure ``P = C/c`` (N/m²) at 1 AU (#18 uses 4.56·10⁻⁶)."""
    return jnp.asarray(solar_constant) / light_speed


def max_visible_latitude(orbit_radius: Any, body_radius: Any = R_EARTH) -> jax.Array:
    """Highest latitude (rad) in line of sight from an equatorial orbit of radius ``orbit_radius``:
    ``arccos(R/r)``."""
    return jnp.arccos(jnp.asarray(body_radius) / orbit_radius)
