"""Poles and transmission zeros: python-control's ``pole``/``poles`` and ``zero``/``zeros``.

Poles are the eigenvalues of ``A``.  Transmission zeros of a square system (``p = m``, as
python-control without Slycot) come from its zero dynamics: with the relative degree ``rᵢ`` of
each output (the first Markov parameter ``M₀ = D``, ``M_k = C A^{k−1} B`` whose row ``i`` is not
zero) and the decoupling matrix ``Δ`` (row ``i`` of ``M_{rᵢ}``), the matrix
``A_z = A − B Δ⁻¹ Φ`` (row ``i`` of ``Φ`` is ``Cᵢ A^{rᵢ}``) has as eigenvalues the ``n − Σrᵢ``
transmission zeros plus ``Σrᵢ`` structural eigenvalues at 0, which are dropped.  A Markov row
counts as zero below ``MARKOV_RTOL`` of the largest one of that output (rows scaled by
``‖A‖^k``), so tiny coefficients are structural zeros, as in exact arithmetic.

Both are ``jit``/``vmap``/``grad``-able; derivatives are those of simple eigenvalues
(``dλ = uᴴ dM v / uᴴ v``), so repeated poles or zeros give NaN derivatives.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.validation import is_concrete
from jaxsim.lti.statespace import StateSpace, as_state_space

MARKOV_RTOL = 1e-10
"""A Markov-parameter row below this fraction of the output's largest (scaled) row is zero."""


def pole(sys: Any) -> jax.Array:
    """The poles (eigenvalues of ``A``), shape ``(n,)`` complex; ``z``-plane poles for a discrete
    system."""
    s = as_state_space(sys)
    if s.n_states == 0:
        return jnp.zeros((0,), dtype=jnp.result_type(s.a, jnp.complex64))
    return jnp.linalg.eigvals(s.a)


def _left_right(m: jax.Array) -> tuple[jax.Array, jax.Array, jax.Array]:
    """Eigenvalues ``w`` with right (columns of ``vr``) and matched left (columns of ``vl``) eigenvectors."""
    w, vr = jnp.linalg.eig(m)
    wl, vl = jnp.linalg.eig(m.conj().T)
    match = jnp.argmin(jnp.abs(jnp.conj(wl)[None, :] - w[:, None]), axis=1)
    return w, vr, vl[:, match]


@jax.custom_jvp
def simple_eigvals(m: jax.Array, keep: jax.Array) -> jax.Array:
    """Eigenvalues of ``m`` (``(n,)``, LAPACK order) whose derivative is taken only for the entries
    with ``keep`` (simple eigenvalues; the others get a zero tangent, e.g. a defective cluster)."""
    return jnp.linalg.eigvals(m)


@simple_eigvals.defjvp
def _simple_eigvals_jvp(primals, tangents):
    m, keep = primals
    dm, _ = tangents
    w, vr, vl = _left_right(m)
    denom = jnp.sum(vl.conj() * vr, axis=0)
    safe = keep & (jnp.abs(denom) > 0)
    vr = jnp.where(safe[None, :], vr, 0.0)
    vl = jnp.where(safe[None, :], vl, 0.0)
    denom = jnp.where(safe, denom, 1.0)
    dw = jnp.einsum("ji,jk,ki->i", vl.conj(), dm.astype(vr.dtype), vr) / denom
    return w, dw


def _relative_degrees(a: jax.Array, b: jax.Array, c: jax.Array, d: jax.Array):
    """Per output ``i``: ``rᵢ``, decoupling row ``Δᵢ`` and ``Φᵢ = Cᵢ A^{rᵢ}``; also whether every
    output has a nonzero Markov row (else its transfer row vanishes identically)."""
    n = a.shape[0]
    scale = jnp.maximum(jnp.linalg.norm(a, 2), jnp.finfo(a.dtype).tiny)
    ca = [c]  # C A^k, k = 0..n
    for _ in range(n):
        ca.append(ca[-1] @ a)
    markov = jnp.stack([d] + [ca[k] @ b for k in range(n)])  # (n + 1, p, m): M_0 = D, M_k = C A^{k−1} B
    weight = scale ** -jnp.arange(n + 1, dtype=a.dtype)
    size = jnp.linalg.norm(markov, axis=2) * weight[:, None]  # (n + 1, p)
    significant = size > MARKOV_RTOL * jnp.max(size, axis=0, keepdims=True)
    r = jnp.argmax(significant, axis=0)  # first significant k per output
    rows = jnp.arange(c.shape[0])
    delta = markov[r, rows]  # (p, m)
    phi = jnp.stack(ca)[r, rows]  # (p, n): C_i A^{r_i}
    return r, delta, phi, jnp.all(jnp.any(significant, axis=0))


def zero_candidates(s: StateSpace) -> tuple[jax.Array, jax.Array, jax.Array, jax.Array, jax.Array]:
    """``(A_z, eigenvalues of stop_gradient(A_z), keep, nonzero_rows, delta)`` for a square system
    with states: ``keep`` marks the transmission zeros (the other ``Σrᵢ`` are structural)."""
    n = s.n_states
    r, delta, phi, nonzero_rows = _relative_degrees(s.a, s.b, s.c, s.d)
    a_z = s.a - s.b @ jnp.linalg.solve(delta, phi)
    w = jnp.linalg.eigvals(jax.lax.stop_gradient(a_z))
    order = jnp.argsort(jnp.abs(w))  # the Σr structural eigenvalues are the ones nearest 0
    rank = jnp.empty_like(order).at[order].set(jnp.arange(n))
    return a_z, w, rank >= jnp.sum(r), nonzero_rows, delta


@jax.jit
def _zeros_and_checks(s: StateSpace) -> tuple[jax.Array, jax.Array, jax.Array, jax.Array]:
    """``(candidate zeros, keep, nonzero_rows, delta)`` as one compiled program per shape (eagerly,
    its few dozen small operations were each compiled on a first call)."""
    a_z, _, keep, nonzero_rows, delta = zero_candidates(s)
    return simple_eigvals(a_z, keep), keep, nonzero_rows, delta


def zero(sys: Any) -> jax.Array:
    """Transmission zeros of a square system (``p = m``), see the module docstring.

    Returns:
        Concrete input: the ``n − Σrᵢ`` finite zeros, complex (``z``-plane for a discrete system).
        Traced input (``jit``/``vmap``/``grad``): a fixed ``(n,)`` array whose structural entries
        (the zeros at infinity) are ``inf``.

    Raises:
        ValueError: naming ``sys`` for a non-square system, or (concrete input) a transfer row
            that is identically zero or a singular decoupling matrix (MIMO structures this
            method does not cover).  Traced: NaN instead.
    """
    s = as_state_space(sys)
    if s.n_outputs != s.n_inputs:
        raise ValueError(
            f"sys: zero() needs a square system (as many outputs as inputs), "
            f"got {s.n_outputs} outputs and {s.n_inputs} inputs"
        )
    cdtype = jnp.result_type(s.a, jnp.complex64)
    if s.n_states == 0:
        return jnp.zeros((0,), dtype=cdtype)
    zeros, keep, nonzero_rows, delta = _zeros_and_checks(s)
    if is_concrete((s.a, s.b, s.c, s.d)):
        if not bool(nonzero_rows):
            raise ValueError("sys: an output has an identically zero transfer row; its zeros are undefined")
        if np.linalg.cond(np.asarray(delta)) > 1e12:
            raise ValueError(
                "sys: singular decoupling matrix (MIMO structure not covered by zero(); "
                "each output's first nonzero Markov rows must be independent)"
            )
    if is_concrete(zeros):
        return zeros[np.asarray(keep)]
    return jnp.where(keep, zeros, jnp.inf).astype(cdtype)
