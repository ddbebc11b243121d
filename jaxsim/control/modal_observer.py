"""Modal (pole-placement) state feedback with a full-order observer of the plant and of a disturbance
internal model: a harmonic oscillator at an assumed frequency plus a constant.

Bondarev et al. (seed 004, #17; spec seed004_part1.md B7 §2): plant ``ẋ = A x + B (u + d)``,
``y = C x`` (single input, the disturbance matched); the disturbance ``d = C_w w`` with
``ẇ = A_w w``, ``A_w = [[0, 1, 0], [−Ω², 0, 0], [0, 0, 0]]``, ``C_w = [1, 0, 1]`` (harmonic at ``Ω``
plus a constant).  The design model is the augmented ``z = [x; w]`` (order ``n + 3``).  Control
``u = −K x̂ − ĉ_w ŵ`` (state feedback + disturbance cancellation); ``K`` places ``eig(A − BK)`` on a
Butterworth pattern of radius ``ω_c``; the observer ``ż̂ = A_a ẑ + B_a u + L (y − C_a ẑ)`` has
Butterworth poles of radius ``ratio·ω_c`` (the paper: an order of magnitude faster, ratio 10),
``L`` from the dual system.  Gains by Ackermann's formula in a scaled time (:func:`scaled_acker`; a few
``jnp`` matrix products, quick to compile and differentiable; SciPy's ``place_poles`` is the oracle in
the tests).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.validation import is_concrete


def butterworth_poles(n: int, radius: Any) -> jax.Array:
    """The ``n`` left-half-plane poles ``radius·exp(j(π/2 + (2k − 1)π/(2n)))``, ``k = 1..n`` (complex ``(n,)``;
    a real pole ``−radius`` for odd ``n``).  ``ValueError`` for ``n < 1``."""
    if int(n) < 1:
        raise ValueError(f"n: must be a positive integer, got {n!r}")
    n = int(n)
    k = jnp.arange(1, n // 2 + 1)
    angle = jnp.pi / 2 + (2 * k - 1) * jnp.pi / (2 * n)
    upper = jnp.exp(1j * angle)  # exact conjugate pairs (place pairs them)
    parts = [upper, jnp.conj(upper)] + ([jnp.array([-1.0 + 0j])] if n % 2 else [])
    p = jnp.concatenate(parts)
    return radius * p


def internal_model(omega: Any) -> tuple[jax.Array, jax.Array]:
    """``(A_w (3,3), C_w (1,3))``: harmonic oscillator at ``omega`` rad/s plus a constant."""
    omega = jnp.asarray(omega, dtype=float)
    a = jnp.zeros((3, 3)).at[0, 1].set(1.0).at[1, 0].set(-(omega**2))
    return a, jnp.array([[1.0, 0.0, 1.0]])


class ModalDesign(NamedTuple):
    """Gains ``K (1,n)``, ``L (n+3,1)`` and the augmented model ``A_a, B_a, C_a``; ``C_w`` the disturbance
    output (``u = −K x̂ − C_w ŵ``)."""

    K: jax.Array
    L: jax.Array
    Aa: jax.Array
    Ba: jax.Array
    Ca: jax.Array
    Cw: jax.Array


def augmented(A: Any, B: Any, C: Any, omega: Any) -> tuple[Any, Any, Any, Any]:  # noqa: N803
    """``(A_a, B_a, C_a, C_w)`` of ``z = [x; w]``: ``A_a = [[A, B C_w], [0, A_w]]``, ``B_a = [B; 0]``,
    ``C_a = [C, 0]`` (NumPy arrays when every input is concrete, so designs inside a traced loss keep
    the model constant)."""
    xp = np if is_concrete((A, B, C, omega)) else jnp
    a, b, c = (xp.atleast_2d(xp.asarray(m, dtype=float)) for m in (A, B, C))
    n = a.shape[0]
    if b.shape != (n, 1) or c.shape != (1, n):
        raise ValueError(f"B, C: expected shapes ({n}, 1) and (1, {n}), got {b.shape} and {c.shape}")
    w2 = xp.asarray(omega, dtype=float) ** 2
    aw = xp.array([[0.0, 1.0, 0.0], [-w2, 0.0, 0.0], [0.0, 0.0, 0.0]])
    cw = xp.array([[1.0, 0.0, 1.0]])
    aa = xp.block([[a, b @ cw], [xp.zeros((3, n)), aw]])
    ba = xp.concatenate([b, xp.zeros((3, 1))])
    ca = xp.concatenate([c, xp.zeros((1, 3))], axis=1)
    return aa, ba, ca, cw


def butterworth_coefficients(n: int) -> np.ndarray:
    """Coefficients ``[1, a1, …, an]`` (highest power first) of the normalised Butterworth polynomial of order
    ``n`` (unit radius): ``a_k = Π_{μ=1..k} cos((μ − 1)γ)/sin(μγ)``, ``γ = π/(2n)`` (real, NumPy)."""
    if int(n) < 1:
        raise ValueError(f"n: must be a positive integer, got {n!r}")
    g = np.pi / (2 * n)
    a = [1.0]
    for mu in range(1, n + 1):
        a.append(a[-1] * np.cos((mu - 1) * g) / np.sin(mu * g))
    return np.array(a)


def scaled_acker(A: Any, B: Any, coeffs: Any, scale: Any) -> jax.Array:  # noqa: N803
    """Ackermann's formula ``K = eₙᵀ 𝒞⁻¹ φ(A)`` (single input) in the time scale ``t' = scale·t``:
    ``eig(A − BK)`` are ``scale`` × the roots of ``coeffs`` (monic, highest power first, length ``n + 1``).
    The scaled roots are ``O(1)``, which keeps ``φ`` and the controllability matrix far better conditioned
    than at the raw scale; real arithmetic only (quick to compile, differentiable)."""
    n = jnp.shape(A)[0]
    if len(coeffs) != n + 1:
        raise ValueError(f"coeffs: expected {n + 1} coefficients, got {len(coeffs)}")
    if is_concrete((A, B)):
        # 𝒞(A/s) = 𝒞(A)·diag(s⁻ᵏ), so eₙᵀ𝒞(A/s)⁻¹ = (s/s₀)ⁿ⁻¹·eₙᵀ𝒞(A/s₀)⁻¹: one NumPy solve at a
        # well-conditioned reference scale s₀ = ‖A‖₂, no linear solve in the traced (tuned) graph
        a0, b0 = np.asarray(A, dtype=float), np.asarray(B, dtype=float)
        s0 = max(float(np.linalg.norm(a0, 2)), 1e-12)
        q0 = np.linalg.solve(_ctrb(a0 / s0, b0, np).T, np.eye(n)[-1])
        q = (scale / s0) ** (n - 1) * jnp.asarray(q0)
    else:
        q = jnp.linalg.solve(_ctrb(jnp.asarray(A) / scale, jnp.asarray(B), jnp).T, jnp.eye(n)[-1])  # eₙᵀ 𝒞⁻¹
    a = jnp.asarray(A) / scale
    phi = jnp.eye(n)
    for c in coeffs[1:]:  # Horner: φ(a) = aⁿ + c1 aⁿ⁻¹ + … + cn I
        phi = phi @ a + c * jnp.eye(n)
    return scale * (q @ phi)[None, :]


def _ctrb(a: Any, b: Any, xp: Any) -> Any:
    """Controllability matrix ``[b, a b, …, aⁿ⁻¹ b]`` (single input) with the array module ``xp``."""
    cols = [b[:, 0]]
    for _ in range(a.shape[0] - 1):
        cols.append(a @ cols[-1])
    return xp.stack(cols, axis=1)


def modal_design(A: Any, B: Any, C: Any, omega: Any, radius: Any, observer_ratio: Any = 10.0) -> ModalDesign:  # noqa: N803
    """Controller poles: Butterworth of order ``n``, radius ``radius`` rad/s; observer poles: Butterworth of
    order ``n + 3``, radius ``observer_ratio·radius``; internal model at ``omega`` rad/s."""
    aa, ba, ca, cw = augmented(A, B, C, omega)
    n = jnp.asarray(A).shape[0]
    k = scaled_acker(A, B, butterworth_coefficients(n), radius)
    lt = scaled_acker(aa.T, ca.T, butterworth_coefficients(n + 3), observer_ratio * radius)
    return ModalDesign(k, lt.T, aa, ba, ca, cw)


def control(design: ModalDesign, z_hat: jax.Array) -> jax.Array:
    """``u = −K x̂ − C_w ŵ`` (scalar) from the observer state ``ẑ = [x̂; ŵ]``."""
    n = design.K.shape[1]
    return -(design.K[0] @ z_hat[:n]) - design.Cw[0] @ z_hat[n:]


def observer_rate(design: ModalDesign, z_hat: jax.Array, u: jax.Array, y: jax.Array) -> jax.Array:
    """``ż̂ = A_a ẑ + B_a u + L (y − C_a ẑ)`` (``u``, ``y`` scalars)."""
    return design.Aa @ z_hat + design.Ba[:, 0] * u + design.L[:, 0] * (y - design.Ca[0] @ z_hat)


def closed_loop_matrix(design: ModalDesign, A: Any, B: Any, C: Any) -> jax.Array:  # noqa: N803
    """The ``(2n + 3)``-state matrix of plant ``[x]`` + observer ``[ẑ]`` under :func:`control` with ``d = 0``;
    its eigenvalues are the controller poles and the observer poles (separation principle)."""
    a, b, c = (jnp.atleast_2d(jnp.asarray(m, dtype=float)) for m in (A, B, C))
    g = jnp.concatenate([design.K, design.Cw], axis=1)  # u = −g ẑ
    top = jnp.concatenate([a, -b @ g], axis=1)
    bottom = jnp.concatenate([design.L @ c, design.Aa - design.Ba @ g - design.L @ design.Ca], axis=1)
    return jnp.concatenate([top, bottom], axis=0)
