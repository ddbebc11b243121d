"""Closed loop of the isoline-seeking unicycle (:mod:`jaxsim.plants.unicycle_field`,
:mod:`jaxsim.control.isoline_seeking`): one ``lax.scan`` at the paper's period ``τ = 0.01 s``; per-run
outcome metrics for Monte Carlo (seed 004, #18; spec B8)."""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from jaxsim.control import isoline_seeking as ctl
from jaxsim.plants import unicycle_field as uf


class Outcome(NamedTuple):
    """One run: ``reached`` (isoline reached), ``t_reach`` s (``inf`` if not), ``collided`` (``d < 0`` once),
    ``min_distance`` m, ``tail_error_rms`` m (RMS of ``ρ − ρ_iso(φ)`` over the samples after reaching, outside
    bypasses), ``coverage`` (share of 5° polar-angle bins visited after reaching: the circuit of the free
    part, in either direction — the bypass direction is random while tracking), ``success``."""

    reached: jax.Array
    t_reach: jax.Array
    collided: jax.Array
    min_distance: jax.Array
    tail_error_rms: jax.Array
    coverage: jax.Array
    success: jax.Array


def rollout(
    g: ctl.SeekingGains,
    pose0: jax.Array,
    discs: jax.Array,
    key: jax.Array,
    *,
    a: Any = 2.0,
    b: Any = 0.5,
    f0: float = 1.0,
    tau: float = 0.01,
    n_steps: int = 3000,
) -> tuple[jax.Array, jax.Array, jax.Array]:
    """Poses ``(n_steps + 1, 3)``, modes ``(n_steps,)`` and the tracking flags ``(n_steps,)`` from ``pose0``."""
    coins = jnp.where(jax.random.bernoulli(key, 0.5, (n_steps,)), 1.0, -1.0)

    def measure(p):
        return uf.field(p, a, b), uf.distance(p, discs)

    s0 = ctl.init(*measure(pose0))

    def body(carry, coin):
        pose, s = carry
        f, d = measure(pose)
        u, s = ctl.control(g, s, f, d, f0, tau, coin)
        pose = uf.step(pose, u, g.v, tau)
        return (pose, s), (pose, s.mode, s.tracking)

    _, (poses, modes, tracking) = jax.lax.scan(body, (pose0, s0), coins)
    return jnp.concatenate([pose0[None], poses]), modes, tracking


def outcome(
    poses: jax.Array,
    modes: jax.Array,
    tracking: jax.Array,
    discs: jax.Array,
    *,
    a: Any = 2.0,
    b: Any = 0.5,
    f0: float = 1.0,
    tau: float = 0.01,
    tol: float = 0.05,
    min_coverage: float = 0.95,
    n_bins: int = 72,
) -> Outcome:
    """Metrics of one rollout; success: reached, no collision, tracking RMS ≤ ``tol`` m and at least
    ``min_coverage`` of the polar-angle bins visited after reaching."""
    p = poses[1:]
    dist = jax.vmap(lambda r: uf.distance(r, discs))(p)
    phi = jnp.arctan2(p[:, 1], p[:, 0])
    err = jnp.hypot(p[:, 0], p[:, 1]) - uf.isoline_radius(phi, f0, a, b)
    n = tracking.shape[0]
    first = jnp.argmax(tracking)
    reached = jnp.any(tracking)
    t_reach = jnp.where(reached, (first + 1) * tau, jnp.inf)
    after = tracking & (modes == ctl.MODE_I)
    rms = jnp.sqrt(jnp.sum(jnp.where(after, err**2, 0.0)) / jnp.maximum(jnp.sum(after), 1))
    bins = jnp.clip(jnp.floor((phi + jnp.pi) / (2 * jnp.pi) * n_bins).astype(int), 0, n_bins - 1)
    coverage = jnp.mean(jnp.zeros(n_bins).at[bins].max(tracking.astype(float)))
    collided = jnp.min(dist) < 0.0
    success = reached & ~collided & (rms <= tol) & (coverage >= min_coverage) & (jnp.sum(after) > n // 10)
    return Outcome(reached, t_reach, collided, jnp.min(dist), rms, coverage, success)
