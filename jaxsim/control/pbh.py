"""Stabilisability and detectability by the Popov–Belevitch–Hautus (PBH) test, on concrete inputs.

``(A, B)`` is stabilisable iff ``rank [A − λI, B] = n`` for every eigenvalue ``λ`` of ``A`` outside
the open stability region (``Re λ ≥ 0`` in continuous time, ``|λ| ≥ 1`` in discrete time);
``(A, C)`` is detectable iff ``(Aᵀ, Cᵀ)`` is stabilisable.  The rank is judged by the smallest
singular value of ``[(A − λI)/‖A‖₂, B̂]`` where ``B̂`` is ``B`` with unit-norm columns (column
scalings do not change the rank, and weights spanning many decades no longer hide behind the
largest): below ``rtol`` (default 1e-8, about the accuracy of a computed eigenvalue of a 2×2
Jordan block) the mode counts as uncontrollable.

These checks run in NumPy at the public boundary only (they raise ``ValueError``); inside
``jit``/``vmap``/``grad`` the inputs are tracers and the solvers return NaN instead.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from jaxsim.control._symplectic_balance import balance_pair

DEFAULT_RTOL = 1e-8


def _boundary_margin(lam: np.ndarray) -> np.ndarray:
    """Eigenvalues this close to the boundary (relative to ``|λ|``) are treated as on it."""
    return 1e3 * np.finfo(float).eps * np.maximum(1.0, np.abs(lam))


def uncontrollable_modes(
    a: np.ndarray,
    b: np.ndarray,
    *,
    discrete: bool = False,
    region: str = "unstable",
    rtol: float = DEFAULT_RTOL,
) -> list[complex]:
    """Eigenvalues of ``A`` in ``region`` that ``B`` cannot move (PBH rank defect).

    Args:
        a: ``(n, n)`` state matrix.
        b: ``(n, m)`` input matrix.
        discrete: unit circle instead of imaginary axis as the stability boundary.
        region: ``"unstable"`` (closed unstable region, for stabilisability), ``"boundary"``
            (only modes on the imaginary axis / unit circle), or ``"all"`` (controllability).
        rtol: relative threshold on the smallest singular value of ``[A − λI, B]``.
    """
    a = np.asarray(a)
    b = np.asarray(b).reshape(a.shape[0], -1)
    real = not (np.iscomplexobj(a) or np.iscomplexobj(b))
    if real and a.size and np.all(np.isfinite(a)) and np.all(np.isfinite(b)):
        a, b = (np.asarray(m) for m in balance_pair(jnp.asarray(a), jnp.asarray(b)))
    a = a.astype(complex)
    b = b.astype(complex)
    n = a.shape[0]
    # Column scalings leave the PBH rank unchanged: unit-norm columns of B (so weights spanning
    # many decades, e.g. Q = diag(1e8, 1), do not hide behind the largest) and A over its norm.
    col = np.linalg.norm(b, axis=0)
    b = b[:, col > 0] / col[col > 0]
    a_scale = max(np.linalg.norm(a, 2), np.finfo(float).tiny)
    lam = np.linalg.eigvals(a)
    dist = (np.abs(lam) - 1.0) if discrete else lam.real  # signed distance to the boundary
    margin = _boundary_margin(lam)
    if region == "unstable":
        lam = lam[dist >= -margin]
    elif region == "boundary":
        lam = lam[np.abs(dist) <= margin]
    if lam.size == 0:
        return []
    pbh = np.concatenate(
        [(a[None] - lam[:, None, None] * np.eye(n)) / a_scale, np.broadcast_to(b, (lam.size,) + b.shape)], axis=2
    )
    smallest = np.linalg.svd(pbh, compute_uv=False)[:, -1]
    return [complex(z) for z in lam[smallest <= rtol]]


def _fmt(modes: list[complex]) -> str:
    return ", ".join(f"{z.real:.6g}{z.imag:+.6g}j" for z in modes)


def check_stabilizable(
    a_name: str,
    a: np.ndarray,
    b_name: str,
    b: np.ndarray,
    *,
    discrete: bool = False,
    rtol: float = DEFAULT_RTOL,
) -> None:
    """Raise ``ValueError`` if ``(a, b)`` is not stabilisable."""
    bad = uncontrollable_modes(a, b, discrete=discrete, rtol=rtol)
    if bad:
        kind = "|λ| ≥ 1" if discrete else "Re λ ≥ 0"
        raise ValueError(
            f"({a_name}, {b_name}): not stabilisable — mode(s) {_fmt(bad)} with {kind} are "
            f"uncontrollable from {b_name} (PBH test)"
        )


def check_detectable(
    a_name: str,
    a: np.ndarray,
    c_name: str,
    c: np.ndarray,
    *,
    discrete: bool = False,
    rtol: float = DEFAULT_RTOL,
) -> None:
    """Raise ``ValueError`` if ``(a, c)`` is not detectable."""
    bad = uncontrollable_modes(np.asarray(a).T, np.asarray(c).T, discrete=discrete, rtol=rtol)
    if bad:
        kind = "|λ| ≥ 1" if discrete else "Re λ ≥ 0"
        raise ValueError(
            f"({a_name}, {c_name}): not detectable — mode(s) {_fmt(bad)} with {kind} are "
            f"unobservable from {c_name} (PBH test)"
        )


def check_no_unobservable_boundary_modes(
    a_name: str,
    a: np.ndarray,
    q_name: str,
    q: np.ndarray,
    *,
    discrete: bool = False,
    dual: bool = False,
    rtol: float = DEFAULT_RTOL,
) -> None:
    """Raise if a mode of ``a`` on the stability boundary is unobservable from the weight ``q``.

    With ``Q ⪰ 0`` and ``(A, B)`` stabilisable this is exactly the condition for the Riccati
    equation to have a stabilising solution (detectability of ``(A, Q^{1/2})`` implies it).
    ``dual=True`` is the filter's version: no boundary mode of ``a`` may be *uncontrollable* from
    the process-noise covariance ``q``.
    """
    a, q = np.asarray(a), np.asarray(q)
    bad = uncontrollable_modes(a if dual else a.T, q if dual else q.T, discrete=discrete, region="boundary", rtol=rtol)
    if bad:
        where = "unit circle" if discrete else "imaginary axis"
        what = "not stabilisable from the process noise" if dual else "not detectable"
        how = "uncontrollable" if dual else "unobservable"
        raise ValueError(
            f"({a_name}, {q_name}): {what} — mode(s) {_fmt(bad)} on the {where} are {how} "
            f"from {q_name}, so no stabilising Riccati solution exists (PBH test)"
        )
