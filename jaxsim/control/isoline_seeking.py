"""Non-gradient isoline seeking and tracking with obstacle bypass: a hybrid sliding-mode law for a
constant-speed unicycle that measures only the field value ``f`` and the distance ``d`` to the nearest
obstacle (seed 004, #18, Nikolaev/Matveev; spec seed004_part1.md B8).  ``ḟ``, ``ḋ`` by backward differences.

Modes: ``I`` (to/along the isoline), ``M`` (mediator: turn until the obstacle is abeam), ``D`` (bypass at
the distance ``d_D`` held at entry)::

    I: u = δ·ū·sgn S_f,   S_f = ḟ + μ·v·χ(f − f0)
    M: u = δ_D·ū
    D: u = δ_D·ū·sgn S_d, S_d = ḋ + η·v·χ(d − d_D)

``χ = arctan``.  Transitions: ``I → M`` when ``d`` decreases to ``d_O``; ``M → D`` when ``ḋ ≥ 0`` (``d_D :=
d``); ``D → I`` when ``f − f0`` changes sign after at least ``t_min`` s in ``D``.  ``δ_D := δ·sgn(f − f0)``
while the isoline has not yet been reached (search), a random ±1 at each entry to ``M`` once it has
(tracking).  The paper's end-of-bypass test state ``T`` and some conditions are garbled in the source;
this simplified switching (documented in the study) keeps ``I``, ``M``, ``D``.  Parameters: the paper's
(spec B8): ``v = 1 m/s``, ``ū = 10 rad/s``, ``μ = η = 0.3``, ``d_O = 0.3 m``, ``δ = 1``.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from jaxsim.core.pytree import pytree_dataclass

MODE_I, MODE_M, MODE_D = 0, 1, 2


@pytree_dataclass
class SeekingGains:
    """``v`` m/s, ``u_max`` rad/s, ``mu``, ``eta``, ``d_o`` m, ``delta`` (±1); ours: ``t_min`` s (dwell in ``D``),
    ``f_tol`` (field units) for "the isoline is reached"."""

    v: Any = 1.0  # paper
    u_max: Any = 10.0  # paper
    mu: Any = 0.3  # paper
    eta: Any = 0.3  # paper
    d_o: Any = 0.3  # paper
    delta: Any = 1.0  # paper
    t_min: Any = 0.3  # assumed: minimum time in D before D → I
    f_tol: Any = 0.05  # assumed: "f reaches f0" as |f − f0| ≤ f_tol (the sliding mode approaches asymptotically)


class SeekingState(NamedTuple):
    """Mode (int), ``d_D`` m, ``δ_D``, previous ``f`` and ``d``, ``tracking`` (isoline reached), time in mode s."""

    mode: jax.Array
    d_d: jax.Array
    delta_d: jax.Array
    f_prev: jax.Array
    d_prev: jax.Array
    tracking: jax.Array
    t_mode: jax.Array


def init(f: jax.Array, d: jax.Array) -> SeekingState:
    """Start in ``I`` with the first measurements as the previous ones."""
    z = jnp.zeros(())
    return SeekingState(jnp.asarray(MODE_I), z, jnp.ones(()), jnp.asarray(f), jnp.asarray(d), jnp.asarray(False), z)


def control(
    g: SeekingGains, s: SeekingState, f: jax.Array, d: jax.Array, f0: Any, tau: Any, coin: jax.Array
) -> tuple[jax.Array, SeekingState]:
    """One period ``tau``: the turn rate ``u`` and the next state from the measurements ``f``, ``d``;
    ``coin`` (±1) is the random bypass direction drawn for this period (used on entry to ``M`` while tracking)."""
    f_dot = (f - s.f_prev) / tau
    d_dot = (d - s.d_prev) / tau
    crossed = (f - f0) * (s.f_prev - f0) <= 0.0
    tracking = s.tracking | crossed | (jnp.abs(f - f0) <= g.f_tol)
    # transitions
    to_m = (s.mode == MODE_I) & (d <= g.d_o) & (d_dot < 0)
    to_d = (s.mode == MODE_M) & (d_dot >= 0)
    to_i = (s.mode == MODE_D) & crossed & (s.t_mode >= g.t_min)
    mode = jnp.where(to_m, MODE_M, jnp.where(to_d, MODE_D, jnp.where(to_i, MODE_I, s.mode)))
    search_dir = g.delta * jnp.where(f >= f0, 1.0, -1.0)
    delta_d = jnp.where(to_m, jnp.where(tracking, coin, search_dir), s.delta_d)
    d_d = jnp.where(to_d, d, s.d_d)
    t_mode = jnp.where(mode == s.mode, s.t_mode + tau, 0.0)
    # laws
    s_f = f_dot + g.mu * g.v * jnp.arctan(f - f0)
    s_d = d_dot + g.eta * g.v * jnp.arctan(d - d_d)
    u = jnp.select(
        [mode == MODE_I, mode == MODE_M],
        [g.delta * g.u_max * jnp.sign(s_f), delta_d * g.u_max],
        delta_d * g.u_max * jnp.sign(s_d),
    )
    return u, SeekingState(mode, d_d, delta_d, f, d, tracking, t_mode)
