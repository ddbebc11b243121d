"""Discrete attitude updates from gyro increments under classical coning (seed 004 part 2, paper #2, spec §2.5).

Strapdown gyros deliver angle increments ``Δθ_k = ∫ ω dt`` over sub-intervals of length ``h``; an
attitude update over ``m`` sub-intervals turns them into a rotation vector ``φ`` and composes
``q_k = q_{k−1} ⊗ exp(φ)``.  Algorithms (:data:`ALGORITHMS`, ``m`` sub-samples per update):

* ``first_order`` (m = 1): ``φ = Δθ`` — no coning correction;
* ``two_sample_previous`` (m = 1): ``φ = Δθ_k + (1/12) Δθ_{k−1} × Δθ_k`` (the increment of the previous
  update interval: a polynomial fit of ω over the current and previous interval);
* ``two_sample`` (m = 2): ``φ = Δθ₁ + Δθ₂ + (2/3) Δθ₁ × Δθ₂``;
* ``three_sample`` (m = 3): ``φ = ΣΔθ + (9/20) Δθ₁ × Δθ₃ + (27/40) Δθ₂ × (Δθ₃ − Δθ₁)``
  (Miller 1983: the coefficients that cancel the coning error through ``λ⁵``).

Classical coning of half-angle ``α`` at frequency ``Ω``: the attitude is ``exp(α[0, cos Ωt, sin Ωt])``
(periodic: no net rotation), the body rate ``ω = [−2Ω sin²(α/2), −Ω sin α sin Ωt, Ω sin α cos Ωt]``.
An algorithm that misses part of the non-commutative (coning) rotation drifts about x at a constant
rate; :func:`coning_drift_rate` gives it in closed form to order ``α²`` (exact in ``λ = Ωh``) from the
increments' cross products ``(Δθ_i × Δθ_j)_x = 4 sin²α sin²(λ/2) sin((j − i)λ)`` and the true coning
rotation ``½ sin²α (mλ − sin mλ)`` of an ``m``-sample interval.  Leading orders: first order
``∝ λ²``, the two-sample forms ``∝ λ⁴``, three-sample ``∝ λ⁶``.

Quaternions are ``[w, x, y, z]`` (Hamilton), body-to-reference.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.rotations import quat_exp, quat_mul, quat_rotation_vector
from jaxsim.core.validation import check_positive, check_shape

__all__ = [
    "ALGORITHMS",
    "SAMPLES_PER_UPDATE",
    "coning_attitude",
    "coning_drift_rate",
    "coning_increments",
    "coning_rate",
    "drift_rate",
    "propagate",
    "quat_exp",
    "quat_mul",
    "quat_rotation_vector",
    "rotation_vectors",
]

SAMPLES_PER_UPDATE = {"first_order": 1, "two_sample_previous": 1, "two_sample": 2, "three_sample": 3}
ALGORITHMS = tuple(SAMPLES_PER_UPDATE)


def coning_attitude(t: Any, alpha: Any, omega: Any) -> jax.Array:
    """Exact attitude ``exp(α[0, cos Ωt, sin Ωt])`` at times ``t`` (s): ``(..., 4)``."""
    t = jnp.asarray(t, float)
    phi = alpha * jnp.stack([jnp.zeros_like(t), jnp.cos(omega * t), jnp.sin(omega * t)], axis=-1)
    return quat_exp(phi)


def coning_rate(t: Any, alpha: Any, omega: Any) -> jax.Array:
    """Body rate of classical coning (rad/s) at ``t``: ``(..., 3)``."""
    t = jnp.asarray(t, float)
    sa = jnp.sin(alpha)
    return jnp.stack(
        [
            jnp.full_like(t, -2.0 * omega * jnp.sin(alpha / 2) ** 2),
            -omega * sa * jnp.sin(omega * t),
            omega * sa * jnp.cos(omega * t),
        ],
        axis=-1,
    )


def coning_increments(n: int, h: float, alpha: Any, omega: Any, t0: float = 0.0) -> jax.Array:
    """Exact gyro increments ``∫ ω dt`` over ``[t0 + k h, t0 + (k+1) h]``, ``k < n``: ``(n, 3)`` rad."""
    check_positive("h", h)
    t = t0 + jnp.arange(n + 1) * h
    sa = jnp.sin(alpha)
    x = jnp.full((n,), -2.0 * omega * jnp.sin(alpha / 2) ** 2 * h)
    y = sa * jnp.diff(jnp.cos(omega * t))
    z = sa * jnp.diff(jnp.sin(omega * t))
    return jnp.stack([x, y, z], axis=-1)


def rotation_vectors(increments: jax.Array, algorithm: str, previous: Any = None) -> jax.Array:
    """Rotation vectors of the updates from sub-interval increments ``(n, 3)`` (``n`` a multiple of the
    algorithm's samples per update): ``(n // m, 3)``.  ``previous (3,)``: the increment of the interval
    before the first (``two_sample_previous`` only; default zero, which leaves the first update
    without its correction)."""
    if algorithm not in SAMPLES_PER_UPDATE:
        raise ValueError(f"algorithm: expected one of {ALGORITHMS}, got {algorithm!r}")
    increments = jnp.asarray(increments, float)
    check_shape("increments", increments, (None, 3))
    m = SAMPLES_PER_UPDATE[algorithm]
    if increments.shape[0] % m:
        raise ValueError(f"increments: {increments.shape[0]} samples is not a multiple of {m} ({algorithm})")
    d = increments.reshape(-1, m, 3)
    total = d.sum(axis=1)
    if algorithm == "first_order":
        return total
    if algorithm == "two_sample_previous":
        first = jnp.zeros((1, 3)) if previous is None else jnp.reshape(jnp.asarray(previous, float), (1, 3))
        prev = jnp.concatenate([first, total[:-1]])
        return total + jnp.cross(prev, total) / 12.0
    if algorithm == "two_sample":
        return total + (2.0 / 3.0) * jnp.cross(d[:, 0], d[:, 1])
    return total + (9.0 / 20.0) * jnp.cross(d[:, 0], d[:, 2]) + (27.0 / 40.0) * jnp.cross(d[:, 1], d[:, 2] - d[:, 0])


def propagate(q0: Any, phis: jax.Array) -> jax.Array:
    """``q_k = q_{k−1} ⊗ exp(φ_k)`` for every update (``lax.scan``): ``(n, 4)``, renormalised each step."""
    q0 = jnp.asarray(q0, float)
    check_shape("q0", q0, (4,))

    def step(q, phi):
        q = quat_mul(q, quat_exp(phi))
        q = q / jnp.linalg.norm(q)
        return q, q

    return jax.lax.scan(step, q0, phis)[1]


def coning_drift_rate(alpha: Any, omega: Any, h: Any, algorithm: str) -> jax.Array:
    """Closed-form x-axis drift rate (rad/s) of ``algorithm`` under classical coning, sub-interval
    ``h`` (s), to order ``α²`` and exact in ``λ = Ωh``: (algorithm's coning term − true coning
    rotation) per update interval ``m h``.  (The y, z components and the x rate integral are exact.)"""
    if algorithm not in SAMPLES_PER_UPDATE:
        raise ValueError(f"algorithm: expected one of {ALGORITHMS}, got {algorithm!r}")
    lam = omega * h
    s2 = jnp.sin(alpha) ** 2
    c = 4.0 * s2 * jnp.sin(lam / 2) ** 2  # (Δθ_i × Δθ_j)_x = c sin((j − i)λ)
    m = SAMPLES_PER_UPDATE[algorithm]
    true = 0.5 * s2 * (m * lam - jnp.sin(m * lam))
    alg = {
        "first_order": 0.0,
        "two_sample_previous": c * jnp.sin(lam) / 12.0,
        "two_sample": (2.0 / 3.0) * c * jnp.sin(lam),
        "three_sample": c * ((9.0 / 20.0) * jnp.sin(2 * lam) + (27.0 / 20.0) * jnp.sin(lam)),
    }[algorithm]
    return (alg - true) / (m * h)


def drift_rate(t: Any, q_true: jax.Array, q_est: jax.Array) -> jax.Array:
    """Drift rates ``(3,)`` (rad/s): least-squares slopes over ``t (n,)`` of the rotation vector of
    ``q_true⁻¹ ⊗ q_est`` (body-frame attitude error), which ignore one-off and zero-mean errors."""
    t = jnp.asarray(t, float)
    conj = q_true * jnp.array([1.0, -1.0, -1.0, -1.0])
    err = quat_rotation_vector(quat_mul(conj, q_est))
    tc = t - t.mean()
    return (tc @ (err - err.mean(axis=0))) / (tc @ tc)
