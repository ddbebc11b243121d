"""Periodic gaits of a capsule robot's internal mass (:mod:`jaxsim.plants.capsule_robot`) and the
closed-form optima they are measured against (seed 004 #1, Chernousko; spec part 1 §B5).

A gait is the relative velocity ``u = ξ̇`` of the internal mass on ``N`` steps of one period,
``(N,)`` in m/s.  :func:`bounded_acceleration_gait` maps any real vector to an admissible gait of the
*acceleration-control* problem, so a gradient tuner can search it without constraints:

* the relative acceleration (the jumps of ``u`` over ``dt``, cyclically) is at most ``a_max`` — with
  ``a_max = kg/μ`` the drive never pushes a resting body backwards, so the body only moves forwards
  (forward motion alternating with rest); braking is unbounded (down to one-step reversals);
* ``ξ`` is periodic (``Σu = 0``) and its range is at most the stroke ``L``.

Closed forms (natural units of :mod:`jaxsim.plants.capsule_robot`; derivations in the functions):

* acceleration control under those constraints, three phases — accelerate at ``kg/μ`` over the stroke,
  reverse instantly, brake at ``kg/μ`` back to rest — :func:`three_phase_optimum`:
  ``V = √(μkgL/2) ≈ 0.7071·√(μkgL)``, period ``2√(2μL/(kg))``;
* velocity control with two moving phases and the body at rest when each period starts
  (:func:`resting_two_phase_speed`): as the return becomes instant, ``V = √(μkgL)·u₁/(1 + u₁²)``
  for ``u₁ ≤ 1`` and ``√(μkgL)/(2u₁)`` above, at most ``√(μkgL)/2`` (``u₁ = 1``).
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.dry_friction import slide
from jaxsim.core.validation import check_positive_int
from jaxsim.plants.capsule_robot import Params, hold_acceleration, mass_ratio, speed_unit


def _check_even(name: str, n: int) -> int:
    n = check_positive_int(name, n)
    if n % 2:
        raise ValueError(f"{name}: must be even (the reversal falls on a step boundary), got {n}")
    return n


def bounded_acceleration_gait(theta: jax.Array, a_max: Any, stroke: Any, dt: Any) -> jax.Array:
    """An admissible gait ``u (N,)`` (m/s) from any ``theta (N,)``: accelerations
    ``a_i = a_max·(1 − s_i/mean(s))`` with ``s = softplus(theta)`` (so ``Σa = 0`` and ``a ≤ a_max``),
    ``u`` their cumulative sum times ``dt`` less its mean (``ξ`` periodic), scaled down by
    ``min(1, stroke/range(ξ))`` (which keeps ``a ≤ a_max``).  ``a_max`` m/s², ``stroke`` m, ``dt`` s."""
    s = jax.nn.softplus(theta)
    a = a_max * (1.0 - s / jnp.mean(s))
    u = jnp.cumsum(a) * dt
    u = u - jnp.mean(u)
    return u * jnp.minimum(1.0, stroke / jnp.maximum(stroke_of(u, dt), 1e-300))


def stroke_of(u: jax.Array, dt: Any) -> jax.Array:
    """The range of ``ξ`` (m) over one period of the gait ``u (N,)``."""
    xi = jnp.cumsum(u) * dt
    return jnp.max(xi) - jnp.min(xi)


def max_acceleration_of(u: jax.Array, dt: Any) -> jax.Array:
    """The largest cyclic jump of ``u`` over ``dt`` (m/s²): the gait's largest forward acceleration."""
    return jnp.max(jnp.diff(u, prepend=u[-1:])) / dt


def three_phase_optimum(p: Params) -> dict[str, Any]:
    """The acceleration-control optimum in closed form.  The mass accelerates at ``a = kg/μ`` from rest
    over the stroke (time ``τ = √(2L/a)``, speed ``v = aτ``; the body holds), reverses instantly (the body
    jumps to ``2μv``), then brakes at ``a`` back to rest at ``ξ = 0`` (time ``τ``; the body decelerates at
    ``μa + kg = 2kg`` and stops exactly when the mass does).  Distance ``(2μv)²/(4kg) = 2μL`` per period
    ``2τ``: ``V = μL/τ = √(μkgL/2)``.  Returns ``speed`` (m/s), ``period`` (s), ``tau`` (s)."""
    a = hold_acceleration(p)
    tau = jnp.sqrt(2 * p.L / a)
    return {"speed": mass_ratio(p) * p.L / tau, "period": 2 * tau, "tau": tau}


def three_phase_gait(p: Params, n: int) -> tuple[jax.Array, jax.Array]:
    """:func:`three_phase_optimum`'s gait on ``n`` steps (``n`` even): ``(u (n,), dt)`` — ``u`` at the
    steps' midpoints, so the staircase's jumps are exactly ``a·dt``."""
    n = _check_even("n", n)
    opt = three_phase_optimum(p)
    a, tau = hold_acceleration(p), opt["tau"]
    dt = 2 * tau / n
    t = (jnp.arange(n) + 0.5) * dt
    return jnp.where(t < tau, a * t, a * (t - 2 * tau)), dt


def resting_two_phase_speed(p: Params, u1: Any, u2: Any) -> jax.Array:
    """Average body speed (m/s) of the velocity-control gait: forward over the stroke at ``u1``, back
    at ``u2`` (both in units of ``√(kgL/μ)``, the mass's speed scale), then rest until the body stops —
    so the body is at rest when each period starts (event-exact: impulses ``−μΔu``, Coulomb slides).
    ``u2 → ∞`` (instant return), natural units: with ``u1 ≤ 1`` the body slides back ``u1²/2`` and stops,
    then the return impulse sends it forward ``1 + u1²/2`` — ``V = u1/(1 + u1²)``; with ``u1 > 1`` it is
    still sliding back when the return starts and nets ``1/u1²`` per ``2/u1`` — ``V = 1/(2·u1)``."""
    d1, w1 = slide(-u1, 1.0, 1.0 / u1)
    d2, w2 = slide(w1 + u1 + u2, 1.0, 1.0 / u2)
    w3 = w2 - u2
    d3, _ = slide(w3, 1.0, jnp.abs(w3))
    return speed_unit(p) * (d1 + d2 + d3) / (1.0 / u1 + 1.0 / u2 + jnp.abs(w3))


def symmetric_two_phase_gait(p: Params, speed: Any, n: int) -> tuple[jax.Array, jax.Array]:
    """Forward and back over the stroke at ``±speed`` (m/s), no rest: ``(u (n,), dt)``, ``n`` even.
    Its periodic regimes form a continuum (the body never stops); from rest the average speed grows
    with ``speed`` without bound — why the optimum needs a constraint set."""
    n = _check_even("n", n)
    dt = 2 * p.L / speed / n
    return jnp.where(jnp.arange(n) < n // 2, speed, -speed) * jnp.ones(n), dt


__all__ = [
    "bounded_acceleration_gait",
    "stroke_of",
    "max_acceleration_of",
    "three_phase_optimum",
    "three_phase_gait",
    "resting_two_phase_speed",
    "symmetric_two_phase_gait",
]
