"""Algebraic Riccati equations (CARE, DARE): float64 forward solves, implicit derivatives.

Conventions are SciPy's (``solve_continuous_are`` / ``solve_discrete_are``):

* CARE: ``Aᵀ X + X A − X B R⁻¹ Bᵀ X + Q = 0`` with ``R ≻ 0``;
* DARE: ``Aᵀ X A − X − Aᵀ X B (R + BᵀXB)⁻¹ Bᵀ X A + Q = 0`` with ``R ⪰ 0`` (singular ``R`` allowed:
  the equation needs ``R + BᵀXB ≻ 0`` at the solution, as in SciPy's DAREX examples 3 and 4).

``Q`` may be indefinite.  The solvers return the *stabilising* solution (``A − B R⁻¹ Bᵀ X`` Hurwitz,
resp. ``A − B (R + BᵀXB)⁻¹ BᵀXA`` Schur) when there is one.  When the Hamiltonian (symplectic pencil)
has eigenvalues on the stability boundary there is none; then the *maximal* solution is returned,
as SciPy does, and its closed loop is only marginally stable — :func:`riccati_diagnostics` says so
(``marginal``), and on concrete inputs a :class:`MarginalStabilityWarning` is issued.  The answer no
longer depends on the last bit of rounding: a problem within rounding of the boundary gets the
same (maximal) solution and the same verdict from either side.

Forward solves (never differentiated; :mod:`jaxsim.control._care_forward`,
:mod:`jaxsim.control._dare_forward`): a state scaling by powers of two that balances the problem
(so the verdict and the accuracy do not depend on the caller's state units), the matrix sign
function (CARE) or structure-preserving doubling (DARE), Newton refinement, and for the boundary
case Newton–Kleinman / Hewer iterations from a stabilising start down to the maximal solution.

A result is kept only if it is finite, its relative residual is below ``1e-6`` and its closed
loop is stable up to the marginal band; otherwise the solvers return NaN (inside ``jit``/``vmap``)
or raise ``ValueError`` (on concrete inputs, with a diagnosis: a PBH test on the balanced pair
names the uncontrollable unstable modes when there are any).

Derivatives (``custom_jvp``, so forward and reverse mode): differentiating ``F(X, θ) = 0`` gives
``F_X[dX] = −F_θ[dθ]`` where ``F_X`` is the Lyapunov operator ``dX ↦ A_clᵀ dX + dX A_cl`` (CARE) or
the Stein operator ``dX ↦ A_clᵀ dX A_cl − dX`` (DARE).  ``F_θ[dθ]`` is the JVP of the residual at
fixed ``X``, and the linear solve is :mod:`jaxsim.control.lyapunov`'s, whose transpose is the
adjoint Lyapunov/Stein equation — so a reverse-mode gradient costs one extra Lyapunov solve.  At a
marginal solution that operator is singular and the derivatives do not exist: they are NaN.

The forward solves use LAPACK's Schur decomposition and eigenvalues (through
:mod:`jaxsim.control.lyapunov` and the closed-loop stability check), which JAX provides on CPU only.
"""

from __future__ import annotations

import warnings
from functools import partial
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.control._care_forward import care_forward
from jaxsim.control._dare_forward import balancing_gain, dare_forward
from jaxsim.control._riccati_common import (
    MARGINAL,
    care_measures,
    care_residual,
    dare_gain,
    dare_measures,
    dare_residual,
    gain_matrix,
    sym,
)
from jaxsim.control._symplectic_balance import balancing_exponents, scale_problem
from jaxsim.control.lyapunov import continuous_lyapunov_unchecked, discrete_lyapunov_unchecked
from jaxsim.control.pbh import uncontrollable_modes
from jaxsim.core.validation import (
    check_finite,
    check_positive_definite,
    check_positive_semidefinite,  # noqa: F401  (re-exported: lqr and kalman_gain import it from here)
    check_square,
    check_symmetric,
    is_concrete,
)

__all__ = [
    "MarginalStabilityWarning",
    "RiccatiDiagnostics",
    "balanced_data",
    "care_residual",
    "check_stabilising",
    "dare_gain",
    "dare_residual",
    "gain_matrix",
    "riccati_diagnostics",
    "solve_continuous_are",
    "solve_discrete_are",
]


class MarginalStabilityWarning(UserWarning):
    """A Riccati solution exists but its closed loop is only marginally stable (maximal solution)."""


# ----------------------------------------------------------------------------- implicit derivatives


def _nan_unless_stabilising(dx: jax.Array, margin: jax.Array) -> jax.Array:
    """Derivatives exist only at a stabilising solution (the linearised operator is singular at a
    marginal one): NaN otherwise.  A product, not a ``where``, so that it stays linear in ``dx``
    (reverse mode transposes it)."""
    return dx * jnp.where(margin >= MARGINAL, 1.0, jnp.nan).astype(dx.dtype)


@jax.custom_jvp
def _care(a, b, q, r):
    return care_forward(a, b, q, r)


@_care.defjvp
def _care_jvp(primals, tangents):
    a, b, q, r = primals
    x, margin = _care(a, b, q, r)
    _, rhs = jax.jvp(lambda *p: care_residual(x, *p), primals, tangents)
    acl = a - gain_matrix(b, r) @ x
    dx = _nan_unless_stabilising(sym(continuous_lyapunov_unchecked(acl.T, -rhs)), margin)
    return (x, margin), (dx, jnp.zeros_like(margin))


@jax.custom_jvp
def _dare(a, b, q, r):
    return dare_forward(a, b, q, r)


@_dare.defjvp
def _dare_jvp(primals, tangents):
    a, b, q, r = primals
    x, margin = _dare(a, b, q, r)
    _, rhs = jax.jvp(lambda *p: dare_residual(x, *p), primals, tangents)
    acl = a - b @ dare_gain(x, a, b, r)
    dx = _nan_unless_stabilising(sym(discrete_lyapunov_unchecked(acl.T, rhs)), margin)
    return (x, margin), (dx, jnp.zeros_like(margin))


# One compiled program per shape: called eagerly, the solvers' loops would otherwise each be
# compiled and loaded as separate small executables (thousands over a test session).
_care_jit = jax.jit(_care)
_dare_jit = jax.jit(_dare)


# ----------------------------------------------------------------------------- public API


def _as_2d(name: str, m, rows: int | None = None) -> jax.Array:
    m = jnp.asarray(m)
    if m.ndim == 0:
        m = m.reshape(1, 1)
    if m.ndim == 1 and rows is not None:
        m = m.reshape(rows, -1)
    if m.ndim != 2:
        raise ValueError(f"{name}: expected a 2-D matrix, got shape {tuple(m.shape)}")
    return m


def prepare_riccati_inputs(a, b, q, r, names=("a", "b", "q", "r"), *, r_definite: bool = True):
    """Shape, finiteness and symmetry checks, and ``R ≻ 0`` (``r_definite``) or ``R ⪰ 0``; returns
    float arrays of one dtype, ``q``/``r`` symmetrised."""
    na, nb, nq, nr = names
    a = _as_2d(na, a)
    check_square(na, a)
    n = a.shape[0]
    b = _as_2d(nb, b, rows=n)
    q = _as_2d(nq, q)
    r = _as_2d(nr, r)
    if b.shape[0] != n:
        raise ValueError(f"{nb}: expected {n} rows to match {na}, got shape {tuple(b.shape)}")
    m = b.shape[1]
    if q.shape != (n, n):
        raise ValueError(f"{nq}: expected shape ({n}, {n}), got {tuple(q.shape)}")
    if r.shape != (m, m):
        raise ValueError(f"{nr}: expected shape ({m}, {m}), got {tuple(r.shape)}")
    for name, v in zip(names, (a, b, q, r)):
        check_finite(name, v)
    check_symmetric(nq, q)
    check_symmetric(nr, r)
    (check_positive_definite if r_definite else check_positive_semidefinite)(nr, r)
    dtype = jnp.result_type(a, b, q, r, float)
    return a.astype(dtype), b.astype(dtype), sym(q.astype(dtype)), sym(r.astype(dtype))


class RiccatiDiagnostics(NamedTuple):
    """What a Riccati solution is worth (all scalars; jit/vmap-able).

    ``relative_residual``: ``‖Res(X)‖_F / Σ‖terms‖_F``.  ``stability_margin``: continuous time the
    smallest ``−Re λ / max(|λ|, 1e-8‖A_cl‖₂)`` over the closed loop's eigenvalues (a damping ratio,
    scale-free), discrete time ``1 − max |λ(A_cl)|`` (positive: stable).
    ``stabilising``: the margin is at least ``1e-5``; ``marginal``: it is not (a margin within
    rounding of zero cannot be told from zero, so the two are exclusive) — the
    maximal solution of a problem whose Hamiltonian (symplectic pencil) has eigenvalues on, or
    within rounding of, the stability boundary; its closed loop is not robustly stable.
    """

    relative_residual: jax.Array
    stability_margin: jax.Array
    stabilising: jax.Array
    marginal: jax.Array


def riccati_diagnostics(x, a, b, q, r, *, discrete: bool) -> RiccatiDiagnostics:
    """Residual and closed-loop stability margin of a CARE (``discrete=False``) or DARE solution ``x``,
    measured on the solvers' balanced data (so they do not depend on the state units)."""
    x, a, b, q, r = (jnp.asarray(v) for v in (x, a, b, q, r))
    b = b.reshape(a.shape[0], -1)
    r = r.reshape(b.shape[1], b.shape[1])
    return _diagnostics(x, a, b, q, r, discrete)


@partial(jax.jit, static_argnums=5)
def _diagnostics(x, a, b, q, r, discrete: bool) -> RiccatiDiagnostics:
    ab, bb, qb, e = _balanced(a, b, q, r)
    xb = x * jnp.outer(jnp.exp2(e), jnp.exp2(e))  # X̃ = D X D
    if discrete:
        rel, margin = dare_measures(xb, ab, bb, qb, r)
    else:
        rel, margin = care_measures(xb, ab, gain_matrix(bb, r), qb)
    marginal = ~(margin >= MARGINAL)  # NaN counts as marginal
    return RiccatiDiagnostics(rel, margin, ~marginal, marginal)


@jax.jit
def _balanced(a, b, q, r):
    e = balancing_exponents(a, balancing_gain(b, r), q)
    return (*scale_problem(a, b, q, e), e)


def _fmt(modes) -> str:
    return ", ".join(f"{z.real:.6g}{z.imag:+.6g}j" for z in modes)


def balanced_data(a, b, q, r) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(D⁻¹AD, D⁻¹B, DQD)`` with the solvers' balancing ``D`` (NumPy, concrete inputs): the
    coordinates in which rank and stability thresholds mean the same whatever the state units."""
    a, b, q, r = (jnp.asarray(v, dtype=float) for v in (a, b, q, r))
    return tuple(np.asarray(v) for v in _balanced(a, b, q, r)[:3])


def _pair_words(names, dual: bool) -> tuple[str, str, str]:
    """(pair, property, how) for messages: dual problems are a filter's ``(Aᵀ, Cᵀ)``."""
    if dual:
        return f"({names[0]}, {names[1]})", "not detectable", f"unobservable from {names[1]}"
    return f"({names[0]}, {names[1]})", "not stabilisable", f"uncontrollable from {names[1]}"


def _explain_failure(a, b, q, r, what: str, names, discrete: bool, dual: bool) -> None:
    """Raise ``ValueError`` for a failed solve, naming uncontrollable unstable modes if there are."""
    try:
        ab, bb, _ = balanced_data(a, b, q, r)
    except (ValueError, np.linalg.LinAlgError):  # the diagnosis must not hide the failure itself
        ab, bb = np.asarray(a), np.asarray(b)
    bad = uncontrollable_modes(ab, bb, discrete=discrete)
    if bad:
        pair, prop, how = _pair_words(names, dual)
        kind = "|λ| ≥ 1" if discrete else "Re λ ≥ 0"
        raise ValueError(
            f"{pair}: {prop} — mode(s) {_fmt(bad)} with {kind} are {how} (PBH test on "
            f"the balanced pair); {what} has no stabilising solution"
        )
    raise ValueError(
        f"({', '.join(names)}): {what} has no solution that could be computed — neither a stabilising "
        "one nor a maximal one with a marginally stable closed loop (e.g. no symmetric solution "
        f"exists for this indefinite {names[2]}, or {names[3]} + {names[1]}ᵀX{names[1]} is singular, or the "
        "problem is too ill-conditioned)"
    )


def _check_concrete_result(x, a, b, q, r, what: str, names, discrete: bool, dual: bool) -> None:
    if not is_concrete((x, a, b, q, r)):
        return
    if not bool(jnp.all(jnp.isfinite(x))):
        _explain_failure(a, b, q, r, what, names, discrete, dual)
    diag = riccati_diagnostics(x, a, b, q, r, discrete=discrete)
    if bool(diag.marginal):
        where = "1 − max|λ|" if discrete else "min −Re λ/|λ|"
        warnings.warn(
            f"({', '.join(names)}): {what}'s closed loop is only marginally stable ({where} = "
            f"{float(diag.stability_margin):.2e}): the returned solution is the maximal one, not a "
            "robustly stabilising one (the Hamiltonian / symplectic pencil has eigenvalues on or "
            "within rounding of the stability boundary)",
            MarginalStabilityWarning,
            stacklevel=3,
        )


def check_stabilising(x, a, b, q, r, *, discrete: bool, names=("a", "b", "q", "r"), dual: bool = False) -> None:
    """For callers that need a *stabilising* solution (LQR, Kalman gains), on concrete inputs: raise
    ``ValueError`` when ``x`` is marginal because a mode on the stability boundary is unobservable
    from ``q`` (``dual``: uncontrollable from the process noise) — no stabilising solution exists."""
    if not is_concrete((x, a, b, q, r)) or not bool(riccati_diagnostics(x, a, b, q, r, discrete=discrete).marginal):
        return
    ab, _, qb = balanced_data(a, b, q, r)
    bad = uncontrollable_modes(ab.T, qb, discrete=discrete, region="boundary")
    if bad:
        where = "unit circle" if discrete else "imaginary axis"
        what = "not stabilisable from the process noise" if dual else "not detectable"
        how = "uncontrollable" if dual else "unobservable"
        raise ValueError(
            f"({names[0]}, {names[2]}): {what} — mode(s) {_fmt(bad)} on the {where} are {how} from "
            f"{names[2]}, so no stabilising Riccati solution exists (PBH test on the balanced data)"
        )


def solve_continuous_are(a, b, q, r, *, names=("a", "b", "q", "r"), dual: bool = False) -> jax.Array:
    """Stabilising (else maximal) solution ``X`` of ``Aᵀ X + X A − X B R⁻¹ Bᵀ X + Q = 0``.

    Args:
        a: ``(n, n)``; b: ``(n, m)``; q: ``(n, n)`` symmetric (may be indefinite); r: ``(m, m)``
            symmetric positive definite (a scalar is accepted for ``m = 1``).
        names: argument names used in error messages (callers such as :func:`lqr` pass theirs).
        dual: the inputs are a filter's ``(Aᵀ, Cᵀ, W, V)``: errors speak of detectability.

    Returns:
        ``X`` of shape ``(n, n)``, symmetric.  Differentiable (implicitly) in all four inputs.
        Concrete inputs: ``ValueError`` if no solution was found (naming uncontrollable unstable
        modes if any); :class:`MarginalStabilityWarning` if the closed loop is only marginally
        stable (see :func:`riccati_diagnostics`).  Under ``jit``/``vmap``: NaN instead of the error.
    """
    a, b, q, r = prepare_riccati_inputs(a, b, q, r, names)
    x = _care_jit(a, b, q, r)[0]
    _check_concrete_result(x, a, b, q, r, "the CARE", names, discrete=False, dual=dual)
    return x


def solve_discrete_are(a, b, q, r, *, names=("a", "b", "q", "r"), dual: bool = False) -> jax.Array:
    """Stabilising (else maximal) solution ``X`` of ``Aᵀ X A − X − Aᵀ X B (R + BᵀXB)⁻¹ Bᵀ X A + Q = 0``.

    Shapes and behaviour as :func:`solve_continuous_are`, except that ``r`` need only be positive
    semi-definite (``R + BᵀXB ≻ 0`` is required at the solution); stability is ``|λ| < 1``.
    """
    a, b, q, r = prepare_riccati_inputs(a, b, q, r, names, r_definite=False)
    x = _dare_jit(a, b, q, r)[0]
    _check_concrete_result(x, a, b, q, r, "the DARE", names, discrete=True, dual=dual)
    return x
