"""Linear-quadratic regulators: continuous ``lqr`` and discrete ``dlqr``.

* ``lqr``: minimises ``∫ (xᵀQx + uᵀRu) dt`` for ``ẋ = Ax + Bu``; ``u = −Kx``, ``K = R⁻¹BᵀP``,
  ``P`` the stabilising CARE solution (python-control's ``control.lqr`` convention).
* ``dlqr``: minimises ``Σ (xᵀQx + uᵀRu)`` for ``x⁺ = Ax + Bu``; ``K = (R + BᵀPB)⁻¹BᵀPA``.

Both are differentiable in ``A, B, Q, R`` through the Riccati solvers' implicit derivatives and
vmappable.  On concrete inputs they check ``Q ⪰ 0``, ``R ≻ 0``, stabilisability of ``(A, B)``
and that no mode on the stability boundary is unobservable from ``Q`` (the exact condition for a
stabilising solution; detectability of ``(A, Q^{1/2})`` implies it), raising ``ValueError``.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax.scipy.linalg import cho_factor, cho_solve

from jaxsim.control.pbh import check_no_unobservable_boundary_modes
from jaxsim.control.riccati import (
    check_positive_semidefinite,
    dare_gain,
    prepare_riccati_inputs,
    solve_continuous_are,
    solve_discrete_are,
)
from jaxsim.core.validation import is_concrete


class LQRGain(NamedTuple):
    """``k``: gain ``(m, n)`` of ``u = −K x``; ``p``: Riccati solution ``(n, n)`` (cost ``x₀ᵀPx₀``)."""

    k: jax.Array
    p: jax.Array


def _check_weights(a, b, q, r, discrete: bool):
    a, b, q, r = prepare_riccati_inputs(a, b, q, r)
    check_positive_semidefinite("q", q)
    if is_concrete((a, q)):
        check_no_unobservable_boundary_modes("a", np.asarray(a), "q", np.asarray(q), discrete=discrete)
    return a, b, q, r


def lqr(a, b, q, r) -> LQRGain:
    """Continuous-time LQR gain.

    Args:
        a: ``(n, n)``; b: ``(n, m)``; q: ``(n, n)`` symmetric ⪰ 0; r: ``(m, m)`` symmetric ≻ 0.

    Returns:
        :class:`LQRGain` with ``k = R⁻¹BᵀP``.
    """
    a, b, q, r = _check_weights(a, b, q, r, discrete=False)
    p = solve_continuous_are(a, b, q, r)
    return LQRGain(cho_solve(cho_factor(r), b.T @ p), p)


def dlqr(a, b, q, r) -> LQRGain:
    """Discrete-time LQR gain ``K = (R + BᵀPB)⁻¹BᵀPA`` (shapes as :func:`lqr`)."""
    a, b, q, r = _check_weights(a, b, q, r, discrete=True)
    p = solve_discrete_are(a, b, q, r)
    return LQRGain(dare_gain(p, a, b, r), p)


def closed_loop_matrix(a: jax.Array, b: jax.Array, k: jax.Array) -> jax.Array:
    """``A − B K`` (``(n, n)``)."""
    return jnp.asarray(a) - jnp.asarray(b) @ jnp.asarray(k)
