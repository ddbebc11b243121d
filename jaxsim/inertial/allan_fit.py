"""Fit of the five-term Allan-variance model (seed 004 part 3 §2.1, eq. 4) to a measured Allan variance.

Model, linear in the squared coefficients ``p = (R², K², B², N², Q²)``::

    σ²(τ) = R²τ²/2 + K²(τ/3 + c·dt²/(6τ)) + B²·2 ln2/π + N²/τ + 3Q²/τ²

``c = 1`` adds seed 004's sampling term of a discrete Wiener sequence (the rate random walk sampled
every ``dt`` also looks like white noise of intensity ``K²dt²/6``); ``c = 0`` is the textbook model.

Two fits of the same data ``(τ_j, σ̂²_j)`` with ``ν_j`` degrees of freedom (``σ̂²_j`` is about
``σ²_j·χ²_ν/ν``, so ``Var σ̂² ≈ 2σ⁴/ν`` and ``Var log σ̂² ≈ 2/ν``):

Either fit may be restricted to some of the terms (``terms="KN"``: the others are held at zero).

* :func:`fit_wls` — iteratively reweighted linear least squares in ``p`` (weights ``ν/(2 σ²_model²)``);
  squares may come out negative when a term is not resolved by the data;
* :func:`fit_gradient` — Adam on ``z = log p`` for the log-residual loss
  ``½ Σ_j (ν_j/2)(log σ²_model(τ_j) − log σ̂²_j)²`` (positive by construction), with the Gauss–Newton
  covariance of ``z`` (inverse Hessian of the loss) as its uncertainty.  It ignores the correlation
  between overlapping estimates at neighbouring τ, so it is optimistic; compare it with a
  Monte-Carlo spread.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import optax

from jaxsim.core.validation import check_positive, check_positive_int, check_shape

__all__ = ["TERMS", "AllanFit", "avar_dof", "avar_model", "design_matrix", "fit_gradient", "fit_wls"]

TERMS = ("R", "K", "B", "N", "Q")
_FLICKER = 2.0 * math.log(2.0) / math.pi


class AllanFit(NamedTuple):
    """``p (5,)`` squared coefficients ``R², K², B², N², Q²``; ``coeffs (5,)`` = ``sign(p)·√|p|``;
    ``cov_log_p (5, 5)`` covariance of ``log p`` (gradient fit; NaN for the linear fit);
    ``loss`` the final weighted loss."""

    p: jax.Array
    coeffs: jax.Array
    cov_log_p: jax.Array
    loss: jax.Array


def design_matrix(tau: Any, dt: float, sampling_correction: bool = True) -> jax.Array:
    """``(T, 5)``: column ``i`` is the Allan variance of unit ``p_i`` at each ``τ`` (s)."""
    tau = jnp.asarray(tau, float)
    c = 1.0 if sampling_correction else 0.0
    return jnp.stack(
        [
            tau**2 / 2.0,
            tau / 3.0 + c * dt**2 / (6.0 * tau),
            jnp.full_like(tau, _FLICKER),
            1.0 / tau,
            3.0 / tau**2,
        ],
        axis=-1,
    )


def avar_model(tau: Any, coeffs: Any, dt: float, sampling_correction: bool = True) -> jax.Array:
    """Seed 004 eq. (4) at ``τ`` for ``coeffs = (R, K, B, N, Q)`` (not squared)."""
    coeffs = jnp.asarray(coeffs, float)
    return design_matrix(tau, dt, sampling_correction) @ coeffs**2


def avar_dof(n_samples: int, m: Any) -> jax.Array:
    """A conservative number of degrees of freedom of an Allan variance of ``n_samples`` samples at
    cluster sizes ``m``: the count of non-overlapping cluster differences ``⌊n/m⌋ − 1`` (≥ 1)."""
    n_samples = check_positive_int("n_samples", n_samples)
    return jnp.maximum(n_samples // jnp.asarray(m) - 1, 1).astype(float)


def _check(tau: Any, avar: Any, dof: Any) -> tuple[jax.Array, jax.Array, jax.Array]:
    tau, avar, dof = (jnp.asarray(a, float) for a in (tau, avar, dof))
    check_shape("tau", tau, (None,))
    check_shape("avar", avar, tau.shape)
    check_shape("dof", dof, tau.shape)
    check_positive("tau", tau)
    check_positive("avar", avar)
    check_positive("dof", dof)
    return tau, avar, dof


def _coeffs(p: jax.Array) -> jax.Array:
    return jnp.sign(p) * jnp.sqrt(jnp.abs(p))


def _columns(terms: str) -> list[int]:
    if not isinstance(terms, str) or not terms or any(t not in TERMS for t in terms) or len(set(terms)) < len(terms):
        raise ValueError(f"terms: expected distinct letters of {''.join(TERMS)!r}, got {terms!r}")
    return sorted(TERMS.index(t) for t in terms)


def _embed(values: jax.Array, cols: list[int], fill: float) -> jax.Array:
    return jnp.full((5,) + values.shape[1:], fill, values.dtype).at[jnp.asarray(cols)].set(values)


def fit_wls(
    tau: Any,
    avar: Any,
    dof: Any,
    dt: float,
    *,
    terms: str = "RKBNQ",
    sampling_correction: bool = True,
    iterations: int = 4,
) -> AllanFit:
    """Weighted linear least squares of ``p`` (see the module docstring); the weights start from the
    data (``ν/(2σ̂⁴)``) and are recomputed ``iterations − 1`` times from the model (floored at 1 %
    of the data to stay positive)."""
    tau, avar, dof = _check(tau, avar, dof)
    check_positive("dt", dt)
    iterations = check_positive_int("iterations", iterations)
    cols = _columns(terms)
    a = design_matrix(tau, dt, sampling_correction)[:, cols]

    def solve(ref):
        w = jnp.sqrt(dof / 2.0) / ref
        p, *_ = jnp.linalg.lstsq(a * w[:, None], avar * w)
        return p

    p = solve(avar)
    for _ in range(iterations - 1):
        p = solve(jnp.maximum(a @ p, 0.01 * avar))
    r = (a @ p - avar) / jnp.maximum(a @ p, 0.01 * avar)
    loss = 0.5 * jnp.sum(dof / 2.0 * r**2)
    p = _embed(p, cols, 0.0)
    return AllanFit(p, _coeffs(p), jnp.full((5, 5), jnp.nan), loss)


def _log_loss(z: jax.Array, a: jax.Array, avar: jax.Array, dof: jax.Array) -> jax.Array:
    return 0.5 * jnp.sum(dof / 2.0 * (jnp.log(a @ jnp.exp(z)) - jnp.log(avar)) ** 2)


def fit_gradient(
    tau: Any,
    avar: Any,
    dof: Any,
    dt: float,
    *,
    init: Any | None = None,
    terms: str = "RKBNQ",
    sampling_correction: bool = True,
    steps: int = 3000,
    learning_rate: float = 0.05,
) -> AllanFit:
    """Adam (``steps``, learning rate decaying ×0.01 over the run) on ``z = log p`` for the
    log-residual loss of the module docstring, from ``init`` (squared coefficients, ``(5,)``; entries
    of terms left out are ignored; default: a tenth of the largest value each term alone could take
    under the data).  Returns ``p``, the coefficients and ``cov_log_p``, the inverse Hessian of the
    loss at the end (NaN rows and columns for terms left out).  Pure JAX apart from the shape checks:
    jit/vmap over data sets."""
    tau, avar, dof = _check(tau, avar, dof)
    check_positive("dt", dt)
    steps = check_positive_int("steps", steps)
    cols = _columns(terms)
    a = design_matrix(tau, dt, sampling_correction)[:, cols]
    if init is None:
        # each term alone explains at most the smallest ratio data/column: start at a tenth of that
        p0 = 0.1 * jnp.min(avar[:, None] / a, axis=0)
    else:
        p0 = jnp.asarray(init, float)
        check_shape("init", p0, (5,))
        p0 = p0[jnp.asarray(cols)]
        check_positive("init", p0)
    opt = optax.adam(optax.exponential_decay(learning_rate, steps, 0.01))
    grad = jax.grad(_log_loss)

    def step(carry, _):
        z, state = carry
        updates, state = opt.update(grad(z, a, avar, dof), state)
        return (optax.apply_updates(z, updates), state), None

    z0 = jnp.log(p0)
    (z, _), _ = jax.lax.scan(step, (z0, opt.init(z0)), None, length=steps)
    hess = jax.hessian(_log_loss)(z, a, avar, dof)
    cov = jnp.full((5, 5), jnp.nan).at[jnp.ix_(jnp.asarray(cols), jnp.asarray(cols))].set(jnp.linalg.inv(hess))
    p = _embed(jnp.exp(z), cols, 0.0)
    return AllanFit(p, jnp.sqrt(p), cov, _log_loss(z, a, avar, dof))
