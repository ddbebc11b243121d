"""Bootstrap particle filter with systematic, stratified or multinomial resampling (or none).

Convention as the Kalman filters: the initial particles are the prior of ``x_0``; at each step the
weights are multiplied by ``p(y_t | x)``, the weighted estimate is recorded, the particles are
resampled when the effective sample size falls below ``ess_threshold · N`` (never with
``resampling=None``: sequential importance sampling, seed 004's "without resampling" variant), then
propagated by sampling the transition.  ``log_likelihood`` is the standard unbiased-in-``exp``
estimate ``Σ_t log Σ_i w_{t−1,i} p(y_t | x_{t,i})``.
"""

from __future__ import annotations

import functools
from typing import Any, Callable, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.pytree import pytree_dataclass, replace, static_field
from jaxsim.core.validation import check_covariance, check_positive_int, is_concrete
from jaxsim.estimation.gating import mahalanobis_squared
from jaxsim.estimation.kalman import LOG_2PI
from jaxsim.estimation.lgssm import LinearGaussianSSM, cholesky_psd, prepare_measurements, validate_model
from jaxsim.precision import to_common_float

RESAMPLING = ("systematic", "stratified", "multinomial", None)


@pytree_dataclass
class ParticleModel:
    """``sample_initial(params, key, n) -> (n, d)``; ``sample_transition(params, key, x (d,), u) -> (d,)``;
    ``log_likelihood(params, y, x (d,)) -> ()`` (static functions), with a ``params`` pytree."""

    params: Any
    sample_initial: Callable[[Any, jax.Array, int], jax.Array] = static_field()
    sample_transition: Callable[[Any, jax.Array, jax.Array, Any], jax.Array] = static_field()
    log_likelihood: Callable[[Any, jax.Array, jax.Array], jax.Array] = static_field()


class ParticleState(NamedTuple):
    """Particles ``(N, d)`` and normalised log-weights ``(N,)``."""

    particles: jax.Array
    log_weights: jax.Array


class ParticleResult(NamedTuple):
    """Weighted ``means (T, d)``, ``covs (T, d, d)`` after each update, ``ess (T,)`` before
    resampling, ``resampled (T,)``, per-step and total log-likelihood estimates, final ``state``."""

    means: jax.Array
    covs: jax.Array
    ess: jax.Array
    resampled: jax.Array
    log_likelihoods: jax.Array
    log_likelihood: jax.Array
    state: ParticleState


def _normalise(log_w: jax.Array) -> jax.Array:
    return log_w - jax.scipy.special.logsumexp(log_w)


def effective_sample_size(log_weights: jax.Array) -> jax.Array:
    """``1 / Σ wᵢ²`` of the normalised weights."""
    return jnp.exp(-jax.scipy.special.logsumexp(2.0 * _normalise(log_weights)))


def _inverse_cdf(weights: jax.Array, positions: jax.Array) -> jax.Array:
    cdf = jnp.cumsum(weights)
    cdf = cdf.at[-1].set(1.0)
    return jnp.minimum(jnp.searchsorted(cdf, positions, side="right"), weights.shape[0] - 1)


def systematic_resample(key: jax.Array, weights: jax.Array) -> jax.Array:
    """Indices ``(N,)`` from one uniform: positions ``(U + k)/N`` (each count is ⌊N wᵢ⌋ or ⌈N wᵢ⌉)."""
    n = weights.shape[0]
    pos = (jax.random.uniform(key, dtype=weights.dtype) + jnp.arange(n, dtype=weights.dtype)) / n
    return _inverse_cdf(weights, pos)


def stratified_resample(key: jax.Array, weights: jax.Array) -> jax.Array:
    """Indices ``(N,)`` from one uniform per stratum: positions ``(Uₖ + k)/N``."""
    n = weights.shape[0]
    pos = (jax.random.uniform(key, (n,), dtype=weights.dtype) + jnp.arange(n, dtype=weights.dtype)) / n
    return _inverse_cdf(weights, pos)


def multinomial_resample(key: jax.Array, weights: jax.Array) -> jax.Array:
    """Indices ``(N,)`` drawn independently with probabilities ``weights``."""
    n = weights.shape[0]
    return _inverse_cdf(weights, jnp.sort(jax.random.uniform(key, (n,), dtype=weights.dtype)))


_RESAMPLERS = {
    "systematic": systematic_resample,
    "stratified": stratified_resample,
    "multinomial": multinomial_resample,
}


def resample(key: jax.Array, log_weights: jax.Array, method: str = "systematic") -> jax.Array:
    """Ancestor indices ``(N,)`` by ``method`` (``"systematic"``, ``"stratified"``, ``"multinomial"``)."""
    if method not in _RESAMPLERS:
        raise ValueError(f"method: expected one of {tuple(_RESAMPLERS)}, got {method!r}")
    return _RESAMPLERS[method](key, jnp.exp(_normalise(log_weights)))


def pf_init(model: ParticleModel, key: jax.Array, n_particles: int) -> ParticleState:
    """Draw ``n_particles`` (a positive integer) from the prior with equal weights."""
    n_particles = check_positive_int("n_particles", n_particles)
    x = model.sample_initial(model.params, key, n_particles)
    return ParticleState(x, jnp.full((n_particles,), -jnp.log(n_particles), dtype=x.dtype))


def pf_step(
    model: ParticleModel,
    key: jax.Array,
    state: ParticleState,
    y: jax.Array,
    u: Any = None,
    *,
    available: jax.Array | bool = True,
    resampling: str | None = "systematic",
    ess_threshold: float = 0.5,
) -> tuple[ParticleState, tuple[jax.Array, jax.Array, jax.Array, jax.Array, jax.Array]]:
    """Weight by ``y`` (skipped where ``available`` is False), estimate, resample, propagate.

    Returns the propagated state and ``(mean, cov, ess, resampled, log_likelihood)`` of the update.
    """
    k_res, k_prop = jax.random.split(key)
    x = state.particles
    loglik = jax.vmap(lambda xi: model.log_likelihood(model.params, y, xi))(x)
    loglik = jnp.where(available, loglik, 0.0)
    joint = state.log_weights + loglik
    step_ll = jax.scipy.special.logsumexp(joint)
    log_w = joint - step_ll
    w = jnp.exp(log_w)
    mean = w @ x
    d = x - mean
    cov = (d.T * w) @ d
    ess = effective_sample_size(log_w)
    n = x.shape[0]
    if resampling is None:
        did = jnp.zeros((), bool)
    else:
        did = ess < ess_threshold * n
        idx = jnp.where(did, resample(k_res, log_w, resampling), jnp.arange(n))
        x = x[idx]
        log_w = jnp.where(did, jnp.full_like(log_w, -jnp.log(n)), log_w)
    keys = jax.random.split(k_prop, n)
    x = jax.vmap(lambda k, xi: model.sample_transition(model.params, k, xi, u))(keys, x)
    return ParticleState(x, log_w), (mean, cov, ess, did, step_ll)


def bootstrap_filter(
    model: ParticleModel,
    key: jax.Array,
    y: Any,
    u: Any = None,
    *,
    n_particles: int,
    resampling: str | None = "systematic",
    ess_threshold: float = 0.5,
    mask: Any = None,
    missing: str = "error",
) -> ParticleResult:
    """Scanned bootstrap particle filter over ``y (T, p)``; ``mask (T,)`` marks available steps.

    ``n_particles`` is a positive integer (a jit-static size).  ``y``, ``u`` and the float leaves of
    ``model.params`` are cast to one float dtype (:func:`jaxsim.precision.to_common_float`).
    """
    if resampling not in RESAMPLING:
        raise ValueError(f"resampling: expected one of {RESAMPLING}, got {resampling!r}")
    n_particles = check_positive_int("n_particles", n_particles)
    if is_concrete(ess_threshold) and not 0.0 < float(ess_threshold) <= 1.0:
        raise ValueError(f"ess_threshold: must lie in (0, 1], got {ess_threshold!r}")
    y = jnp.asarray(y)
    if y.ndim != 2:
        raise ValueError(f"y: expected shape (T, p), got {tuple(y.shape)}")
    (y, u), params = to_common_float((y, None if u is None else jnp.asarray(u)), model.params)
    model = replace(model, params=params)
    y, m = prepare_measurements(y, y.shape[1], None if mask is None else jnp.asarray(mask), missing)
    return _run_particle_filter(model, key, y, jnp.all(m, axis=1), u, n_particles, resampling, float(ess_threshold))


@functools.partial(jax.jit, static_argnames=("n_particles", "resampling", "ess_threshold"))
def _run_particle_filter(model, key, y, available, u, n_particles, resampling, ess_threshold) -> ParticleResult:
    k0, k1 = jax.random.split(key)
    state = pf_init(model, k0, int(n_particles))
    keys = jax.random.split(k1, y.shape[0])

    def step(s, inp):
        k, y_t, a_t, u_t = inp
        return pf_step(model, k, s, y_t, u_t, available=a_t, resampling=resampling, ess_threshold=ess_threshold)

    final, (means, covs, ess, did, ll) = jax.lax.scan(step, state, (keys, y, available, u))
    return ParticleResult(means, covs, ess, did, ll, jnp.sum(ll), final)


def _gaussian_initial(p, key, n):
    z = jax.random.normal(key, (n, p["m0"].shape[0]), dtype=p["m0"].dtype)
    return p["m0"] + z @ p["L0"].T


def _gaussian_transition(p, key, x, u):
    nxt = p["F"] @ x + p["LQ"] @ jax.random.normal(key, x.shape, dtype=x.dtype)
    if u is not None and "B" in p:
        nxt = nxt + p["B"] @ u
    return nxt


def _gaussian_loglik(p, y, x):
    r = y - p["H"] @ x
    return -0.5 * (mahalanobis_squared(r, p["R"]) + p["logdet_R"] + y.shape[0] * LOG_2PI)


def particle_model_from_lgssm(model: LinearGaussianSSM) -> ParticleModel:
    """The bootstrap-filter model of a time-invariant linear-Gaussian model (for checks against the KF).

    ``R`` must be positive definite (the particle weights are Gaussian densities in ``R``; a singular
    ``R`` makes them NaN); the model is validated and cast to one float dtype.  Under ``jit`` (a
    traced ``R``) this is not checked and a singular ``R`` gives NaN estimates.
    """
    if np.ndim(model.F) != 2 or np.ndim(model.Q) != 2 or np.ndim(model.H) != 2 or np.ndim(model.R) != 2:
        raise ValueError("model: time-varying matrices are not supported here")
    validate_model(model)
    check_covariance("R", model.R, definite=True, purpose="a particle filter's likelihood")
    (model,), _ = to_common_float((model,))
    params = {
        "m0": model.m0,
        "L0": cholesky_psd(model.P0),
        "F": model.F,
        "LQ": cholesky_psd(model.Q),
        "H": model.H,
        "R": model.R,
        "logdet_R": jnp.linalg.slogdet(model.R)[1],
    }
    if model.B is not None:
        params["B"] = model.B
    return ParticleModel(params, _gaussian_initial, _gaussian_transition, _gaussian_loglik)
