"""α–β filters, the growing-memory (least-squares) α–β filter and sliding-window polynomial fits.

Constant-velocity tracking per coordinate (``d`` coordinates in parallel), scan period ``dt``::

    x⁻ = x + v dt,   r = z − x⁻,   x ← x⁻ + α r,   v ← v + (β/dt) r.

* Fixed gains: any ``0 < α ≤ 1``, ``0 < β ≤ 1``; Benedict–Bordner's choice ``β = α²/(2 − α)``.
* Growing memory (seed 003, the vessel tracker's gain rule): initialise ``x = z₁, v = 0`` and use
  ``α_k = 2(2k − 1)/(k(k + 1))``, ``β_k = 6/(k(k + 1))`` for the ``k``-th measurement (``k ≥ 2``):
  after ``k`` measurements the estimate *is* the least-squares straight line through them,
  evaluated at the last one.  ``max_memory = J`` freezes the gains at ``k = J`` afterwards.
* Sliding-window polynomial least squares (seeds 002 and 003): the fit of a degree-``N``
  polynomial to the last ``M`` samples is a fixed FIR filter, :func:`poly_window_weights`;
  a line over the last ``k`` samples equals the growing-memory α–β filter restarted ``k`` samples
  ago, so :func:`window_bank` gives the vessel tracker's whole tuple of windows ``j = 2..J``.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.validation import check_positive


class AlphaBetaResult(NamedTuple):
    """``positions (T, d)``, ``velocities (T, d)`` after each update; ``predictions (T, d)`` the
    one-step predictions each update started from; ``residuals (T, d)`` = measurement − prediction
    (zero for the initialising first sample)."""

    positions: jax.Array
    velocities: jax.Array
    predictions: jax.Array
    residuals: jax.Array


def benedict_bordner_beta(alpha: Any) -> jax.Array:
    """Benedict–Bordner's ``β = α²/(2 − α)``."""
    alpha = jnp.asarray(alpha)
    return alpha**2 / (2.0 - alpha)


def growing_memory_gains(k: Any) -> tuple[jax.Array, jax.Array]:
    """``(α_k, β_k) = (2(2k − 1)/(k(k + 1)), 6/(k(k + 1)))`` for the ``k``-th measurement, ``k ≥ 2``."""
    k = jnp.asarray(k, dtype=float)
    return 2.0 * (2.0 * k - 1.0) / (k * (k + 1.0)), 6.0 / (k * (k + 1.0))


def alpha_beta_update(
    position: jax.Array, velocity: jax.Array, z: jax.Array, alpha: Any, beta: Any, dt: Any
) -> tuple[jax.Array, jax.Array, jax.Array, jax.Array]:
    """One predict–correct step; returns ``(position, velocity, prediction, residual)``."""
    pred = position + velocity * dt
    r = z - pred
    return pred + alpha * r, velocity + beta / dt * r, pred, r


def _as_track(z: Any) -> jax.Array:
    z = jnp.asarray(z)
    if z.ndim == 1:
        z = z[:, None]
    if z.ndim != 2 or z.shape[0] < 1:
        raise ValueError(f"z: expected shape (T,) or (T, d) with T ≥ 1, got {tuple(np.shape(z))}")
    return z


def _run(z: jax.Array, dt: Any, gains) -> AlphaBetaResult:
    def step(carry, inp):
        x, v = carry
        z_t, k = inp
        a, b = gains(k)
        x, v, pred, r = alpha_beta_update(x, v, z_t, a, b, dt)
        return (x, v), (x, v, pred, r)

    x0, v0 = z[0], jnp.zeros_like(z[0])
    ks = jnp.arange(2, z.shape[0] + 1)
    _, (x, v, pred, r) = jax.lax.scan(step, (x0, v0), (z[1:], ks))
    cat = lambda first, rest: jnp.concatenate([first[None], rest])  # noqa: E731
    return AlphaBetaResult(cat(x0, x), cat(v0, v), cat(x0, pred), cat(jnp.zeros_like(x0), r))


def alpha_beta_filter(z: Any, dt: Any, alpha: Any, beta: Any) -> AlphaBetaResult:
    """Fixed-gain α–β filter over ``z (T,)`` or ``(T, d)``; initialised with ``x = z₀, v = 0``."""
    check_positive("dt", dt)
    return _run(_as_track(z), dt, lambda k: (alpha, beta))


def growing_memory_filter(z: Any, dt: Any, max_memory: int | None = None) -> AlphaBetaResult:
    """Growing-memory α–β filter (least-squares line through all samples so far, or through a
    memory growing up to ``max_memory`` samples and then fixed gains ``α_J, β_J``)."""
    check_positive("dt", dt)
    if max_memory is not None and int(max_memory) < 2:
        raise ValueError(f"max_memory: must be at least 2, got {max_memory!r}")
    cap = math.inf if max_memory is None else int(max_memory)
    return _run(_as_track(z), dt, lambda k: growing_memory_gains(jnp.minimum(k, cap)))


def poly_window_weights(window: int, degree: int, dt: Any, eval_t: Any = 0.0) -> jax.Array:
    """FIR weights ``W (degree + 1, window)`` of the least-squares polynomial fit over a window.

    The samples sit at ``t = −(window − 1)·dt, …, −dt, 0`` (oldest first, newest at ``t = 0``).
    Row ``i`` of ``W @ samples`` is the ``i``-th time derivative of the fitted polynomial at
    ``eval_t`` (``eval_t > 0`` extrapolates, e.g. ``dt`` for a one-step prediction).
    """
    window, degree = int(window), int(degree)
    if degree < 0 or window < degree + 1:
        raise ValueError(f"window: need at least degree + 1 = {degree + 1} samples, got {window}")
    check_positive("dt", dt)
    t = (jnp.arange(window, dtype=float) - (window - 1)) * dt - eval_t
    powers = jnp.arange(degree + 1)
    fact = jnp.asarray([math.factorial(i) for i in range(degree + 1)], dtype=float)
    phi = t[:, None] ** powers[None, :] / fact[None, :]  # Taylor basis: coefficients = derivatives
    return jnp.linalg.pinv(phi)


def sliding_window_fit(z: Any, window: int, degree: int, dt: Any, eval_t: Any = 0.0) -> jax.Array:
    """Derivative estimates ``(T − window + 1, degree + 1, d)`` from every window of ``z (T, d)``."""
    z = _as_track(z)
    if z.shape[0] < window:
        raise ValueError(f"z: needs at least window = {window} samples, got {z.shape[0]}")
    w = poly_window_weights(window, degree, dt, eval_t)
    idx = jnp.arange(z.shape[0] - window + 1)[:, None] + jnp.arange(window)[None, :]
    return jnp.einsum("kw,twd->tkd", w, z[idx])


def window_bank(last: Any, dt: Any) -> jax.Array:
    """Line fits over the last ``j`` samples for every ``j = 2..J`` of ``last (J, d)`` (oldest first).

    Returns ``(J − 1, 2, d)``: ``[j − 2, 0]`` position and ``[j − 2, 1]`` velocity at the newest sample.
    """
    z = _as_track(last)
    big_j = z.shape[0]
    if big_j < 2:
        raise ValueError(f"last: needs at least 2 samples, got {big_j}")
    rows = []
    for j in range(2, big_j + 1):
        rows.append(jnp.einsum("kw,wd->kd", poly_window_weights(j, 1, dt), z[big_j - j :]))
    return jnp.stack(rows)
