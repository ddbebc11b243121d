"""Prediction of GNSS differential corrections (DC) with constraints (seed 004 part 3, #30, Zaitsev;
spec ``seed004_part3.md`` §2.11).

The last ``m + 1`` corrections ``d_k = g(t_k) + v_k`` (oldest ``t_m``, latest ``t_0``, step ``Δt``) are
fitted by ``g(t) = c·φ(t)``, ``φ(t) = b0 + b1 s + b2 s²`` with ``s = (t − t_m)/T``, ``T = (m + n)Δt``, and
``g`` is predicted ``n`` steps after ``t_0`` (at ``s = 1``).  The constrained fits keep ``|φ| ≤ 1`` and
``|dφ/ds| ≤ ψ`` on a grid of ``s ∈ [0, 1]`` (the paper's constraints (4), reconstructed); ``c`` (m) and
``ψ`` are tuning parameters.  Predictors (the paper's names):

* ``quadratic`` (КП) and ``quadratic_constrained`` (КПО): ``c·φ(1)``;
* ``linear`` (ЛП) and ``linear_constrained`` (ЛПО): ``g(t_0) + ġ(t_0)(t_n − t_0)`` from the fit;
* ``hold`` (ФП): the last correction ``d_0``.

The constrained least squares is a 3-variable QP solved by a log-barrier Newton method with a fixed
schedule (:func:`constrained_fit`, unrolled in ``lax.scan``): pure, vmappable and differentiable in the
data, ``c`` and ``ψ`` (the barrier smooths the active set), so ``(c, ψ)`` can be tuned by gradient.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

__all__ = ["PREDICTORS", "basis", "constrained_fit", "predict", "unconstrained_fit"]

PREDICTORS = ("quadratic", "linear", "hold", "quadratic_constrained", "linear_constrained")

GRID = 21
"""Points of ``s ∈ [0, 1]`` where the constraints are imposed."""


def basis(s: jax.Array) -> jax.Array:
    """``[1, s, s²]`` rows ``(..., 3)``."""
    s = jnp.asarray(s)
    return jnp.stack([jnp.ones_like(s), s, s * s], axis=-1)


def basis_slope(s: jax.Array) -> jax.Array:
    """``d/ds [1, s, s²] = [0, 1, 2s]`` rows ``(..., 3)``."""
    s = jnp.asarray(s)
    return jnp.stack([jnp.zeros_like(s), jnp.ones_like(s), 2 * s], axis=-1)


def sample_times(m: int, n: int) -> jax.Array:
    """``s`` of the ``m + 1`` samples, oldest first: ``k/(m + n)``, ``k = 0..m``."""
    return jnp.arange(m + 1) / (m + n)


def unconstrained_fit(d: jax.Array, n: int) -> jax.Array:
    """Least-squares ``c·b`` ``(3,)`` (m) of ``d (m + 1,)`` (oldest first)."""
    a = basis(sample_times(d.shape[0] - 1, n))
    return jnp.linalg.lstsq(a, d)[0]


def constrained_fit(
    d: jax.Array, n: int, c: jax.Array, psi: jax.Array, iters: int = 60, mu0: float = 1.0, shrink: float = 0.7
) -> jax.Array:
    """``b (3,)`` minimising ``Σ (d_k − c·φ(t_k))²/(m + 1)`` subject to ``|φ| ≤ 1``, ``|dφ/ds| ≤ ψ`` on
    :data:`GRID` points, by Newton steps on the log-barrier objective with ``μ`` shrinking from ``mu0``
    by ``shrink`` per step (a feasible start ``b = 0``, step halving keeps it strictly feasible).
    Returns ``b``; the fitted correction is ``c·B(s) b``."""
    m = d.shape[0] - 1
    a = c * basis(sample_times(m, n))
    s = jnp.linspace(0.0, 1.0, GRID)
    g = jnp.concatenate([basis(s), -basis(s), basis_slope(s), -basis_slope(s)])  # G b ≤ h
    h = jnp.concatenate([jnp.ones(2 * GRID), jnp.full(2 * GRID, 1.0) * psi])

    n_data, n_con = a.shape[0], g.shape[0]
    ata = 2.0 / n_data * a.T @ a

    def step(b, mu):
        # gradient and Hessian of mean((d − A b)²) − μ·mean(log(h − G b)), written out
        slack = h - g @ b
        grad = -2.0 / n_data * a.T @ (d - a @ b) + mu / n_con * g.T @ (1.0 / slack)
        hess = ata + mu / n_con * (g.T * slack**-2) @ g
        delta = -jnp.linalg.solve(hess + 1e-12 * jnp.eye(3), grad)
        # largest step in (0, 1] that keeps every slack positive (fraction to the boundary 0.99)
        rate = g @ delta
        limit = jnp.min(jnp.where(rate > 0, slack / jnp.where(rate > 0, rate, 1.0), jnp.inf))
        t = jnp.minimum(1.0, 0.99 * limit)
        return b + t * delta, None

    mus = mu0 * shrink ** jnp.arange(iters)
    return jax.lax.scan(step, jnp.zeros(3, d.dtype), mus)[0]


def predict(d: jax.Array, n: int, c: jax.Array, psi: jax.Array, method: str) -> jax.Array:
    """The correction ``n`` steps after the latest of ``d (m + 1,)`` (oldest first), metres."""
    if method not in PREDICTORS:
        raise ValueError(f"method: expected one of {PREDICTORS}, got {method!r}")
    if method == "hold":
        return d[-1]
    m = d.shape[0] - 1
    if method.endswith("constrained"):
        coef = c * constrained_fit(d, n, c, psi)
    else:
        coef = unconstrained_fit(d, n)
    if method.startswith("quadratic"):
        return basis(1.0) @ coef
    s0 = m / (m + n)  # latest sample
    return basis(s0) @ coef + (basis_slope(s0) @ coef) * (1.0 - s0)
