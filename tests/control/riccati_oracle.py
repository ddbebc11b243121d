"""Helpers shared by the Riccati tests: residuals and a condition estimate, in NumPy/SciPy only."""

from __future__ import annotations

import numpy as np
import scipy.linalg as sl


def gain_matrix(b, r):
    return b @ np.linalg.solve(r, b.T)


def care_relative_residual(x, a, b, q, r):
    g = gain_matrix(b, r)
    res = a.T @ x + x @ a - x @ g @ x + q
    scale = sum(np.linalg.norm(t) for t in (q, a.T @ x, x @ a, x @ g @ x))
    return np.linalg.norm(res) / scale


def scipy_care_residual(x, a, b, q, r):
    """The residual matrix exactly as SciPy's test suite forms it (``X A + AᵀX + Q − XB R⁻¹ BᵀX``)."""
    xb = x @ b
    return x @ a + a.T @ x + q - xb @ np.linalg.solve(np.atleast_2d(r), xb.T)


def scipy_dare_residual(x, a, b, q, r):
    """The DARE residual matrix as SciPy's test suite forms it."""
    xa, xb = x @ a, x @ b
    return a.T @ xa - x + q - a.T @ xb @ np.linalg.solve(r + b.T @ xb, b.T @ xa)


def dare_closed_loop(x, a, b, r):
    k = np.linalg.solve(r + b.T @ x @ b, b.T @ x @ a)
    return a - b @ k, k


def dare_relative_residual(x, a, b, q, r):
    _, k = dare_closed_loop(x, a, b, r)
    res = a.T @ x @ a - x - a.T @ x @ b @ k + q
    scale = sum(np.linalg.norm(t) for t in (q, x, a.T @ x @ a, a.T @ x @ b @ k))
    return np.linalg.norm(res) / scale


def condition_estimate(x, a, b, q, r, discrete: bool, iters: int = 12) -> float:
    """First-order relative condition number of the Riccati solution (Byers / Kenney–Hewer style):
    ``‖Ω⁻¹‖₂ · (‖Q‖ + c_A‖X‖ + c_G‖X‖²) / ‖X‖`` where ``Ω`` is the closed loop's Lyapunov operator
    (continuous: ``c_A = 2‖A‖``, ``c_G = ‖G‖``) or Stein operator (discrete: ``c_A = ‖A‖²``,
    ``c_G = ‖G‖‖A‖²``).  ``‖Ω⁻¹‖₂`` comes from a power iteration on ``Ω⁻ᵀΩ⁻¹`` with SciPy's Lyapunov
    solvers, independent of the solvers under test."""
    g = gain_matrix(b, r)
    na = np.linalg.norm(a, 2)
    if discrete:
        acl, _ = dare_closed_loop(x, a, b, r)
        inv = lambda v: sl.solve_discrete_lyapunov(acl.T, v)  # noqa: E731  Δ − AclᵀΔAcl = V
        inv_t = lambda v: sl.solve_discrete_lyapunov(acl, v)  # noqa: E731
        c_a, c_g = na**2, np.linalg.norm(g, 2) * na**2
    else:
        acl = a - g @ x
        inv = lambda v: sl.solve_continuous_lyapunov(acl.T, v)  # noqa: E731  AclᵀΔ + ΔAcl = V
        inv_t = lambda v: sl.solve_continuous_lyapunov(acl, v)  # noqa: E731
        c_a, c_g = 2 * na, np.linalg.norm(g, 2)
    v = np.random.default_rng(0).normal(size=a.shape)
    sigma = 0.0
    for _ in range(iters):
        v = inv_t(inv(v / np.linalg.norm(v)))
        sigma = np.sqrt(np.linalg.norm(v))  # ‖Ω⁻ᵀΩ⁻¹v‖ → σ_max(Ω⁻¹)² for unit v
    nx = max(np.linalg.norm(x, 2), np.finfo(float).tiny)
    return float(sigma * (np.linalg.norm(q, 2) + c_a * nx + c_g * nx**2) / nx)
