"""Fit a second-order resonator to frequency-response samples (Levenberg–Marquardt on autodiff Jacobians).

Model ``H(f) = g·ω_n² / (ω_n² − ω² + j·ω·ω_n/Q)``, ``ω = 2πf``: a mass–spring–damper from force to
displacement scaled to a static gain ``g``.  Parameters ``θ = [g, f_n, log Q]`` (``f_n`` in Hz).  The
amplitude peak sits at ``f_r = f_n·√(1 − 1/(2Q²))`` (for ``Q > 1/√2``).

Two residuals:

* ``complex``: ``(H(θ) − H_meas)/|H_meas|`` (real and imaginary parts) — an H1 estimate with phase;
* ``magnitude``: ``log|H(θ)| − log|A_meas|`` — amplitude tables (``g`` then only up to its sign).

At most ``n_iter`` Levenberg–Marquardt trials (:func:`jaxsim.core.least_squares.levenberg_marquardt_solve`,
stopping early at convergence); pure JAX, so it runs under ``jit`` and ``vmap`` (one fit per
Monte-Carlo record).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from jaxsim.core.least_squares import levenberg_marquardt_solve


class ResonatorFit(NamedTuple):
    """``theta = [g, f_n, log Q]``; ``f_r`` amplitude-peak frequency (Hz); ``q``; ``cost`` = ½‖r‖²."""

    theta: jax.Array
    f_n: jax.Array
    q: jax.Array
    f_r: jax.Array
    cost: jax.Array


def resonator_response(theta: jax.Array, f: jax.Array) -> jax.Array:
    """Complex ``H(f)`` of the model for ``theta = [g, f_n, log Q]``, ``f`` in Hz."""
    g, fn, logq = theta[0], theta[1], theta[2]
    wn, w = 2 * jnp.pi * fn, 2 * jnp.pi * jnp.asarray(f)
    return g * wn**2 / (wn**2 - w**2 + 1j * w * wn * jnp.exp(-logq))


def peak_frequency(f_n: jax.Array, q: jax.Array) -> jax.Array:
    """Amplitude-peak frequency ``f_n·√(1 − 1/(2Q²))`` (Hz)."""
    return f_n * jnp.sqrt(1.0 - 0.5 / q**2)


def hold_factor(f: jax.Array, hold: float) -> jax.Array:
    """Zero-order hold of period ``hold`` s: ``(1 − e^{−jωT})/(jωT)`` (1 for ``hold = 0``)."""
    x = 2j * jnp.pi * jnp.asarray(f) * hold
    return jnp.where(hold > 0, (1.0 - jnp.exp(-x)) / jnp.where(hold > 0, x, 1.0), 1.0)


def _residual(theta: jax.Array, f: jax.Array, h: jax.Array, mode: str, hold: float) -> jax.Array:
    model = resonator_response(theta, f) * hold_factor(f, hold)
    if mode == "complex":
        r = (model - h) / jnp.abs(h)
        return jnp.concatenate([jnp.real(r), jnp.imag(r)])
    return jnp.log(jnp.abs(model)) - jnp.log(jnp.abs(h))


def fit_resonator(
    f: jax.Array,
    h: jax.Array,
    theta0: jax.Array,
    *,
    mode: str = "complex",
    hold: float = 0.0,
    n_iter: int = 60,
    lam0: float = 1e-3,
) -> ResonatorFit:
    """Least-squares resonator through ``(f, h)``; ``h`` complex (``mode='complex'``) or amplitudes
    (``mode='magnitude'``); ``theta0 = [g, f_n, log Q]`` a start near the peak.  ``hold``: the
    period (s) of a zero-order hold between the recorded input samples and the resonator (a DAC
    driving the coil from the recorded samples): the model is then ``H(f)·(1 − e^{−jωT})/(jωT)``."""
    if mode not in ("complex", "magnitude"):
        raise ValueError(f"mode: must be 'complex' or 'magnitude', got {mode!r}")
    f = jnp.asarray(f, float)
    h = jnp.asarray(h)
    if f.ndim != 1 or h.shape != f.shape:
        raise ValueError(f"h: expected shape {tuple(f.shape)} matching f (1-D), got {tuple(h.shape)}")
    theta0 = jnp.asarray(theta0, float)
    if theta0.shape != (3,):
        raise ValueError(f"theta0: expected [g, f_n, log Q] of shape (3,), got {tuple(theta0.shape)}")

    def res(t: jax.Array) -> jax.Array:
        return _residual(t, f, h, mode, hold)

    state = levenberg_marquardt_solve(res, theta0, max_steps=int(n_iter), damping=lam0)
    theta, c = state.u, 0.5 * state.cost
    q = jnp.exp(theta[2])
    return ResonatorFit(theta, theta[1], q, peak_frequency(theta[1], q), c)
