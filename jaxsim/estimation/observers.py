"""Luenberger observers by pole placement, and sliding-mode observer building blocks.

Pole placement ``eig(A − B K) = poles``:

* one input: Ackermann's formula ``K = e_nᵀ 𝒞⁻¹ φ(A)`` (``𝒞`` the controllability matrix, ``φ`` the
  desired characteristic polynomial) — the gain is unique, differentiable in ``A, B`` and the poles;
* several inputs: eigenvector assignment in the spirit of Kautsky, Nichols & Van Dooren's method 0
  (the gain is not unique; the free eigenvectors are swept towards orthogonality, which keeps the
  closed-loop eigenvectors well conditioned).  With ``B = [U₀ U₁] [Z; 0]``, eigenvector ``xⱼ`` of
  ``λⱼ`` must lie in ``null(U₁ᴴ (A − λⱼ I))``; then ``K = Z⁻¹ U₀ᴴ (A − X Λ X⁻¹)``.  Complex poles must
  come in conjugate pairs (their eigenvectors are kept conjugate, so ``K`` is real).

An observer gain is the dual: ``L = place(Aᵀ, Cᵀ, poles)ᵀ`` gives ``eig(A − L C) = poles``.

Sliding-mode observers (Utkin; Walcott & Żak; seed 000 paper 2) add a discontinuous injection
``G ρ v(e_y)`` of the output error ``e_y = y − C x̂``; :func:`switching` gives the exact ``sign`` and
its smooth surrogates (``e/(|e| + ε)`` — seed 000's ``v_eq`` —, ``tanh(e/ε)``, saturation ``e/ε``).
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.switching import get_switch
from jaxsim.core.validation import check_finite, check_square, is_concrete

SWITCHING = ("sign", "fraction", "tanh", "saturation")


def _check_pair(a: jax.Array, b: jax.Array, poles: jax.Array) -> None:
    check_square("A", a)
    n = a.shape[0]
    if b.ndim != 2 or b.shape[0] != n:
        raise ValueError(f"B: expected shape ({n}, m), got {tuple(b.shape)}")
    if poles.shape != (n,):
        raise ValueError(f"poles: expected {n} poles, got shape {tuple(poles.shape)}")
    check_finite("A", a)
    check_finite("B", b)


def _conjugate_partners(poles: np.ndarray, tol: float = 1e-9) -> list[int]:
    """Index of each pole's conjugate (itself for a real pole); raises if a pair is missing."""
    partner = list(range(len(poles)))
    used = set()
    for i, p in enumerate(poles):
        if abs(p.imag) <= tol * max(1.0, abs(p)) or i in used:
            continue
        cands = [
            j
            for j in range(len(poles))
            if j != i and j not in used and abs(poles[j] - np.conj(p)) <= 1e-9 * max(1.0, abs(p))
        ]
        if not cands:
            raise ValueError(f"poles: complex pole {p} has no conjugate partner")
        partner[i], partner[cands[0]] = cands[0], i
        used.update((i, cands[0]))
    return partner


def ackermann(A: Any, B: Any, poles: Any) -> jax.Array:
    """Single-input pole placement ``K (1, n)`` with ``eig(A − B K) = poles`` (Ackermann's formula)."""
    a, b = jnp.asarray(A), jnp.asarray(B)
    poles = jnp.asarray(poles)
    _check_pair(a, b, poles)
    if b.shape[1] != 1:
        raise ValueError(f"B: Ackermann's formula needs one input, got {b.shape[1]}")
    n = a.shape[0]
    ctrb = jnp.concatenate([jnp.linalg.matrix_power(a, k) @ b for k in range(n)], axis=1)
    coeffs = jnp.real(jnp.poly(poles)).astype(a.dtype)  # [1, a1, …, an]
    phi = sum(c * jnp.linalg.matrix_power(a, n - i) for i, c in enumerate(coeffs))
    e_n = jnp.zeros((n,), a.dtype).at[-1].set(1.0)
    row = jnp.linalg.solve(ctrb.T, e_n)
    return (row @ phi)[None, :]


def place_poles(A: Any, B: Any, poles: Any, *, sweeps: int = 10) -> jax.Array:
    """State-feedback gain ``K (m, n)`` with ``eig(A − B K) = poles``.

    One input: :func:`ackermann`.  Several inputs: eigenvector assignment with ``sweeps`` KNV-0
    orthogonalisation sweeps (poles must be concrete here, to pair complex conjugates).
    """
    a, b = jnp.asarray(A), jnp.asarray(B)
    poles_arr = jnp.asarray(poles)
    _check_pair(a, b, poles_arr)
    if b.shape[1] == 1:
        return ackermann(a, b, poles_arr)
    if not is_concrete(poles_arr):
        raise ValueError("poles: must be concrete for multi-input placement (conjugate pairing)")
    p_np = np.asarray(poles_arr, dtype=complex)
    partner = _conjugate_partners(p_np)
    n, m = b.shape
    if m > n:
        raise ValueError(f"B: more inputs ({m}) than states ({n})")
    cdt = jnp.result_type(a.dtype, jnp.complex64)
    q, r = jnp.linalg.qr(b, mode="complete")
    u0, u1, z = q[:, :m], q[:, m:], r[:m, :]
    lam = jnp.asarray(p_np, dtype=cdt)
    eye = jnp.eye(n, dtype=cdt)

    def subspace(l):  # orthonormal basis (n, m) of the admissible eigenvectors of pole l
        if n == m:
            return eye[:, :m]
        _, _, vh = jnp.linalg.svd(u1.T.astype(cdt) @ (a.astype(cdt) - l * eye))
        return jnp.conj(vh[-m:].T)

    bases = [subspace(lam[j]) for j in range(n)]
    x = jnp.stack([bases[j][:, 0] for j in range(n)], axis=1)
    x = _keep_conjugates(x, partner)

    def sweep(_, x):
        for j in range(n):
            if partner[j] < j:
                continue  # set with its partner
            others = jnp.delete(x, j, axis=1, assume_unique_indices=True)
            qo, _ = jnp.linalg.qr(others, mode="complete")
            y = qo[:, -1]
            s = bases[j]
            v = s @ (jnp.conj(s.T) @ y)
            v = v / jnp.linalg.norm(v)
            x = x.at[:, j].set(v)
            if partner[j] != j:
                x = x.at[:, partner[j]].set(jnp.conj(v))
        return x

    x = jax.lax.fori_loop(0, int(sweeps), sweep, x)
    closed = x @ jnp.diag(lam) @ jnp.linalg.inv(x)
    k = jnp.linalg.solve(z.astype(cdt), jnp.conj(u0.T).astype(cdt) @ (a.astype(cdt) - closed))
    return jnp.real(k).astype(a.dtype)


def _keep_conjugates(x: jax.Array, partner: list[int]) -> jax.Array:
    for j, pj in enumerate(partner):
        if pj > j:
            x = x.at[:, pj].set(jnp.conj(x[:, j]))
    return x


def luenberger_gain(A: Any, C: Any, poles: Any) -> jax.Array:
    """Observer gain ``L (n, p)`` with ``eig(A − L C) = poles`` (prediction form)."""
    a, c = jnp.asarray(A), jnp.asarray(C)
    return place_poles(a.T, c.T, poles).T


def current_observer_gain(A: Any, C: Any, poles: Any) -> jax.Array:
    """Gain ``L (n, p)`` of the current (filter) form ``x̂⁺ = x̂⁻ + L (y − C x̂⁻)``, ``x̂⁻ = A x̂⁺ + B u``:
    the error obeys ``e⁻ ← (A − A L C) e⁻``, whose eigenvalues equal those of ``A − L C A``."""
    a, c = jnp.asarray(A), jnp.asarray(C)
    return luenberger_gain(a, c @ a, poles)


def luenberger_step(
    x_hat: jax.Array,
    y: jax.Array,
    u: jax.Array | None,
    A: jax.Array,
    B: jax.Array | None,
    C: jax.Array,
    L: jax.Array,
) -> jax.Array:
    """Discrete prediction-form observer ``x̂_{k+1} = A x̂ + B u + L (y − C x̂)``."""
    nxt = A @ x_hat + L @ (y - C @ x_hat)
    return nxt if B is None or u is None else nxt + B @ u


def luenberger_derivative(
    x_hat: jax.Array,
    y: jax.Array,
    u: jax.Array | None,
    A: jax.Array,
    B: jax.Array | None,
    C: jax.Array,
    L: jax.Array,
) -> jax.Array:
    """Continuous observer ``dx̂/dt = A x̂ + B u + L (y − C x̂)``."""
    return luenberger_step(x_hat, y, u, A, B, C, L)


def switching(e: jax.Array, mode: str = "sign", epsilon: Any = 1e-3) -> jax.Array:
    """The switching function of a sliding-mode injection, element-wise.

    ``"sign"``: exact ``sign(e)``; ``"fraction"``: ``e/(|e| + ε)``; ``"tanh"``: ``tanh(e/ε)``;
    ``"saturation"``: ``clip(e/ε, −1, 1)``.  All smooth forms tend to ``sign`` as ``ε → 0``.
    Thin front end to :mod:`jaxsim.core.switching` ("fraction" is its "ratio").
    """
    if mode not in SWITCHING:
        raise ValueError(f"mode: expected one of {SWITCHING}, got {mode!r}")
    return get_switch("ratio" if mode == "fraction" else mode)(e, epsilon)


def sliding_mode_injection(e_y: jax.Array, rho: Any, mode: str = "sign", epsilon: Any = 1e-3) -> jax.Array:
    """``ν = ρ · v(e_y)``: the discontinuous (or smoothed) output-error injection."""
    return jnp.asarray(rho) * switching(e_y, mode, epsilon)


def sliding_mode_observer_derivative(
    x_hat: jax.Array,
    y: jax.Array,
    u: jax.Array | None,
    A: jax.Array,
    B: jax.Array | None,
    C: jax.Array,
    L: jax.Array,
    G: jax.Array,
    rho: Any,
    *,
    mode: str = "sign",
    epsilon: Any = 1e-3,
) -> tuple[jax.Array, jax.Array]:
    """``dx̂/dt = A x̂ + B u + L e_y + G ν``, ``ν = ρ v(e_y)``, ``e_y = y − C x̂``; returns ``(dx̂/dt, ν)``.

    On the sliding surface the low-pass-filtered ``ν`` (the *equivalent injection*) reconstructs
    the unknown input that ``G`` spans (fault identification, seed 000 paper 2).
    """
    e_y = y - C @ x_hat
    nu = sliding_mode_injection(e_y, rho, mode, epsilon)
    dx = luenberger_derivative(x_hat, y, u, A, B, C, L) + G @ nu
    return dx, nu


def low_pass(filtered: jax.Array, signal: jax.Array, tau: Any, dt: Any) -> jax.Array:
    """One exact step of the first-order filter ``τ ẏ = s − y`` (``s`` held over ``dt``): recovers
    the equivalent injection from an exactly switching ``ν``."""
    a = jnp.exp(-jnp.asarray(dt) / jnp.asarray(tau))
    return a * filtered + (1.0 - a) * signal
