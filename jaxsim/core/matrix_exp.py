"""Matrix exponential for the toolkit's discretisations: one Padé approximant, small compiled code.

``jax.scipy.linalg.expm`` picks one of five Padé approximants with ``lax.switch`` and undoes the
scaling with a scan of ``lax.cond``; every branch is compiled, and differentiated, into the
caller's program.  Inside a loss that is differentiated end to end (an LQG design from weights, then
``c2d_zoh``) that machinery cost about as much XLA compile time as the Riccati solver itself.

:func:`expm` uses the degree-13 diagonal Padé approximant only (scaling and squaring, Higham 2005,
"The scaling and squaring method for the matrix exponential revisited", SIAM J. Matrix Anal. Appl.
26(4), Table 2.3 and eq. (2.1)): ``A`` is scaled by ``2^-s`` with ``s = max(0, ⌈log₂(‖A‖₁/θ₁₃)⌉)``,
``θ₁₃ = 5.37``, so that the approximant is accurate to double precision, and squared back ``s``
times.  For small norms the lower-degree approximants that Higham's algorithm would choose are only
cheaper, not more accurate, so the result agrees with SciPy's to rounding.  The squarings run in a
fixed-length scan with a mask (at most :data:`MAX_SQUARINGS`), so the function is differentiable in
forward and reverse mode, and vmappable.  Norms that would need more squarings give NaN (as
``jax.scipy.linalg.expm`` does).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

MAX_SQUARINGS = 16  # ‖A‖₁ up to θ₁₃·2¹⁶ ≈ 3.5e5; beyond, NaN
THETA_13 = 5.371920351148152  # Higham (2005), Table 2.3, m = 13, double precision

# Coefficients b_0 … b_13 of the degree-13 Padé approximant (Higham 2005, eq. (2.1) ff.)
_B = (
    64764752532480000.0,
    32382376266240000.0,
    7771770303897600.0,
    1187353796428800.0,
    129060195264000.0,
    10559470521600.0,
    670442572800.0,
    33522128640.0,
    1323241920.0,
    40840800.0,
    960960.0,
    16380.0,
    182.0,
    1.0,
)


def _pade13(a: jax.Array) -> jax.Array:
    """``r₁₃(A) = q(A)⁻¹ p(A)`` with ``p(A) = V + U``, ``q(A) = V − U`` (``U`` odd, ``V`` even part)."""
    b = _B
    eye = jnp.eye(a.shape[0], dtype=a.dtype)
    a2 = a @ a
    a4 = a2 @ a2
    a6 = a4 @ a2
    u = a @ (a6 @ (b[13] * a6 + b[11] * a4 + b[9] * a2) + b[7] * a6 + b[5] * a4 + b[3] * a2 + b[1] * eye)
    v = a6 @ (b[12] * a6 + b[10] * a4 + b[8] * a2) + b[6] * a6 + b[4] * a4 + b[2] * a2 + b[0] * eye
    return jnp.linalg.solve(v - u, v + u)


def expm(a: jax.Array) -> jax.Array:
    """``e^A`` of a square matrix ``a (n, n)`` (float or complex); NaN if ``‖A‖₁ > θ₁₃·2^16``.

    Differentiable (forward and reverse mode: the derivative of the same scaled Padé approximant,
    i.e. the Fréchet derivative to the approximant's accuracy) and vmappable."""
    a = jnp.asarray(a)
    if a.ndim != 2 or a.shape[0] != a.shape[1]:
        raise ValueError(f"a: expected a square matrix, got shape {tuple(a.shape)}")
    norm = jax.lax.stop_gradient(jnp.max(jnp.sum(jnp.abs(a), axis=0)))
    s = jnp.maximum(0.0, jnp.ceil(jnp.log2(norm / THETA_13)))
    s = jnp.where(jnp.isfinite(s), s, 0.0)
    r = _pade13(a * jnp.exp2(-s).astype(a.dtype))

    def square(i, m):
        needed = i < s
        x = jnp.where(needed, m, jnp.zeros_like(m))  # masked before the product: no NaN·0 in gradients
        return jnp.where(needed, x @ x, m)

    r = jax.lax.fori_loop(0, MAX_SQUARINGS, square, r)
    return jnp.where(s > MAX_SQUARINGS, jnp.nan, r)
