"""Path-following guidance with dynamic control allocation (seed 004 part 1 §B6, KIT).

* :func:`track` — a centreline made of straights and constant-radius arcs, sampled by arc length.
* :func:`natural_spline` / :func:`spline_eval` — a natural cubic spline ``p(s)`` through waypoints.
* :func:`project` — the vehicle's arc-length on the spline by Newton–Raphson in ``lax.fori_loop``.
* :func:`lookahead` — ``Δ(e_y) = (Δ_max − Δ_min)·exp(−K e_y²) + Δ_min`` (the paper's reconstructed law).
* :func:`allocation_rhs` — a Johansen-type dynamic allocation: primal–dual gradient flow on the
  (augmented) Lagrangian ``½uᵀWu + λᵀ(τ_d − Bu) + ½ρ‖τ_d − Bu‖²``; its equilibrium is the
  minimum-``W``-norm allocation (KKT), reached without a per-step optimisation.  Actuator-limit
  barrier terms of the paper are not modelled.
"""

from __future__ import annotations

from typing import Any, Sequence

import jax
import jax.numpy as jnp
import numpy as np


def track(segments: Sequence[tuple[float, float]], ds: float) -> dict[str, np.ndarray]:
    """Centreline of ``segments`` (``(length_m, turn_rad)``; ``turn = 0``: a straight of that length,
    else an arc of radius ``length_m`` turning by ``turn_rad``, + left), sampled every ≤ ``ds`` m
    exactly on the geometry, starting at the origin heading +X.  Returns ``s`` (arc length), ``xy``
    ``(n, 2)``, ``heading`` and ``segment`` (index of the segment each sample lies in)."""
    if ds <= 0:
        raise ValueError(f"ds must be positive, got {ds}")
    pos, hdg, s0 = np.zeros(2), 0.0, 0.0
    S, XY, H, G = [0.0], [pos.copy()], [0.0], [0]
    for k, (a, turn) in enumerate(segments):
        if a <= 0:
            raise ValueError(f"segments[{k}]: length/radius must be positive, got {a}")
        length = a if turn == 0 else a * abs(turn)
        n = max(1, int(np.ceil(length / ds)))
        sig = np.linspace(0.0, length, n + 1)[1:]
        if turn == 0:
            pts = pos + sig[:, None] * np.array([np.cos(hdg), np.sin(hdg)])
            hs = np.full(n, hdg)
        else:
            sgn = np.sign(turn)
            hs = hdg + sgn * sig / a
            c = pos + sgn * a * np.array([-np.sin(hdg), np.cos(hdg)])
            pts = c + sgn * a * np.stack([np.sin(hs), -np.cos(hs)], axis=1)
        S.extend(s0 + sig)
        XY.extend(pts)
        H.extend(hs)
        G.extend([k] * n)
        pos, hdg, s0 = pts[-1], hs[-1], s0 + length
    return {"s": np.array(S), "xy": np.array(XY), "heading": np.array(H), "segment": np.array(G)}


def natural_spline(s: jax.Array, y: jax.Array) -> jax.Array:
    """Coefficients ``(n−1, 4, d)`` (``a + b t + c t² + e t³`` with ``t = s − s_i``) of the natural cubic
    spline through ``(s_i, y_i)``; ``s`` ``(n,)`` strictly increasing, ``y`` ``(n, d)``."""
    s, y = jnp.asarray(s), jnp.asarray(y)
    if s.ndim != 1 or y.shape[0] != s.shape[0] or s.shape[0] < 3:
        raise ValueError(f"s must be (n,) with n >= 3 and y (n, d); got {s.shape}, {y.shape}")
    h = jnp.diff(s)
    n = s.shape[0]
    A = jnp.zeros((n, n)).at[0, 0].set(1.0).at[-1, -1].set(1.0)
    i = jnp.arange(1, n - 1)
    A = A.at[i, i - 1].set(h[:-1]).at[i, i].set(2 * (h[:-1] + h[1:])).at[i, i + 1].set(h[1:])
    dy = jnp.diff(y, axis=0) / h[:, None]
    rhs = jnp.zeros_like(y).at[1:-1].set(3 * (dy[1:] - dy[:-1]))
    c = jnp.linalg.solve(A, rhs)
    b = dy - h[:, None] * (2 * c[:-1] + c[1:]) / 3
    e = (c[1:] - c[:-1]) / (3 * h[:, None])
    return jnp.stack([y[:-1], b, c[:-1], e], axis=1)


def spline_eval(knots: jax.Array, coef: jax.Array, s: jax.Array) -> tuple[jax.Array, jax.Array, jax.Array]:
    """``(p, p', p'')`` of the spline at scalar ``s`` (clamped to the knot range), each ``(d,)``."""
    s = jnp.clip(s, knots[0], knots[-1])
    i = jnp.clip(jnp.searchsorted(knots, s, side="right") - 1, 0, knots.shape[0] - 2)
    t = s - knots[i]
    a, b, c, e = coef[i]
    return a + t * (b + t * (c + t * e)), b + t * (2 * c + 3 * t * e), 2 * c + 6 * t * e


def project(knots: jax.Array, coef: jax.Array, p: jax.Array, s0: jax.Array, iters: int = 5) -> jax.Array:
    """Arc length ``s`` of the spline point nearest ``p`` ``(2,)`` by Newton–Raphson on
    ``g(s) = (c(s) − p)·c'(s) = 0`` from the guess ``s0`` (``iters`` steps, clamped to the track)."""

    def body(_, s):
        c, d1, d2 = spline_eval(knots, coef, s)
        g = jnp.dot(c - p, d1)
        dg = jnp.dot(d1, d1) + jnp.dot(c - p, d2)
        return jnp.clip(s - g / jnp.maximum(dg, 1e-6), knots[0], knots[-1])

    return jax.lax.fori_loop(0, iters, body, jnp.asarray(s0, dtype=p.dtype))


def cross_track(knots: jax.Array, coef: jax.Array, p: jax.Array, s: jax.Array) -> jax.Array:
    """Signed cross-track error (m, + left of the path) of ``p`` at the projection ``s``."""
    c, d1, _ = spline_eval(knots, coef, s)
    t = d1 / jnp.linalg.norm(d1)
    return t[0] * (p[1] - c[1]) - t[1] * (p[0] - c[0])


def lookahead(e_y: jax.Array, delta_max: Any, delta_min: Any, K: Any) -> jax.Array:
    """``Δ(e_y) = (Δ_max − Δ_min)·exp(−K e_y²) + Δ_min`` (m)."""
    return (delta_max - delta_min) * jnp.exp(-K * e_y**2) + delta_min


def allocation_rhs(z: jax.Array, tau_d: jax.Array, B: jax.Array, W: jax.Array, gamma: Any, rho: Any) -> jax.Array:
    """Time derivative of ``z = [u, λ]`` (``m + k``) for the demand ``τ_d`` ``(k,)``, effectiveness
    ``B`` ``(k, m)`` and weight ``W`` ``(m, m)``: ``u̇ = −γ ∂L/∂u``, ``λ̇ = +γ ∂L/∂λ`` with
    ``L = ½uᵀWu + λᵀ(τ_d − Bu) + ½ρ‖τ_d − Bu‖²``."""
    m = B.shape[1]
    u, lam = z[:m], z[m:]
    err = tau_d - B @ u
    du = -gamma * (W @ u - B.T @ lam - rho * B.T @ err)
    return jnp.concatenate([du, gamma * err])


def allocate(z: jax.Array, tau_d: jax.Array, B: jax.Array, W: jax.Array, gamma: Any, rho: Any, dt: float, n_sub: int):
    """``n_sub`` explicit Euler sub-steps of :func:`allocation_rhs` over ``dt`` (demand held)."""
    h = dt / n_sub
    return jax.lax.fori_loop(0, n_sub, lambda _, zz: zz + h * allocation_rhs(zz, tau_d, B, W, gamma, rho), z)


def min_norm_allocation(tau_d: jax.Array, B: jax.Array, W: jax.Array) -> jax.Array:
    """Closed form ``u* = W⁻¹Bᵀ(BW⁻¹Bᵀ)⁻¹τ_d`` (the flow's equilibrium)."""
    Wi_Bt = jnp.linalg.solve(W, B.T)
    return Wi_Bt @ jnp.linalg.solve(B @ Wi_Bt, tau_d)
