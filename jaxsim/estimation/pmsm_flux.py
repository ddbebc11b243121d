"""DREM flux observer of a surface-mount PMSM with biased current and voltage sensors (seed 004 #29,
Sinetova, Vedyakov, Pyrkin; spec part 3 §2.9), built on :mod:`jaxsim.estimation.drem`.

Measured ``i_m = i + δ_i``, ``v_m = v + δ_v`` (constant unknown biases), ``R``, ``L`` known.  With
``ξ̇ = v_m − R i_m`` (``ξ(0) = 0``, integrated from the measurements) the flux is ``λ = ξ + ζ t + λ(0)``,
``ζ = R δ_i − δ_v``, and the magnet flux ``x_m = λ − L i = λ_m C(θ)`` is, with ``q = ξ − L i_m``,

    x_m(t) = q(t) + ζ t + c,       c = λ(0) + L δ_i.

``|x_m|² = λ_m²`` is the linear regression ``y = φᵀθ`` with ``y = −|q|²``, ``φ = (2q, 2t q, t², 2t, 1)`` and
the 7 constants ``θ = (c, ζ, |ζ|², ζᵀc, |c|² − λ_m²)`` (:func:`regressor`).  Only ``c``, ``ζ`` and
``λ_m`` enter: ``λ(0)`` and ``δ_i`` are **not separately identifiable** from ``(i_m, v_m)``, so the total
flux is known up to ``L δ_i``, while ``x_m`` — the rotor's electrical angle ``atan2(x_m)`` and
``λ_m = |x_m|`` — is.  (The paper's regression has 9 unknowns: it keeps the flux ``λ(t)`` itself among
them and filters out its growth; the content is the same.)
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from jaxsim.estimation import drem

N_PARAMS = 7


class DremState(NamedTuple):
    """``xi (2,)`` the integral of ``v_m − R i_m``; ``v_last``, ``i_last (2,)`` the previous measurements;
    ``filt (N, 8)`` the filtered ``(y, φ)`` of each of the ``N = 7`` filters; ``theta (7,)`` the estimate."""

    xi: jax.Array
    v_last: jax.Array
    i_last: jax.Array
    filt: jax.Array
    theta: jax.Array


def regressor(q: jax.Array, t: jax.Array) -> tuple[jax.Array, jax.Array]:
    """``(y, φ (7,))`` of ``y = φᵀθ`` at time ``t`` (s) from ``q = ξ − L i_m (2,)`` (Wb)."""
    one = jnp.ones_like(t)
    return -(q @ q), jnp.concatenate([2 * q, 2 * t * q, jnp.stack([t * t, 2 * t, one])])


def true_parameters(c: jax.Array, zeta: jax.Array, lam_m: jax.Array) -> jax.Array:
    """``θ (7,)`` of the regression for given ``c``, ``ζ`` (2,) each and ``λ_m``."""
    return jnp.concatenate([c, zeta, jnp.stack([zeta @ zeta, zeta @ c, c @ c - lam_m**2])])


def magnet_flux(q: jax.Array, t: jax.Array, theta: jax.Array) -> jax.Array:
    """``x̂_m = q + ζ̂ t + ĉ`` (Wb) from the estimate ``θ``."""
    return q + theta[2:4] * t + theta[0:2]


def init(theta0: jax.Array | None = None) -> DremState:
    """Zero integral and filters; ``θ̂(0) = theta0`` (zeros by default)."""
    theta0 = jnp.zeros(N_PARAMS) if theta0 is None else jnp.asarray(theta0, float)
    return DremState(jnp.zeros(2), jnp.zeros(2), jnp.zeros(2), jnp.zeros((N_PARAMS, N_PARAMS + 1)), theta0)


def step(
    state: DremState,
    i_m: jax.Array,
    v_m: jax.Array,
    t: jax.Array,
    R: jax.Array,
    L: jax.Array,
    bank: tuple[jax.Array, jax.Array],
    gamma: jax.Array,
    dt: float,
) -> tuple[DremState, dict[str, jax.Array]]:
    """Advance by ``dt`` with the measurements at ``t``: the integral (the voltage held over the previous
    step — the drive's zero-order hold — and the current by the trapezoid; zero at the first step), the 7 filters
    (``bank`` from :func:`jaxsim.estimation.drem.lowpass_bank`), mixing, the implicit gradient step.
    Returns the state and ``{"x_m": x̂_m (2,), "delta": Δ, "q": q}``."""
    first = t <= 0.0
    xi = state.xi + jnp.where(first, 0.0, dt * (state.v_last - 0.5 * R * (i_m + state.i_last)))
    q = xi - L * i_m
    y, phi = regressor(q, t)
    a, b = bank
    filt = a[:, None] * state.filt + b[:, None] * jnp.concatenate([y[None], phi])[None, :]
    delta, big_y = drem.mix(filt[:, 1:], filt[:, 0])
    theta = drem.estimator_step(state.theta, delta, big_y, gamma, dt)
    return DremState(xi, v_m, i_m, filt, theta), {"x_m": magnet_flux(q, t, theta), "delta": delta, "q": q}


__all__ = ["N_PARAMS", "DremState", "regressor", "true_parameters", "magnet_flux", "init", "step"]
