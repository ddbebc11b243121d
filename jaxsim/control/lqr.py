"""Linear-quadratic regulators: continuous ``lqr`` and discrete ``dlqr``.

* ``lqr``: minimises ``∫ (xᵀQx + uᵀRu) dt`` for ``ẋ = Ax + Bu``; ``u = −Kx``, ``K = R⁻¹BᵀP``,
  ``P`` the stabilising CARE solution (python-control's ``control.lqr`` convention).
* ``dlqr``: minimises ``Σ (xᵀQx + uᵀRu)`` for ``x⁺ = Ax + Bu``; ``K = (R + BᵀPB)⁻¹BᵀPA``.

Both are differentiable in ``A, B, Q, R`` through the Riccati solvers' implicit derivatives and
vmappable.  On concrete inputs they check ``Q ⪰ 0`` and ``R ≻ 0`` (``dlqr``: ``R ⪰ 0``), and after
the solve raise ``ValueError`` if ``(A, B)`` is not stabilisable or a mode on the stability boundary
is unobservable from ``Q`` (then no stabilising gain exists) — judged on the balanced data, so
the verdict does not depend on the state units.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
from jax.scipy.linalg import cho_factor, cho_solve

from jaxsim.control.riccati import (
    check_positive_semidefinite,
    check_stabilising,
    dare_gain,
    prepare_riccati_inputs,
    solve_continuous_are,
    solve_discrete_are,
)


class LQRGain(NamedTuple):
    """``k``: gain ``(m, n)`` of ``u = −K x``; ``p``: Riccati solution ``(n, n)`` (cost ``x₀ᵀPx₀``)."""

    k: jax.Array
    p: jax.Array


def _check_weights(a, b, q, r, discrete: bool):
    a, b, q, r = prepare_riccati_inputs(a, b, q, r, r_definite=not discrete)
    check_positive_semidefinite("q", q)
    return a, b, q, r


def lqr(a, b, q, r) -> LQRGain:
    """Continuous-time LQR gain.

    Args:
        a: ``(n, n)``; b: ``(n, m)``; q: ``(n, n)`` symmetric ⪰ 0; r: ``(m, m)`` symmetric ≻ 0
            (``dlqr``: ⪰ 0 is enough when ``R + BᵀPB ≻ 0``).

    Returns:
        :class:`LQRGain` with ``k = R⁻¹BᵀP``.
    """
    a, b, q, r = _check_weights(a, b, q, r, discrete=False)
    p = solve_continuous_are(a, b, q, r)
    check_stabilising(p, a, b, q, r, discrete=False)
    return LQRGain(cho_solve(cho_factor(r), b.T @ p), p)


def dlqr(a, b, q, r) -> LQRGain:
    """Discrete-time LQR gain ``K = (R + BᵀPB)⁻¹BᵀPA`` (shapes as :func:`lqr`)."""
    a, b, q, r = _check_weights(a, b, q, r, discrete=True)
    p = solve_discrete_are(a, b, q, r)
    check_stabilising(p, a, b, q, r, discrete=True)
    return LQRGain(dare_gain(p, a, b, r), p)


def closed_loop_matrix(a: jax.Array, b: jax.Array, k: jax.Array) -> jax.Array:
    """``A − B K`` (``(n, n)``)."""
    return jnp.asarray(a) - jnp.asarray(b) @ jnp.asarray(k)
