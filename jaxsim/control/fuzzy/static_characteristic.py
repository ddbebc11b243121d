"""Static characteristic ``u(e)`` of a single-input fuzzy controller and its three-section fit.

The paper (spec §1.2) analyses a fuzzy controller only through its static characteristic, which
it approximates by two linear sections and a saturation (:class:`~.characteristic.ThreeSection`).
:func:`static_characteristic` evaluates any single-input characteristic on a grid (a
:class:`~.inference.FuzzySystem` with one input, a ``ThreeSection``, any callable);
:func:`fit_three_section` finds the least-squares ``(a, b, c, d)``.

The fit uses odd symmetry (samples ``(e, u)`` are folded to ``(|e|, sign(e)·u)``).  For fixed
breakpoints ``(a, c)`` the model is linear in the levels ``(b, d)`` — ``u = b·φ_b(|e|) + d·φ_d(|e|)``
with hat-like basis functions — so the levels come from a linear least-squares solve and only
``(a, c)`` are searched: on a grid of candidate pairs, then refined by Nelder–Mead (variable
projection).  This is an offline NumPy/SciPy routine.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np
import scipy.optimize

from jaxsim.control.fuzzy.characteristic import ThreeSection


def static_characteristic(char: Callable[[jax.Array], jax.Array], e: Any) -> jax.Array:
    """``u(e)`` on the grid ``e`` ``(N,)`` for a single-input characteristic (vmapped)."""
    e = jnp.asarray(e, float)
    if e.ndim != 1:
        raise ValueError(f"e: expected shape (N,), got {e.shape}")
    return jax.vmap(lambda v: jnp.reshape(char(v), ()))(e)


@dataclass(frozen=True)
class ThreeSectionFit:
    """Result of :func:`fit_three_section`: the characteristic and its root-mean-square residual."""

    params: ThreeSection
    rms: float

    @property
    def abcd(self) -> tuple[float, float, float, float]:
        p = self.params
        return float(p.a), float(p.b), float(p.c), float(p.d)


def _basis(x: np.ndarray, a: float, c: float) -> np.ndarray:
    """``(N, 2)`` columns multiplying ``b`` and ``d`` at abscissae ``x ≥ 0``."""
    s = np.clip((x - a) / (c - a), 0.0, 1.0)
    phi_b = np.where(x <= a, x / a, 1.0 - s)
    return np.stack([phi_b, s], axis=-1)


def _levels(x: np.ndarray, y: np.ndarray, a: float, c: float) -> tuple[np.ndarray, float]:
    A = _basis(x, a, c)
    bd, *_ = np.linalg.lstsq(A, y, rcond=None)
    r = A @ bd - y
    return bd, float(np.mean(r**2))


def fit_three_section(e: Any, u: Any, *, n_candidates: int = 48) -> ThreeSectionFit:
    """Least-squares ``(a, b, c, d)`` of the odd three-section characteristic through samples ``(e, u)``.

    Args:
        e, u: ``(N,)`` samples of the characteristic (any signs; folded by odd symmetry).
        n_candidates: breakpoint candidates per axis for the initial grid over ``(a, c)``.

    Raises:
        ValueError: shapes differ, fewer than 4 samples with ``e ≠ 0``, or non-finite samples.
    """
    e, u = np.asarray(e, float).ravel(), np.asarray(u, float).ravel()
    if e.shape != u.shape:
        raise ValueError(f"u: expected the shape of e {e.shape}, got {u.shape}")
    if not (np.all(np.isfinite(e)) and np.all(np.isfinite(u))):
        raise ValueError("e/u: samples must be finite")
    keep = e != 0
    x, y = np.abs(e[keep]), np.sign(e[keep]) * u[keep]
    if x.size < 4:
        raise ValueError(f"e: need at least 4 samples with e ≠ 0, got {x.size}")
    lo, hi = float(x.min()), float(x.max())
    cand = np.linspace(lo, hi, n_candidates + 2)[1:-1]
    best = (np.inf, None)
    for i, a in enumerate(cand):
        for c in cand[i + 1 :]:
            _, mse = _levels(x, y, a, c)
            if mse < best[0]:
                best = (mse, (a, c))

    def objective(ac: np.ndarray) -> float:
        a, c = ac
        if not (0 < a < c <= hi * 1.5):
            return np.inf
        return _levels(x, y, a, c)[1]

    res = scipy.optimize.minimize(
        objective, np.array(best[1]), method="Nelder-Mead", options={"xatol": 1e-12, "fatol": 1e-16, "maxiter": 4000}
    )
    a, c = res.x if res.fun <= best[0] else np.array(best[1])
    (b, d), mse = _levels(x, y, a, c)
    f = lambda v: jnp.asarray(float(v))  # noqa: E731
    return ThreeSectionFit(ThreeSection(f(a), f(b), f(c), f(d)), float(np.sqrt(mse)))
