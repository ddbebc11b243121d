"""Room air temperature of one heating unit (seed 004, paper #11, lines 2698–2841; spec B12).

Model (1): ``m·c_a·ṫ_a = Q_h − k_w·s_w·(t_a − t_out) − 0.28·L·ρ_a·c_a·(t_a − t_vent)``, i.e. the
scalar state-space form (2)–(3) ``ẋ = A x + B1 u1 + B2 u2 + B3 u3``, ``y = x`` with

* ``x = t_a`` (°C), inputs ``u = [Q_h, t_out, t_vent]`` (heater heat, outdoor and ventilation-air
  temperature);
* ``A = −(k_w s_w + 0.28 L ρ_a c_a)/(m c_a)``, ``B1 = 1/(m c_a)``, ``B2 = k_w s_w/(m c_a)``,
  ``B3 = 0.28 L ρ_a/m`` (= ``0.28 L ρ_a c_a/(m c_a)``).

The paper gives **no** physical values, only the controllability gramians of the three channels,
``W_i = B_i²/(−2A)`` = 0.0783, 0.6136, 0.00025.  Three gramians fix the three lumped parameters
``k_w s_w``, ``0.28 L ρ_a c_a`` and ``m c_a`` uniquely (:func:`params_from_gramians`); the defaults
below are that back-solve as printed in the spec (B12), in the paper's unstated (scaled) units — an
assumption, not paper data.  Time unit: the paper's, unstated (hours read best: ``−1/A`` ≈ 0.78).
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.pytree import pytree_dataclass
from jaxsim.core.system import Plant
from jaxsim.core.validation import check_finite, check_positive


@pytree_dataclass
class HeatingRoomParams:
    """Lumped parameters (paper's scaled units; spec B12 back-solve, assumed):

    ``envelope = k_w·s_w`` (heat per °C), ``ventilation = 0.28·L·ρ_a·c_a`` (heat per °C),
    ``capacity = m·c_a`` (heat per °C per time unit)."""

    envelope: Any = 2.7994
    ventilation: Any = 0.05651
    capacity: Any = 2.2360


@pytree_dataclass
class HeatedRoomParams:
    """The room seen from the heater: lumped parameters plus the two temperatures as parameters
    (°C; assumed defaults, the paper gives none), so a loop's controller drives ``Q_h`` alone and a
    Monte Carlo draws ``t_out``."""

    room: HeatingRoomParams = HeatingRoomParams()
    t_out: Any = -10.0
    t_vent: Any = 18.0


def state_space(p: HeatingRoomParams) -> tuple[jax.Array, jax.Array]:
    """``(A (1, 1), B (1, 3))`` of eq. (2); inputs ``[Q_h, t_out, t_vent]``."""
    a = -(p.envelope + p.ventilation) / p.capacity
    b = jnp.stack([1.0 / p.capacity, p.envelope / p.capacity, p.ventilation / p.capacity])
    return jnp.reshape(a, (1, 1)), jnp.reshape(b, (1, 3))


def gramians(p: HeatingRoomParams) -> jax.Array:
    """Closed-form controllability gramians ``W_i = B_i²/(−2A)`` of the three channels, eq. (4), ``(3,)``."""
    a, b = state_space(p)
    return b[0] ** 2 / (-2.0 * a[0, 0])


def params_from_gramians(w_heater: float, w_outdoor: float, w_vent: float) -> HeatingRoomParams:
    """The unique positive lumped parameters whose gramians are the given ones.

    With ``B1 = 1/M``, ``B2 = k/M``, ``B3 = h/M``: ``k = √(W2/W1)``, ``h = √(W3/W1)`` and
    ``W1 = 1/(2 M (k + h))`` gives ``M``.
    """
    w = np.asarray([w_heater, w_outdoor, w_vent], float)
    if not np.all(np.isfinite(w)) or np.any(w <= 0):
        raise ValueError(f"w_heater/w_outdoor/w_vent: gramians must be positive and finite, got {w.tolist()}")
    k = float(np.sqrt(w[1] / w[0]))
    h = float(np.sqrt(w[2] / w[0]))
    return HeatingRoomParams(envelope=k, ventilation=h, capacity=1.0 / (2.0 * w[0] * (k + h)))


def steady_heat(p: HeatingRoomParams, t_room: Any, t_out: Any, t_vent: Any) -> jax.Array:
    """Heater heat ``Q_h`` that holds ``t_room`` (°C) against ``t_out``, ``t_vent`` (°C): ``ẋ = 0``."""
    return p.envelope * (t_room - t_out) + p.ventilation * (t_room - t_vent)


def dynamics(p: HeatingRoomParams, x: jax.Array, u: jax.Array, t: jax.Array) -> jax.Array:
    """``ẋ = A x + B u``, ``x (1,)`` °C, ``u = [Q_h, t_out, t_vent]``."""
    return (u[0] - p.envelope * (x[0] - u[1]) - p.ventilation * (x[0] - u[2]))[None] / p.capacity


def output(p: HeatingRoomParams, x: jax.Array) -> jax.Array:
    """Room temperature, shape ``(1,)``."""
    return x[:1]


def heater_dynamics(p: HeatedRoomParams, x: jax.Array, u: jax.Array, t: jax.Array) -> jax.Array:
    """``ẋ`` of eq. (1) with ``u = [Q_h]`` and the temperatures from ``p``."""
    full = jnp.stack([u[0], jnp.asarray(p.t_out, x.dtype), jnp.asarray(p.t_vent, x.dtype)])
    return dynamics(p.room, x, full, t)


def heated_room(params: HeatedRoomParams | None = None, **kwargs: Any) -> Plant:
    """The room as a one-input plant (``u = [Q_h]``) for a heater loop; ``t_out``, ``t_vent`` are parameters."""
    p = params if params is not None else HeatedRoomParams(**kwargs)
    heating_room(p.room)  # checks the lumped parameters
    check_finite("t_out", p.t_out)
    check_finite("t_vent", p.t_vent)
    return Plant(p, heater_dynamics, _room_output, n_states=1, n_inputs=1, n_outputs=1, name="heated_room")


def _room_output(p: HeatedRoomParams, x: jax.Array) -> jax.Array:
    return x[:1]


def heating_room(params: HeatingRoomParams | None = None, **kwargs: Any) -> Plant:
    """The room as a :class:`~jaxsim.core.system.Plant` with 3 inputs ``[Q_h, t_out, t_vent]``."""
    p = params if params is not None else HeatingRoomParams(**kwargs)
    for name in ("envelope", "ventilation", "capacity"):
        check_finite(name, getattr(p, name))
    check_positive("capacity", p.capacity)
    check_positive("envelope", p.envelope, allow_zero=True)
    check_positive("ventilation", p.ventilation, allow_zero=True)
    return Plant(p, dynamics, output, n_states=1, n_inputs=3, n_outputs=1, name="heating_room")
