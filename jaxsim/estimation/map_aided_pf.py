"""Rao–Blackwellised particle filter for map-aided navigation with a drifting navigation error and an
unknown map/sensor bias (seed 004 part 4 §B4), with and without systematic resampling.

Navigation-system (NS) output ``X^NS_i = X_i + ΔX_i`` with ``ΔX_i = Δ̄ + δx_i`` per axis: ``Δ̄`` a
random constant, ``(δx, δV)`` a second-order Markov process per axis (``δẋ = δV``,
``δV̇ = −2hδV − h²δx + q w``, stationary ``σ_x² = q²/(4h³)``).  Field fixes::

    z_i = G(X^NS_i − ΔX_i) + c + v_i,   c ~ N(0, σ_c²) constant,  v_i ~ N(0, σ_v²) white.

Particles carry the six nonlinear states ``ξ = (Δ̄x, Δ̄y, δx, δy, δVx, δVy)``; the bias ``c`` enters
linearly and is integrated out by one scalar Kalman filter per particle (its variance is the same for
every particle, so only the per-particle means are stored).  One step: map look-up at
``X^NS − (Δ̄ + δx)``, weight by the predictive density of the innovation, update the per-particle
bias mean, record the weighted estimate, resample (systematic, every step) or not (sequential
importance sampling), propagate ``(δx, δV)`` with four Gaussian draws per particle.

Units: km for positions, km/s for velocity errors, s for time, field units (mGal) for ``G``, ``c``, ``v``.
Float64 throughout (set in :mod:`jaxsim.precision`).
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.discretize import van_loan
from jaxsim.core.grid_interp import bilinear
from jaxsim.core.pytree import pytree_dataclass, static_field
from jaxsim.core.validation import check_positive, check_positive_int
from jaxsim.estimation.particle import systematic_resample


@pytree_dataclass
class MapPFModel:
    """The filter's model.

    ``values (ny, nx)`` map (mGal) with south-west node at ``origin (2,)`` km and node ``spacing`` km
    (static); ``phi (2, 2)`` and ``chol_q (2, 2)``: per-axis transition and lower Cholesky factor of the
    process noise of ``(δx, δV)`` over one fix interval; ``sigma_bar`` (km): σ of ``Δ̄`` per axis;
    ``chol_p0 (2, 2)``: lower Cholesky factor of the initial covariance of ``(δx, δV)`` per axis;
    ``sigma_c``, ``sigma_v`` (mGal)."""

    values: jax.Array
    origin: jax.Array
    phi: jax.Array
    chol_q: jax.Array
    chol_p0: jax.Array
    sigma_bar: jax.Array
    sigma_c: jax.Array
    sigma_v: jax.Array
    spacing: float = static_field()


class PFState(NamedTuple):
    """``particles (L, 6)`` = (Δ̄x, Δ̄y, δx, δy, δVx, δVy); ``c_mean (L,)`` per-particle bias means;
    ``c_var ()`` the shared bias variance; ``weights (L,)`` normalised."""

    particles: jax.Array
    c_mean: jax.Array
    c_var: jax.Array
    weights: jax.Array


class PFEstimate(NamedTuple):
    """Weighted estimate of the NS position error ``ΔX = Δ̄ + δx``: ``mean (2,)`` km, ``cov (2, 2)``
    km², and the effective sample size before resampling."""

    mean: jax.Array
    cov: jax.Array
    ess: jax.Array


def markov2_discrete(h: float, sigma_x: float, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(Φ, chol Q_d, chol P∞)`` (2×2 each) of ``δẋ = δV, δV̇ = −2hδV − h²δx + q w`` over ``dt`` s with
    ``q² = 4h³σ_x²`` (stationary ``σ_x`` in km, ``σ_V = hσ_x``); ``h`` in 1/s."""
    check_positive("h", h)
    check_positive("sigma_x", sigma_x)
    check_positive("dt", dt)
    a = jnp.array([[0.0, 1.0], [-(h**2), -2.0 * h]])
    g = jnp.array([[0.0], [math.sqrt(4.0 * h**3 * sigma_x**2)]])
    phi, qd = van_loan(a, jnp.eye(1), dt, g)
    qd = 0.5 * (qd + qd.T)
    p_inf = np.diag([sigma_x**2, (h * sigma_x) ** 2])
    return np.asarray(phi), np.linalg.cholesky(np.asarray(qd)), np.linalg.cholesky(p_inf)


def make_model(
    values: Any,
    origin: Any,
    spacing: float,
    *,
    h: float,
    sigma_x: float,
    dt: float,
    sigma_bar: float,
    sigma_c: float,
    sigma_v: float,
) -> MapPFModel:
    """:class:`MapPFModel` from the map and the error-model parameters (checked here, before tracing)."""
    values = jnp.asarray(values, dtype=float)
    if values.ndim != 2 or min(values.shape) < 2:
        raise ValueError(f"values: expected a (ny, nx) map with ny, nx ≥ 2, got shape {tuple(values.shape)}")
    origin = jnp.asarray(origin, dtype=float)
    if origin.shape != (2,):
        raise ValueError(f"origin: expected shape (2,), got {tuple(origin.shape)}")
    check_positive("spacing", spacing)
    check_positive("sigma_bar", sigma_bar, allow_zero=True)
    check_positive("sigma_c", sigma_c, allow_zero=True)
    check_positive("sigma_v", sigma_v)
    phi, lq, lp0 = markov2_discrete(h, sigma_x, dt)
    f = lambda v: jnp.asarray(v, dtype=float)  # noqa: E731
    return MapPFModel(
        values, origin, f(phi), f(lq), f(lp0), f(sigma_bar), f(sigma_c), f(sigma_v), spacing=float(spacing)
    )


def position_error(particles: jax.Array) -> jax.Array:
    """``ΔX = Δ̄ + δx`` (km) of ``particles (..., 6)`` → ``(..., 2)``."""
    return particles[..., 0:2] + particles[..., 2:4]


def sample_prior(model: MapPFModel, key: jax.Array, n: int) -> jax.Array:
    """``(n, 6)`` draws of ξ: ``Δ̄ ~ N(0, σ̄² I)``, ``(δx, δV)`` per axis from the stationary law."""
    kb, km = jax.random.split(key)
    bar = model.sigma_bar * jax.random.normal(kb, (n, 2))
    z = jax.random.normal(km, (n, 2, 2))  # (particle, axis, [x, V])
    xv = jnp.einsum("ij,naj->nai", model.chol_p0, z)
    return jnp.concatenate([bar, xv[:, :, 0], xv[:, :, 1]], axis=1)


def propagate(model: MapPFModel, key: jax.Array, particles: jax.Array) -> jax.Array:
    """One fix interval of ``(δx, δV)`` per axis (four Gaussian draws per particle); ``Δ̄`` constant."""
    n = particles.shape[0]
    xv = jnp.stack([particles[:, 2:4], particles[:, 4:6]], axis=-1)  # (n, axis, [x, V])
    w = jax.random.normal(key, (n, 2, 2))
    xv = jnp.einsum("ij,naj->nai", model.phi, xv) + jnp.einsum("ij,naj->nai", model.chol_q, w)
    return jnp.concatenate([particles[:, :2], xv[:, :, 0], xv[:, :, 1]], axis=1)


@jax.jit
def map_lookup(values: jax.Array, origin: jax.Array, spacing: jax.Array, points: jax.Array) -> jax.Array:
    """Bilinear map value (mGal) at ``points (L, 2)`` km → ``(L,)`` (one named call, so that an operation
    count can treat it as the paper's "map-value interpolation")."""
    return bilinear(values[None], origin, spacing, points)[:, 0]


def pf_init(model: MapPFModel, key: jax.Array, n_particles: int) -> PFState:
    """``n_particles`` prior draws with equal weights; bias mean 0, variance ``σ_c²``."""
    n = check_positive_int("n_particles", n_particles)
    x = sample_prior(model, key, n)
    return PFState(x, jnp.zeros(n), model.sigma_c**2, jnp.full(n, 1.0 / n))


def pf_step(
    model: MapPFModel, key: jax.Array, state: PFState, z: jax.Array, x_ns: jax.Array, resampling: bool
) -> tuple[PFState, PFEstimate]:
    """Weight by the fix ``z`` (mGal) taken at NS position ``x_ns (2,)`` km, estimate, resample (if
    ``resampling``, a Python bool), propagate to the next fix."""
    k_res, k_prop = jax.random.split(key)
    x = state.particles
    g = map_lookup(model.values, model.origin, model.spacing, x_ns - position_error(x))
    s = state.c_var + model.sigma_v**2  # predictive variance of the innovation (shared)
    r = z - g - state.c_mean
    q = -0.5 * r * r / s
    w = state.weights * jnp.exp(q - jax.lax.stop_gradient(jnp.max(q)))  # one exponent per particle
    w = w / jnp.sum(w)
    gain = state.c_var / s
    c_mean = state.c_mean + gain * r
    c_var = (1.0 - gain) * state.c_var
    d = position_error(x)
    mean = w @ d
    e = d - mean
    est = PFEstimate(mean, (e.T * w) @ e, 1.0 / jnp.sum(w * w))
    if resampling:
        idx = systematic_resample(k_res, w)
        x, c_mean = x[idx], c_mean[idx]
        w = jnp.full_like(w, 1.0 / x.shape[0])
    return PFState(propagate(model, k_prop, x), c_mean, c_var, w), est


def simulate_run(model: MapPFModel, key: jax.Array, track: jax.Array) -> tuple[jax.Array, jax.Array, jax.Array]:
    """One truth realisation along the true ``track (T, 2)`` km: ``(x_ns (T, 2), z (T,), error (T, 2))``
    with the true NS error drawn from the filter's own prior and dynamics, ``c ~ N(0, σ_c²)``."""
    k0, kc, kv, kw = jax.random.split(key, 4)
    xi0 = sample_prior(model, k0, 1)

    def step(xi, k):
        return propagate(model, k, xi), position_error(xi[0])

    _, err = jax.lax.scan(step, xi0, jax.random.split(kw, track.shape[0]))
    c = model.sigma_c * jax.random.normal(kc)
    z = map_lookup(model.values, model.origin, model.spacing, track) + c
    z = z + model.sigma_v * jax.random.normal(kv, (track.shape[0],))
    return track + err, z, err


def run_filter(
    model: MapPFModel, key: jax.Array, z: jax.Array, x_ns: jax.Array, n_particles: int, resampling: bool
) -> PFEstimate:
    """Scanned filter over ``z (T,)`` and ``x_ns (T, 2)``: estimates after each fix (leading axis T)."""
    k0, k1 = jax.random.split(key)
    state = pf_init(model, k0, n_particles)

    def step(s, inp):
        k, zi, xi = inp
        return pf_step(model, k, s, zi, xi, resampling)

    _, est = jax.lax.scan(step, state, (jax.random.split(k1, z.shape[0]), z, x_ns))
    return est


def monte_carlo(
    model: MapPFModel, key: jax.Array, track: Any, n_runs: int, n_particles: int, resampling: bool
) -> tuple[jax.Array, PFEstimate]:
    """``n_runs`` independent runs (truth + filter), vmapped: ``(true error (R, T, 2), estimates)``.
    Jit it with ``n_runs``, ``n_particles`` and ``resampling`` static."""
    check_positive_int("n_runs", n_runs)
    track = jnp.asarray(track, dtype=float)
    if track.ndim != 2 or track.shape[1] != 2:
        raise ValueError(f"track: expected shape (T, 2), got {tuple(track.shape)}")

    def one(k):
        ks, kf = jax.random.split(k)
        x_ns, z, err = simulate_run(model, ks, track)
        return err, run_filter(model, kf, z, x_ns, n_particles, resampling)

    return jax.vmap(one)(jax.random.split(key, n_runs))
