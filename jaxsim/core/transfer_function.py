"""SISO transfer functions ↔ state space (controller canonical form, as ``scipy.signal``).

Polynomials are 1-D arrays in descending powers of ``s``.  Both directions are pure ``jnp`` code,
so they differentiate and vmap (the characteristic polynomial uses the Faddeev–LeVerrier
recursion, exact in exact arithmetic and fine for the small orders of control models).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxsim.core.validation import check_finite, check_square, is_concrete


def tf2ss(num: jax.Array, den: jax.Array) -> tuple[jax.Array, jax.Array, jax.Array, jax.Array]:
    """``num/den`` (proper) → ``(A, B, C, D)`` in the same canonical form as ``scipy.signal.tf2ss``.

    Shapes: ``A (n, n)``, ``B (n, 1)``, ``C (1, n)``, ``D (1, 1)`` with ``n = len(den) − 1``.
    """
    num = jnp.atleast_1d(jnp.asarray(num, dtype=float))
    den = jnp.atleast_1d(jnp.asarray(den, dtype=float))
    check_finite("num", num)
    check_finite("den", den)
    if num.ndim != 1 or den.ndim != 1:
        raise ValueError(f"num/den: expected 1-D coefficient arrays, got {num.shape} and {den.shape}")
    if num.shape[0] > den.shape[0]:
        raise ValueError(f"num: improper transfer function (len(num)={num.shape[0]} > len(den)={den.shape[0]})")
    if is_concrete(den) and float(den[0]) == 0.0:
        raise ValueError("den: leading coefficient must be non-zero")
    return _controller_canonical(num, den)


@jax.jit
def _controller_canonical(num: jax.Array, den: jax.Array) -> tuple[jax.Array, jax.Array, jax.Array, jax.Array]:
    # one compiled program per degree (eagerly, each of these small operations compiled on its own)
    n = den.shape[0] - 1
    num = jnp.concatenate([jnp.zeros(den.shape[0] - num.shape[0]), num]) / den[0]
    den = den / den[0]
    d = num[:1].reshape(1, 1)
    if n == 0:
        return jnp.zeros((0, 0)), jnp.zeros((0, 1)), jnp.zeros((1, 0)), d
    a = jnp.zeros((n, n)).at[0, :].set(-den[1:]).at[1:, :-1].set(jnp.eye(n - 1))
    b = jnp.zeros((n, 1)).at[0, 0].set(1.0)
    c = (num[1:] - num[0] * den[1:]).reshape(1, n)
    return a, b, c, d


def _faddeev_leverrier(a: jax.Array) -> tuple[jax.Array, list[jax.Array]]:
    """``det(sI − A)`` coefficients ``(n + 1,)`` and the matrices ``M_1 … M_n`` with
    ``adj(sI − A) = Σ_k M_k s^(n−k)`` (``M_1 = I``, ``M_(k+1) = A M_k + c_k I``)."""
    n = a.shape[0]
    coeffs = [jnp.ones((), a.dtype)]
    mats = []
    m = jnp.zeros_like(a)
    eye = jnp.eye(n, dtype=a.dtype)
    for k in range(1, n + 1):
        m = a @ m + coeffs[-1] * eye
        mats.append(m)
        coeffs.append(-jnp.trace(a @ m) / k)
    return jnp.stack(coeffs), mats


def characteristic_polynomial(a: jax.Array) -> jax.Array:
    """Coefficients of ``det(sI − A)``, shape ``(n + 1,)``, leading 1 (Faddeev–LeVerrier)."""
    a = jnp.asarray(a)
    check_square("a", a)
    return _faddeev_leverrier(a)[0]


def ss2tf(a: jax.Array, b: jax.Array, c: jax.Array, d: jax.Array) -> tuple[jax.Array, jax.Array]:
    """SISO ``(A, B, C, D)`` → ``(num, den)``, both of length ``n + 1``.

    ``num = C adj(sI − A) B + D·det(sI − A)`` with the adjugate from the Faddeev–LeVerrier
    recursion, so the rounding errors scale with ``|C|·|B|`` and ``|D|``.  (``scipy.signal``'s
    ``det(sI − A + BC) + (D − 1)·det(sI − A)`` loses ``C B`` and ``D`` to cancellation against the
    monic determinants when they are small: ``B = 1e-9`` came back with a relative error of 1e-7.)
    """
    a, b, c, d = (jnp.atleast_2d(jnp.asarray(m, dtype=float)) for m in (a, b, c, d))
    check_square("a", a)
    n = a.shape[0]
    if b.shape != (n, 1):
        raise ValueError(f"b: expected shape ({n}, 1) for a SISO system, got {tuple(b.shape)}")
    if c.shape != (1, n):
        raise ValueError(f"c: expected shape (1, {n}) for a SISO system, got {tuple(c.shape)}")
    if d.shape != (1, 1):
        raise ValueError(f"d: expected shape (1, 1), got {tuple(d.shape)}")
    den, mats = _faddeev_leverrier(a)
    cab = jnp.stack([jnp.zeros((), a.dtype)] + [(c @ m @ b)[0, 0] for m in mats])
    return cab + d[0, 0] * den, den
