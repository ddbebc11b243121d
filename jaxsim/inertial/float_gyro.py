"""Float-gyro temperature drift: a random constant plus a temperature-driven first-order Markov process,
and three identifications of its correlation rate ``α`` and temperature coefficient ``β`` (seed 004
part 3, #23, spec §2.2).

Continuous model (spec §2.2, reconstructed; the paper's equation is garbled)::

    ε(t) = ε₀ + ε̃(t),      dε̃/dt = −α ε̃ + β u(t) + √(2ασ²) w(t),      ε̃(0) ~ N(0, σ²)

with ``u = T(t)`` (the temperature, ``variant="temperature"``) or ``u = dT/dt`` (``variant="rate"``) —
the surviving characters fit both.  Measurements ``y_k = ε₀ + ε̃_k + v_k``, ``v_k ~ N(0, r²)``.
Exact discretisation with sample time ``Δ`` and the input held over the interval (ZOH)::

    φ = e^{−αΔ},   ε̃_{k+1} = φ ε̃_k + β (1 − φ)/α · u_k + w_k,   var w_k = σ² (1 − φ²)

Units: ``α`` in s⁻¹, ``β`` in drift unit/(s·°C) (``temperature``) or drift unit/°C (``rate``), ``σ``,
``σ₀`` and ``r`` in drift units (d.u.), ``Δ`` in s.

Identifications of ``θ = (α, β)``:

* :func:`bank_log_likelihoods` — the Bayesian bank: one Kalman filter per grid hypothesis (``vmap``),
  whose total log-likelihoods give the grid posterior (:func:`grid_posterior_mean`);
* :func:`augmented_ekf_model` — the EKF with the state augmented by ``α`` and ``β`` (random constants);
* :func:`ml_estimate` — maximum likelihood by damped Newton steps on the exact Kalman log-likelihood
  (``jax.grad`` through the scanned filter; the Hessian by central differences of that gradient).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.validation import check_positive_scalar
from jaxsim.estimation.lgssm import LinearGaussianSSM, kalman_filter
from jaxsim.estimation.nonlinear import NonlinearSSM

VARIANTS = ("temperature", "rate")
ALPHA_TRUE = 0.00055  # s⁻¹, spec §2.2 Table 1
BETA_TRUE = -0.001  # spec §2.2 Table 1 (units garbled in the paper)
BETA_SCALE = 1e-3  # ML parametrisation θ = (ln α, β / BETA_SCALE)


def _check_concrete(**kw: Any) -> None:
    for name, v in kw.items():
        if not isinstance(v, jax.core.Tracer):
            check_positive_scalar(name, v)


def warmup_temperature(t: Any, delta_t: float = 10.0, tau: float = 2000.0) -> jax.Array:
    """Temperature rise above the start ``ΔT (1 − e^{−t/τ})`` (°C; ``t`` in s) — an assumed warm-up."""
    _check_concrete(tau=tau)
    return delta_t * (1.0 - jnp.exp(-jnp.asarray(t) / tau))


def warmup_rate(t: Any, delta_t: float = 10.0, tau: float = 2000.0) -> jax.Array:
    """``dT/dt = ΔT/τ e^{−t/τ}`` (°C/s) of :func:`warmup_temperature`."""
    _check_concrete(tau=tau)
    return delta_t / tau * jnp.exp(-jnp.asarray(t) / tau)


def transition_terms(alpha: Any, beta: Any, dt: float, sigma: Any) -> tuple[jax.Array, jax.Array, jax.Array]:
    """``(φ, b, q)``: ``φ = e^{−αΔ}``, input gain ``b = β(1 − φ)/α`` and Markov increment variance
    ``q = σ²(1 − φ²)`` of the exact discretisation (differentiable in ``α``, ``β``, ``σ``)."""
    phi = jnp.exp(-alpha * dt)
    return phi, beta * (-jnp.expm1(-alpha * dt)) / alpha, sigma**2 * (-jnp.expm1(-2 * alpha * dt))


def drift_model(
    alpha: Any, beta: Any, dt: float = 10.0, sigma: Any = 1.0, sigma0: Any = 3.0, r: Any = 0.3
) -> LinearGaussianSSM:
    """The drift as a :class:`~jaxsim.estimation.lgssm.LinearGaussianSSM`: state ``[ε₀, ε̃]``, input
    ``u (1,)`` (``T`` or ``dT/dt``), output ``y = ε₀ + ε̃``; ``m0 = 0``, ``P0 = diag(σ₀², σ²)``.
    Traceable in every argument but ``dt`` (concrete non-positive ``alpha``/``dt``/``sigma``/``r`` → ValueError)."""
    _check_concrete(alpha=alpha, dt=dt, sigma=sigma, r=r)
    phi, b, q = transition_terms(alpha, beta, dt, sigma)
    dtype = jnp.result_type(float)
    z = jnp.zeros((), dtype)
    F = jnp.array([[1.0, 0.0], [0.0, 0.0]], dtype) + jnp.array([[0.0, 0.0], [0.0, 1.0]], dtype) * phi
    Q = jnp.stack([jnp.stack([z, z]), jnp.stack([z, q + z])])
    B = jnp.stack([z, b + z])[:, None]
    H = jnp.array([[1.0, 1.0]], dtype)
    R = jnp.reshape(jnp.asarray(r, dtype) ** 2, (1, 1))
    P0 = jnp.diag(jnp.stack([jnp.asarray(sigma0, dtype) ** 2, jnp.asarray(sigma, dtype) ** 2]))
    return LinearGaussianSSM(F, Q, H, R, jnp.zeros(2, dtype), P0, B)


def log_likelihood(alpha: Any, beta: Any, y: Any, u: Any, **model_kw: Any) -> jax.Array:
    """Exact Kalman log-likelihood ``log p(y | α, β)`` of ``y (T, 1)`` with inputs ``u (T, 1)``."""
    return kalman_filter(drift_model(alpha, beta, **model_kw), y, u).log_likelihood


def bank_log_likelihoods(alphas: Any, betas: Any, y: Any, u: Any, **model_kw: Any) -> jax.Array:
    """Total log-likelihoods ``(M,)`` of a bank of Kalman filters, one per hypothesis ``(αᵢ, βᵢ)``
    (``alphas``, ``betas`` of shape ``(M,)``; ``vmap`` over the bank)."""
    return jax.vmap(lambda a, b: log_likelihood(a, b, y, u, **model_kw))(jnp.asarray(alphas), jnp.asarray(betas))


class GridPosterior(NamedTuple):
    """Posterior over a grid: ``weights (M,)``; posterior means and standard deviations of α and β."""

    weights: jax.Array
    alpha: jax.Array
    beta: jax.Array
    alpha_std: jax.Array
    beta_std: jax.Array


def grid_posterior_mean(alphas: Any, betas: Any, log_liks: Any, log_prior: Any = None) -> GridPosterior:
    """Bayes posterior over grid hypotheses from their log-likelihoods (uniform prior by default)."""
    lj = jnp.asarray(log_liks) + (0.0 if log_prior is None else jnp.asarray(log_prior))
    w = jnp.exp(lj - jax.scipy.special.logsumexp(lj))
    a, b = jnp.asarray(alphas), jnp.asarray(betas)
    ma, mb = w @ a, w @ b
    return GridPosterior(
        w, ma, mb, jnp.sqrt(jnp.maximum(w @ (a - ma) ** 2, 0.0)), jnp.sqrt(jnp.maximum(w @ (b - mb) ** 2, 0.0))
    )


def augmented_ekf_model(
    dt: float = 10.0,
    sigma: float = 1.0,
    sigma0: float = 3.0,
    r: float = 0.3,
    alpha0: float = 0.0004,
    beta0: float = -0.0008,
    alpha_std: float = 0.0002,
    beta_std: float = 0.0005,
) -> NonlinearSSM:
    """EKF model with state ``[ε₀, ε̃, α, β]`` (α, β random constants, prior ``N(α₀, σ_α²)``,
    ``N(β₀, σ_β²)``); input ``u (1,)``.  The Markov increment variance is taken at the prior ``α₀``
    (the EKF's process noise cannot depend on its state) — one source of its bias."""
    _check_concrete(dt=dt, sigma=sigma, sigma0=sigma0, r=r, alpha0=alpha0, alpha_std=alpha_std, beta_std=beta_std)
    q = sigma**2 * -np.expm1(-2 * alpha0 * dt)

    def f(params, x, u):
        phi, b, _ = transition_terms(x[2], x[3], dt, 0.0)
        return jnp.stack([x[0], phi * x[1] + b * u[0], x[2], x[3]])

    def h(params, x):
        return x[:1] + x[1:2]

    return NonlinearSSM(
        None,
        jnp.diag(jnp.array([0.0, q, 0.0, 0.0])),
        jnp.array([[r**2]]),
        jnp.array([0.0, 0.0, alpha0, beta0]),
        jnp.diag(jnp.array([sigma0**2, sigma**2, alpha_std**2, beta_std**2])),
        f,
        h,
    )


class MLEstimate(NamedTuple):
    """``alpha``, ``beta`` at the last iterate, ``log_likelihood`` there, ``grad`` of the log-likelihood
    in ``θ = (ln α, β/BETA_SCALE)`` and its norm ``grad_norm``, and ``alpha_std``, ``beta_std`` from the
    inverse observed information (the negative Hessian)."""

    alpha: jax.Array
    beta: jax.Array
    log_likelihood: jax.Array
    grad: jax.Array
    grad_norm: jax.Array
    alpha_std: jax.Array
    beta_std: jax.Array


def ml_estimate(
    y: Any,
    u: Any,
    alpha0: Any,
    beta0: Any,
    iterations: Any = 25,
    max_step: float = 0.5,
    fd_step: float = 1e-4,
    **model_kw: Any,
) -> MLEstimate:
    """Maximum-likelihood ``(α, β)`` by damped Newton steps on the Kalman log-likelihood in
    ``θ = (ln α, β/BETA_SCALE)``.  The gradient is ``jax.grad`` through the scanned filter; the Hessian is
    the central difference of that gradient (step ``fd_step``; one vmapped gradient at five points per
    iteration — a nested ``jax.hessian`` of the filter compiles several times slower for the same answer).
    Its eigenvalues are clipped so the step ascends, and the step is limited to ``max_step`` (θ units).
    ``iterations`` may be traced (one compilation for any count; ``0`` returns the start)."""

    def ll(theta):
        return log_likelihood(jnp.exp(theta[0]), theta[1] * BETA_SCALE, y, u, **model_kw)

    value_grads = jax.vmap(jax.value_and_grad(ll))
    offsets = jnp.concatenate([jnp.zeros((1, 2)), fd_step * jnp.eye(2), -fd_step * jnp.eye(2)])

    def body(i, carry):
        # the filter's gradient is traced once: the last pass (i = iterations) only evaluates at the final θ
        theta = carry[0]
        v, g = value_grads(theta + offsets)
        hm = (g[1:3] - g[3:5]).T / (2 * fd_step)
        hm = 0.5 * (hm + hm.T)
        lam, vec = jnp.linalg.eigh(-hm)
        lam = jnp.maximum(lam, 1e-3 * jnp.max(jnp.abs(lam)) + 1e-12)
        step = vec @ ((vec.T @ g[0]) / lam)
        step = step * jnp.minimum(1.0, max_step / (jnp.linalg.norm(step) + 1e-300))
        return jnp.where(i < iterations, theta + step, theta), v[0], g[0], hm

    theta0 = jnp.stack([jnp.log(jnp.asarray(alpha0, float)), jnp.asarray(beta0, float) / BETA_SCALE])
    init = (theta0, jnp.zeros(()), jnp.zeros(2), jnp.zeros((2, 2)))
    theta, value, g, hm = jax.lax.fori_loop(0, iterations + 1, body, init)
    cov = jnp.linalg.inv(-hm)
    alpha = jnp.exp(theta[0])
    return MLEstimate(
        alpha,
        theta[1] * BETA_SCALE,
        value,
        g,
        jnp.linalg.norm(g),
        alpha * jnp.sqrt(jnp.abs(cov[0, 0])),
        BETA_SCALE * jnp.sqrt(jnp.abs(cov[1, 1])),
    )
