"""Controllability gramians of a stable LTI system ``ẋ = A x + B u``.

``W = ∫₀^∞ e^{At} B Bᵀ e^{Aᵀt} dt`` two ways:

* :func:`controllability_gramian` — the Lyapunov equation ``A W + W Aᵀ + B Bᵀ = 0`` solved by
  :func:`jaxsim.control.lyapunov.solve_continuous_lyapunov` (differentiable implicitly);
* :func:`impulse_gramian` — the *empirical* gramian: the impulse response of every input channel
  (``x(0⁺) = B e_i``, ``u = 0`` after) integrated with fixed RK4 steps, ``W ≈ Σ_i ∫₀^T x_i x_iᵀ dt``
  by Simpson's rule.  It converges to ``W`` as ``T → ∞`` and the step → 0 (truncation error
  ``‖e^{AT}‖²``), so it checks the Lyapunov route with no shared code.

Units: if ``x`` is in X, ``u`` in U and time in s, ``W`` is in X²·s/U².
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.control.lyapunov import solve_continuous_lyapunov
from jaxsim.core.integrators import RK4, integrate
from jaxsim.core.validation import check_finite, check_square, is_concrete


def _check(a: jax.Array, b: jax.Array) -> tuple[jax.Array, jax.Array]:
    a = jnp.asarray(a, dtype=jnp.result_type(a, float))
    b = jnp.asarray(b, dtype=a.dtype)
    check_square("a", a)
    if b.ndim != 2 or b.shape[0] != a.shape[0]:
        raise ValueError(f"b: expected shape ({a.shape[0]}, m), got {tuple(b.shape)}")
    check_finite("a", a)
    check_finite("b", b)
    if is_concrete(a):
        eig = np.linalg.eigvals(np.asarray(a))
        if np.any(eig.real >= 0):
            raise ValueError(f"a: the gramian over an infinite horizon needs a Hurwitz matrix; eigenvalues {eig}")
    return a, b


def controllability_gramian(a: jax.Array, b: jax.Array) -> jax.Array:
    """``W`` ``(n, n)`` of ``a`` ``(n, n)`` (Hurwitz) and ``b`` ``(n, m)``: ``A W + W Aᵀ = −B Bᵀ``."""
    a, b = _check(a, b)
    return solve_continuous_lyapunov(a, -b @ b.T)


def impulse_gramian(a: jax.Array, b: jax.Array, t_final: float, n_steps: int) -> jax.Array:
    """Empirical gramian ``Σ_i ∫₀^T x_i(t) x_i(t)ᵀ dt`` from the simulated impulse responses.

    Args:
        a: ``(n, n)`` Hurwitz matrix; b: ``(n, m)``.
        t_final: horizon ``T`` (time unit of ``a``); choose ``T`` ≫ the slowest time constant.
        n_steps: number of RK4 steps, even (Simpson's rule).

    Returns:
        ``(n, n)`` symmetric positive semi-definite matrix.
    """
    a, b = _check(a, b)
    if int(n_steps) < 2 or int(n_steps) % 2:
        raise ValueError(f"n_steps: must be an even integer ≥ 2 (Simpson's rule), got {n_steps!r}")
    if not (np.isfinite(float(t_final)) and float(t_final) > 0):
        raise ValueError(f"t_final: must be positive and finite, got {t_final!r}")
    dt = float(t_final) / int(n_steps)

    def one(b_i: jax.Array) -> jax.Array:
        _, xs = integrate(lambda t, x: a @ x, b_i, 0.0, dt, int(n_steps), RK4)
        return xs  # (n_steps + 1, n)

    xs = jax.vmap(one, in_axes=1)(b)  # (m, N+1, n)
    w = jnp.ones(int(n_steps) + 1).at[1:-1:2].set(4.0).at[2:-1:2].set(2.0) * (dt / 3.0)
    return jnp.einsum("k,ikp,ikq->pq", w, xs, xs)
