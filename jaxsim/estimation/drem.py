"""Dynamic regressor extension and mixing (DREM; Aranovskiy, Bobtsov, Ortega, Pyrkin 2017): from one
linear regression ``z(t) = φ(t)ᵀθ`` with ``θ ∈ Rⁿ`` constant, ``n`` filtered copies ``z_k = H_k[z]``,
``ψ_k = H_k[φ]`` (stable LTI operators, zero initial state, so the copies hold exactly) are stacked into
``Z = M θ`` and multiplied by ``adj M``: ``Y = adj(M) Z = Δ θ`` with ``Δ = det M`` — ``n`` *scalar*
regressions sharing one regressor ``Δ``.  The gradient estimator ``θ̂̇_j = γ Δ (Y_j − Δ θ̂_j)`` then gives
``θ̃̇_j = −γ Δ² θ̃_j``: each error decays monotonically, element by element, exponentially if ``Δ`` is
persistently exciting and asymptotically if ``Δ ∉ L²``.

:func:`estimator_step` takes that law implicitly over a step (``θ̂ ← (θ̂ + dt γ Δ Y)/(1 + dt γ Δ²)``):
the element-wise monotonicity holds exactly for any ``dt`` and any ``γ`` (a very large ``γ`` is fine,
which matters because ``Δ`` is a product of ``n`` regressor entries and may be tiny).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np


def adjugate(m: jax.Array) -> jax.Array:
    """``adj M`` of a square ``m (n, n)`` by cofactors (well defined for a singular ``M``, unlike ``det·M⁻¹``)."""
    n = m.shape[-1]
    if m.shape[-2:] != (n, n):
        raise ValueError(f"m: expected a square matrix, got shape {m.shape}")
    if n == 1:
        return jnp.ones_like(m)
    idx = np.array([[k for k in range(n) if k != i] for i in range(n)])  # (n, n−1): all but i
    minors = m[idx[:, None, :, None], idx[None, :, None, :]]  # (i, j, n−1, n−1): row i, column j removed
    signs = np.array([[(-1.0) ** (i + j) for j in range(n)] for i in range(n)])
    return (signs * jnp.linalg.det(minors)).T


def mix(m: jax.Array, z: jax.Array) -> tuple[jax.Array, jax.Array]:
    """``(Δ, Y)``: ``Δ = det M`` and ``Y = adj(M) Z`` for the extended regression ``Z (n,) = M (n, n) θ``."""
    return jnp.linalg.det(m), adjugate(m) @ z


def estimator_step(theta_hat: jax.Array, delta: jax.Array, y: jax.Array, gamma: jax.Array, dt: float) -> jax.Array:
    """One implicit step of ``θ̂̇ = γ Δ (Y − Δ θ̂)`` over ``dt``: ``(θ̂ + dt γ Δ Y)/(1 + dt γ Δ²)``."""
    return (theta_hat + dt * gamma * delta * y) / (1.0 + dt * gamma * delta * delta)


def lowpass_bank(alphas: jax.Array, dt: float) -> tuple[jax.Array, jax.Array]:
    """``(a, b) (N,)``: the filters ``α_k/(p + α_k)`` discretised exactly for an input held over ``dt``:
    ``s ← a s + b u`` with ``a = e^{−α dt}``, ``b = 1 − a``."""
    a = jnp.exp(-jnp.asarray(alphas) * dt)
    return a, 1.0 - a


__all__ = ["adjugate", "mix", "estimator_step", "lowpass_bank"]
