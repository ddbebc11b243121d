"""State-feedback pole placement: python-control's ``place`` (robust, multi-input) and ``acker``.

Both return ``K`` for ``u = −K x`` such that the eigenvalues of ``A − B K`` are the requested poles
(conjugate pairs for complex ones).  Discrete or continuous makes no difference here.

``place`` — Kautsky–Nichols–Van Dooren, method 0 (1985).  With ``B = [U₀ U₁] [Z; 0]`` (QR), the
eigenvector ``x_j`` of a pole ``λ_j`` must lie in ``S_j = ker U₁ᵀ(A − λ_j I)`` (an ``m``-dimensional
space).  Starting from one vector per space, each sweep replaces ``x_j`` by the projection onto
``S_j`` of the vector orthogonal to all other eigenvectors (column ``j`` of ``X⁻ᴴ``), which makes the
eigenvector matrix ``X`` better conditioned — the closed-loop poles less sensitive; conjugate poles
keep conjugate eigenvectors.  Then ``A − B K = X Λ X⁻¹`` gives ``K = Z⁻¹ U₀ᵀ (A − X Λ X⁻¹)``.  With
one input ``K`` is unique (SciPy's ``place_poles``, the oracle, gives the same); with several it
depends on the method — SciPy defaults to Yang–Tits, so the gains differ while the poles agree.
With as many inputs as states (``B`` invertible) the eigenvectors are free, and the orthonormal ones
KNV strives for are taken directly: ``A − B K`` is the real normal matrix with the requested poles.

Derivatives (``custom_jvp``): ``K`` is a smooth function of ``(A, B, poles)`` once the *parameter
vectors* ``g_j = K x_j`` are fixed, through ``x_j = (A − λ_j I)⁻¹ B g_j`` and ``K = G X⁻¹``; the
tangent holds the ``g_j`` that KNV chose at the current point (exact for one input, where ``K`` is
unique; for several inputs the derivative of the gain family through the current design).  NaN
when a requested pole equals an eigenvalue of ``A``.

``acker`` — Ackermann's formula ``K = [0 … 0 1] 𝒞⁻¹ φ(A)`` (``φ`` the desired characteristic
polynomial, ``𝒞`` the controllability matrix), single input only, plain ``jnp`` (differentiable),
numerically fragile beyond a few states; it also accepts repeated poles.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.validation import check_finite, check_square, is_concrete
from jaxsim.lti.structure import ctrb
from jaxsim.lti.transfer import poly_from_roots

KNV_SWEEPS = 30


def _inputs(A: Any, B: Any, p: Any) -> tuple[jax.Array, jax.Array, jax.Array]:  # noqa: N803
    a = jnp.atleast_2d(jnp.asarray(A, dtype=float))
    check_square("A", a)
    n = a.shape[0]
    b = jnp.asarray(B, dtype=float)
    if b.ndim == 1:
        b = b.reshape(-1, 1)
    if b.ndim != 2 or b.shape[0] != n:
        raise ValueError(f"B: expected shape ({n}, m), got {tuple(b.shape)}")
    poles = jnp.atleast_1d(jnp.asarray(p))
    poles = poles.astype(jnp.result_type(poles, jnp.complex64))
    if poles.shape != (n,):
        raise ValueError(f"p: expected {n} poles (one per state), got shape {tuple(poles.shape)}")
    check_finite("A", a)
    check_finite("B", b)
    check_finite("p", poles)
    if is_concrete(poles):
        v = np.asarray(poles)
        upper, lower = np.sort_complex(v[v.imag > 0]), np.sort_complex(np.conj(v[v.imag < 0]))
        if upper.shape != lower.shape or not np.allclose(upper, lower, rtol=1e-10, atol=1e-12):
            raise ValueError(f"p: complex poles must come in conjugate pairs, got {v!r}")
    if is_concrete((a, b)):
        an, bn = np.asarray(a), np.asarray(b)
        if np.linalg.matrix_rank(np.asarray(ctrb(an, bn))) < n:
            raise ValueError("A: (A, B) is not controllable; its uncontrollable poles cannot be moved")
    return a, b, poles


def _partners(p: jax.Array) -> jax.Array:
    """Each pole's conjugate partner index (itself for a real pole): every upper-half pole is matched
    greedily to the nearest unmatched conjugate (repeated complex pairs each get their own)."""
    n = p.shape[0]
    partner = jnp.arange(n)
    taken = jnp.zeros(n, bool)
    lower = p.imag < 0
    for j in range(n):
        dist = jnp.where(lower & ~taken, jnp.abs(p - jnp.conj(p[j])), jnp.inf)
        k = jnp.argmin(dist)
        upper = p[j].imag > 0
        partner = jnp.where(upper, partner.at[j].set(k).at[k].set(j), partner)
        taken = jnp.where(upper, taken.at[k].set(True), taken)
    return partner


def _real_phase(v: jax.Array) -> jax.Array:
    """``v`` rotated so that its largest entry is real and positive (a real eigenvector of a real
    pole then has zero imaginary part), normalised."""
    big = v[jnp.argmax(jnp.abs(v))]
    v = v * jnp.conj(big) / jnp.abs(big)
    return v / jnp.linalg.norm(v)


def _allowed_subspaces(a: jax.Array, u1: jax.Array, p: jax.Array, m: int) -> jax.Array:
    """``S_j`` (``(n, n, m)``: one orthonormal ``n × m`` basis per pole)."""
    n = a.shape[0]
    if u1.shape[1] == 0:
        return jnp.broadcast_to(jnp.eye(n, dtype=p.dtype), (n, n, n))

    def basis(lam):
        mat = u1.T.astype(p.dtype) @ (a.astype(p.dtype) - lam * jnp.eye(n, dtype=p.dtype))
        _, _, vh = jnp.linalg.svd(mat, full_matrices=True)
        return vh[n - m :].conj().T

    return jax.vmap(basis)(p)


@jax.jit
def _knv0(a: jax.Array, b: jax.Array, p: jax.Array) -> tuple[jax.Array, jax.Array]:
    """``(K, X)`` by KNV method 0 (module docstring); column ``j`` of ``X`` belongs to ``p[j]``."""
    n, m = b.shape
    q, r = jnp.linalg.qr(b, mode="complete")
    u0, u1, z = q[:, :m], q[:, m:], r[:m]
    partner = _partners(p)
    is_real, is_lower = p.imag == 0, p.imag < 0
    s = _allowed_subspaces(a, u1, p, m)

    def settle(x, j, xj):
        """Put ``xj`` in column ``j`` (real part for a real pole) and its conjugate in the partner's."""
        xj = _real_phase(xj)
        xj = jnp.where(is_real[j], xj.real.astype(xj.dtype), xj)
        x = x.at[:, j].set(xj)
        return jnp.where(is_real[j], x, x.at[:, partner[j]].set(jnp.conj(xj)))

    # one vector from each S_j (conjugates for the lower-half poles); a pole repeated r ≤ m times has
    # the same S_j each time, so its copies start from different basis vectors of it (else X is singular)
    same = jnp.abs(p[:, None] - p[None, :]) <= 1e-10 * (1.0 + jnp.abs(p[:, None]))
    column = jnp.sum(jnp.tril(same, -1) & ~is_lower[None, :], axis=1) % m
    x = jnp.zeros((n, n), p.dtype)
    for j in range(n):
        x = jnp.where(is_lower[j], x, settle(x, j, s[j][:, column[j]]))

    def update(j, x):
        y = jnp.linalg.inv(x).conj().T[:, j]  # orthogonal to every other eigenvector
        return jnp.where(is_lower[j], x, settle(x, j, s[j] @ (s[j].conj().T @ y)))

    if m > 1:
        x = jax.lax.fori_loop(0, KNV_SWEEPS * n, lambda i, x: update(i % n, x), x)
    closed = x @ jnp.diag(p) @ jnp.linalg.inv(x)
    k = jnp.linalg.solve(z, u0.T @ (a - closed.real))
    return k, x


def _gain_from_parameters(a: jax.Array, b: jax.Array, p: jax.Array, g: jax.Array) -> jax.Array:
    """``K = G X⁻¹`` with ``x_j = (A − λ_j I)⁻¹ B g_j`` (columns ``g_j`` of ``G``) — the smooth family."""
    n = a.shape[0]
    cd = p.dtype
    x = jax.vmap(
        lambda lam, gj: jnp.linalg.solve(a.astype(cd) - lam * jnp.eye(n, dtype=cd), b.astype(cd) @ gj),
        in_axes=(0, 1),
        out_axes=1,
    )(p, g)
    return jnp.real(jnp.linalg.solve(x.T, g.T).T)


@jax.custom_jvp
def _place(a: jax.Array, b: jax.Array, p: jax.Array) -> jax.Array:
    return _knv0(a, b, p)[0]


@_place.defjvp
def _place_jvp(primals, tangents):
    a, b, p = primals
    k, x = _knv0(a, b, p)
    g = k.astype(x.dtype) @ x  # g_j = K x_j, held fixed
    _, dk = jax.jvp(lambda aa, bb, pp: _gain_from_parameters(aa, bb, pp, g), primals, tangents)
    return k, dk


def place(A: Any, B: Any, p: Any) -> jax.Array:  # noqa: N803
    """python-control's ``place(A, B, p)``: ``K`` (``(m, n)``) with ``eig(A − B K) = p``.

    Args:
        A: ``(n, n)``; B: ``(n, m)`` of full column rank; p: ``(n,)`` poles, complex ones in
            conjugate pairs, each repeated at most ``m`` times.

    Raises:
        ValueError: naming ``A``/``B``/``p`` for shapes, NaN, unpaired complex poles, ``(A, B)``
            not controllable, ``B`` rank-deficient, or a pole repeated more than ``rank B`` times
            (concrete input; traced: NaN).
    """
    a, b, poles = _inputs(A, B, p)
    if is_concrete((b, poles)):
        m = np.linalg.matrix_rank(np.asarray(b))
        if m < b.shape[1]:
            raise ValueError(f"B: must have full column rank ({b.shape[1]}), got rank {m}")
        v = np.asarray(poles)
        mult = max(int(np.sum(np.isclose(v, x, rtol=1e-10, atol=1e-12))) for x in v)
        if mult > m:
            raise ValueError(
                f"p: a pole repeated {mult} times cannot be placed with rank(B) = {m} "
                "(use acker for repeated poles of a single-input system)"
            )
    if b.shape[1] == a.shape[0]:
        return _place_square(a, b, poles)
    return _place(a, b, poles)


def _normal_matrix(p: jax.Array) -> jax.Array:
    """A real normal matrix with eigenvalues ``p`` (conjugate pairs): ``X diag(p) Xᴴ`` with the unitary
    ``X`` whose column is ``e_j`` for a real pole and ``(e_j ± i e_k)/√2`` for a pair ``(j, k)``."""
    n = p.shape[0]
    partner = _partners(p)
    eye = jnp.eye(n, dtype=p.dtype)
    mate = eye[:, partner]
    pair = jnp.where(p.imag > 0, eye + 1j * mate, mate - 1j * eye) / jnp.sqrt(2.0)
    x = jnp.where(p.imag == 0, eye, pair)
    return jnp.real(x @ jnp.diag(p) @ x.conj().T)


def _place_square(a: jax.Array, b: jax.Array, p: jax.Array) -> jax.Array:
    """``m = n`` (invertible ``B``): every closed loop is reachable, and KNV's best-conditioned one has
    orthonormal eigenvectors — the normal matrix of :func:`_normal_matrix`: ``K = B⁻¹(A − M)``."""
    return jnp.linalg.solve(b, a - _normal_matrix(p))


def acker(A: Any, B: Any, poles: Any) -> jax.Array:  # noqa: N803
    """python-control's ``acker(A, B, poles)``: Ackermann's formula, single input, ``K`` ``(1, n)``."""
    a, b, p = _inputs(A, B, poles)
    if b.shape[1] != 1:
        raise ValueError(f"B: acker is for a single input, got {b.shape[1]} columns (use place)")
    n = a.shape[0]
    coeffs = poly_from_roots(p)  # descending: φ(s) = s^n + c_1 s^{n−1} + … + c_n
    phi = jnp.zeros_like(a)
    for c in coeffs:  # Horner: φ(A) = (…((A + c_1 I) A + c_2 I) A …) + c_n I
        phi = phi @ a + c * jnp.eye(n, dtype=a.dtype)
    e_last = jnp.zeros((1, n), a.dtype).at[0, -1].set(1.0)
    return e_last @ jnp.linalg.solve(ctrb(a, b), phi)
