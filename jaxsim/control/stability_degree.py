"""Controller design for maximum stability degree (метод максимальной степени устойчивости).

The stability degree of a closed loop is ``η = −max Re(λ)`` over its poles.  For a plant
``N(s)/D(s)`` and a controller structure whose gains enter the closed-loop characteristic polynomial
``c(s; k) = D(s)·Dc(s) + N(s)·Nc(s; k)`` affinely (``c = c₀ + M k``), :func:`max_stability_degree`

1. finds every *coalesced-root* candidate ``c(s; k) = c_lead·(s + η)ⁿ``: with ``m = n − 1`` free
   gains the left null vector ``w`` of ``M`` turns the matching conditions into one polynomial
   equation in ``η`` (``w·(c_lead·binom(n, j)·ηʲ − c₀ⱼ) = 0``), solved by its companion matrix;
2. maximises ``η(k)`` numerically (multi-start Nelder–Mead on the pole real parts) as an
   independent check, and keeps the coalesced candidate unless the search beats it.

The maximum need not be attained at a single point: for P control of a second-order plant every
gain at or above the double-root gain gives the same ``η`` (the poles become a complex pair with
that real part).  The coalesced-root design is then the smallest gain of that set — the
non-oscillatory boundary, and the design the fuzzy-PID paper uses (0.4 and 1.25).

This is an offline design routine (NumPy/SciPy, not traced); it returns plain floats.
"""

from __future__ import annotations

from dataclasses import dataclass
from math import comb
from typing import Sequence

import numpy as np
import scipy.optimize

from jaxsim.core.validation import check_finite

Structure = str  # "P", "PI", "PD", "PID"


def _trim(p: np.ndarray) -> np.ndarray:
    p = np.atleast_1d(np.asarray(p, float))
    nz = np.flatnonzero(np.abs(p) > 0)
    return p[nz[0] :] if nz.size else np.zeros(1)


def _check_poly(name: str, p: Sequence[float], what: str, why: str) -> np.ndarray:
    """A finite, not identically zero 1-D coefficient vector (descending powers of s)."""
    arr = np.atleast_1d(np.asarray(p, float))
    if arr.ndim != 1 or arr.size == 0:
        raise ValueError(f"{name}: expected a 1-D coefficient vector, got shape {arr.shape}")
    check_finite(name, arr)
    if not np.any(arr):
        raise ValueError(f"{name}: the plant {what} is identically zero (got {arr.tolist()}): {why}")
    return arr


def controller_polynomials(structure: Structure, gains: Sequence[float], tf: float = 0.0):
    """``(Nc, Dc)`` of the controller, descending powers; gains ordered as in ``gain_names``."""
    g = dict(zip(gain_names(structure), gains))
    kp, ki, kd = g.get("kp", 0.0), g.get("ki", 0.0), g.get("kd", 0.0)
    s = structure.upper()
    if s == "P":
        return np.array([kp]), np.array([1.0])
    if s == "PI":
        return np.array([kp, ki]), np.array([1.0, 0.0])
    if s == "PD":
        return np.array([kp * tf + kd, kp]), np.array([tf, 1.0]) if tf > 0 else np.array([1.0])
    if s == "PID":
        return np.array([kp * tf + kd, kp + ki * tf, ki]), (
            np.array([tf, 1.0, 0.0]) if tf > 0 else np.array([1.0, 0.0])
        )
    raise ValueError(f"structure: must be one of P, PI, PD, PID, got {structure!r}")


def gain_names(structure: Structure) -> tuple[str, ...]:
    names = {"P": ("kp",), "PI": ("kp", "ki"), "PD": ("kp", "kd"), "PID": ("kp", "ki", "kd")}
    try:
        return names[structure.upper()]
    except KeyError:
        raise ValueError(f"structure: must be one of P, PI, PD, PID, got {structure!r}") from None


def characteristic_polynomial(num, den, structure: Structure, gains, tf: float = 0.0) -> np.ndarray:
    """Closed-loop characteristic polynomial ``D·Dc + N·Nc`` (descending powers)."""
    nc, dc = controller_polynomials(structure, gains, tf)
    a = np.polymul(np.asarray(den, float), dc)
    b = np.polymul(np.asarray(num, float), nc)
    return _trim(np.polyadd(a, b))


def stability_degree(char_poly) -> float:
    """``η = −max Re(roots)``; positive for a stable polynomial."""
    roots = np.roots(_trim(char_poly))
    return float(-np.max(roots.real)) if roots.size else np.inf


def _affine_form(num, den, structure, tf, fixed: dict[str, float]):
    """``c(k_free) = c0 + M k_free``, all as equal-length coefficient vectors (descending)."""
    names = gain_names(structure)
    free = [n for n in names if n not in fixed]
    base = [fixed.get(n, 0.0) for n in names]

    def poly(gains):
        return characteristic_polynomial(num, den, structure, gains, tf)

    deg = max(len(poly([1.0 if n in free else fixed[n] for n in names])), len(poly(base)))

    def pad(p):
        return np.concatenate([np.zeros(deg - len(p)), p])

    c0 = pad(poly(base))
    cols = []
    for n in free:
        g = [fixed.get(m, 0.0) for m in names]
        g[names.index(n)] = 1.0
        cols.append(pad(poly(g)) - c0)
    m = np.stack(cols, axis=1) if cols else np.zeros((deg, 0))
    return c0, m, free


@dataclass(frozen=True)
class StabilityDegreeDesign:
    """Result of :func:`max_stability_degree`."""

    gains: dict[str, float]
    degree: float
    poles: np.ndarray
    char_poly: np.ndarray
    method: str  # "coalesced" or "search"
    search_degree: float  # best η the independent numerical search found


def coalesced_root_candidates(c0: np.ndarray, m: np.ndarray) -> list[tuple[np.ndarray, float]]:
    """All real ``(k, η)`` with ``c0 + M k = c_lead (s + η)ⁿ``, for ``m = n − 1`` free gains."""
    n = len(c0) - 1
    lead = c0[0]
    if np.any(m[0] != 0):
        raise ValueError("structure: the gains change the leading coefficient; not supported")
    if m.shape[1] != n - 1:
        return []
    mt = m[1:]  # rows j = 1..n
    w = np.linalg.svd(mt.T)[2][-1] if mt.shape[1] else np.ones(n)  # left null vector of mt
    # w · (lead·binom(n, j)·η^j − c0_j) = 0, a polynomial in η (ascending j → descending coeffs).
    asc = np.array([0.0] + [w[j - 1] * lead * comb(n, j) for j in range(1, n + 1)])
    asc[0] = -float(w @ c0[1:])
    roots = np.roots(asc[::-1])
    out = []
    for eta in roots:
        if abs(eta.imag) > 1e-9 * max(1.0, abs(eta.real)) or eta.real <= 0:
            continue
        eta = float(eta.real)
        target = np.array([lead * comb(n, j) * eta**j for j in range(1, n + 1)])
        k, *_ = np.linalg.lstsq(mt, target - c0[1:], rcond=None)
        if np.allclose(mt @ k + c0[1:], target, rtol=1e-9, atol=1e-12):
            out.append((k, eta))
    return out


def max_stability_degree(
    num: Sequence[float],
    den: Sequence[float],
    structure: Structure = "P",
    *,
    tf: float = 0.0,
    fixed: dict[str, float] | None = None,
    n_starts: int = 8,
    seed: int = 0,
    gain_scale: float = 10.0,
) -> StabilityDegreeDesign:
    """Gains of ``structure`` maximising the stability degree of the loop with plant ``num/den``.

    Args:
        num, den: plant transfer function, descending powers of s.
        structure: "P", "PI", "PD" or "PID" (parallel form; derivative filtered by ``tf`` seconds).
        tf: derivative filter time constant (PD/PID); 0 gives the ideal derivative.
        fixed: gains held at given values (e.g. ``{"kd": 0.1}``); the others are designed.
        n_starts, seed, gain_scale: the independent multi-start search (starts drawn log-uniformly
            in ``[1e-3, gain_scale]``).

    Raises:
        ValueError: unknown structure, ``num`` or ``den`` identically zero or not finite (a zero
            numerator leaves no loop to design: every gain gives the open-loop poles), or a design
            whose stability degree is unbounded (as many free gains as closed-loop poles: the
            poles can be moved arbitrarily far left).
    """
    num = _check_poly(
        "num", num, "numerator", "no controller gain reaches the closed-loop poles, so there is nothing to design"
    )
    den = _check_poly("den", den, "denominator", "not a transfer function")
    fixed = dict(fixed or {})
    names = gain_names(structure)
    for key in fixed:
        if key not in names:
            raise ValueError(f"fixed: {key!r} is not a gain of a {structure} controller {names}")
    if tf < 0 or not np.isfinite(tf):
        raise ValueError(f"tf: must be finite and non-negative, got {tf!r}")
    c0, m, free = _affine_form(num, den, structure, tf, fixed)
    n = len(c0) - 1
    if len(free) >= n and np.linalg.matrix_rank(m[1:]) >= n:
        raise ValueError(
            f"structure: {structure} with {len(free)} free gains places all {n} closed-loop poles; "
            "the stability degree is unbounded (fix a gain or add a derivative filter tf > 0)"
        )

    def full(k_free: np.ndarray) -> list[float]:
        it = iter(k_free)
        return [fixed[nm] if nm in fixed else float(next(it)) for nm in names]

    def degree_of(k_free: np.ndarray) -> float:
        return stability_degree(c0 + m @ np.asarray(k_free))

    rng = np.random.default_rng(seed)
    best_k, best_eta = None, -np.inf
    for _ in range(n_starts):
        start = np.exp(rng.uniform(np.log(1e-3), np.log(gain_scale), size=len(free)))
        res = scipy.optimize.minimize(
            lambda k: -degree_of(k),
            start,
            method="Nelder-Mead",
            options={"xatol": 1e-10, "fatol": 1e-12, "maxiter": 4000},
        )
        if -res.fun > best_eta:
            best_k, best_eta = res.x, -res.fun
    candidates = coalesced_root_candidates(c0, m)
    stable = [(k, eta) for k, eta in candidates if degree_of(k) > 0]
    if stable:
        k_c, eta_c = max(stable, key=lambda ke: ke[1])
        # Multiple roots are found by np.roots only to ~eps^(1/n): allow that much slack.
        if eta_c >= best_eta - 1e-4 * max(1.0, abs(eta_c)):
            gains = full(k_c)
            cp = c0 + m @ k_c
            return StabilityDegreeDesign(
                dict(zip(names, gains)), float(eta_c), np.roots(cp), cp, "coalesced", float(best_eta)
            )
    gains = full(best_k)
    cp = c0 + m @ best_k
    return StabilityDegreeDesign(dict(zip(names, gains)), float(best_eta), np.roots(cp), cp, "search", float(best_eta))
