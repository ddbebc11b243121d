"""Exact discretisation of LTI models.

* :func:`c2d_zoh` — zero-order hold: ``Ad = e^{A dt}``, ``Bd = ∫₀^dt e^{Aτ} dτ B``, both from one
  matrix exponential of the block matrix ``[[A, B], [0, 0]]``.
* :func:`van_loan` — Van Loan's method for the process-noise covariance of a continuous white-noise
  input with intensity (power spectral density) ``Qc`` entering through ``G``:
  ``Qd = ∫₀^dt e^{Aτ} G Qc Gᵀ e^{Aᵀτ} dτ``.

Both are differentiable (forward and reverse mode) and vmappable; the exponential is
:func:`jaxsim.core.matrix_exp.expm` (one Padé approximant: a fraction of the compile time of
``jax.scipy.linalg.expm`` inside differentiated losses).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.matrix_exp import expm
from jaxsim.core.validation import check_finite, check_positive, check_square


def _check_dt(dt: float | jax.Array) -> None:
    if np.ndim(dt) == 0:
        check_positive("dt", dt)


def c2d_zoh(a: jax.Array, b: jax.Array, dt: float | jax.Array) -> tuple[jax.Array, jax.Array]:
    """Zero-order-hold discretisation of ``ẋ = A x + B u``.

    Args:
        a: state matrix, shape ``(n, n)``.
        b: input matrix, shape ``(n, m)``.
        dt: sample period (same time unit as the model), scalar > 0.

    Returns:
        ``(Ad, Bd)`` of shapes ``(n, n)`` and ``(n, m)``.
    """
    a = jnp.asarray(a)
    b = jnp.asarray(b)
    check_square("a", a)
    if b.ndim != 2 or b.shape[0] != a.shape[0]:
        raise ValueError(f"b: expected shape ({a.shape[0]}, m), got {tuple(b.shape)}")
    check_finite("a", a)
    check_finite("b", b)
    _check_dt(dt)
    n, m = b.shape
    dtype = jnp.result_type(a, b, jnp.asarray(dt))
    block = jnp.zeros((n + m, n + m), dtype=dtype)
    block = block.at[:n, :n].set(a).at[:n, n:].set(b)
    e = expm(block * dt)
    return e[:n, :n], e[:n, n:]


def van_loan(
    a: jax.Array,
    qc: jax.Array,
    dt: float | jax.Array,
    g: jax.Array | None = None,
) -> tuple[jax.Array, jax.Array]:
    """Discretise ``ẋ = A x + G w`` with ``E[w(t) w(s)ᵀ] = Qc δ(t − s)``.

    Args:
        a: state matrix, shape ``(n, n)``.
        qc: continuous noise intensity, shape ``(q, q)``, symmetric positive semi-definite.
        dt: sample period, scalar > 0.
        g: noise input matrix, shape ``(n, q)``; identity when omitted (then ``q = n``).

    Returns:
        ``(Ad, Qd)``: the transition matrix ``e^{A dt}`` and the discrete process-noise covariance,
        both ``(n, n)``.
    """
    a = jnp.asarray(a)
    qc = jnp.asarray(qc)
    check_square("a", a)
    check_square("qc", qc)
    n = a.shape[0]
    g = jnp.eye(n, dtype=a.dtype) if g is None else jnp.asarray(g)
    if g.shape != (n, qc.shape[0]):
        raise ValueError(f"g: expected shape ({n}, {qc.shape[0]}), got {tuple(g.shape)}")
    check_finite("a", a)
    check_finite("qc", qc)
    _check_dt(dt)
    gqg = g @ qc @ g.T
    block = jnp.block([[-a, gqg], [jnp.zeros_like(a), a.T]])
    e = expm(block * dt)
    ad = e[n:, n:].T
    qd = ad @ e[:n, n:]
    return ad, 0.5 * (qd + qd.T)
