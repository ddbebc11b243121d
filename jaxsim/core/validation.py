"""Argument checks at the public boundary.

Each check raises ``ValueError`` naming the offending argument.  Checks look at concrete values
only: when an argument is a JAX tracer (inside ``jit``/``vmap``/``grad``) the value-dependent part is
skipped and only the static shape is checked, so the same public function works both eagerly and
under transformations.
"""

from __future__ import annotations

import math
from typing import Any, Callable

import jax
import numpy as np


def is_concrete(x: Any) -> bool:
    """True when ``x`` holds values we can inspect (not a tracer)."""
    return not any(isinstance(leaf, jax.core.Tracer) for leaf in jax.tree_util.tree_leaves(x))


def _shape_matches(actual: tuple[int, ...], shape: tuple[int | None, ...]) -> bool:
    return len(actual) == len(shape) and all(s is None or s == a for s, a in zip(shape, actual))


def check_shape(name: str, x: Any, shape: tuple[int | None, ...]) -> None:
    """Require ``x.shape`` to match ``shape`` (``None`` matches any length)."""
    actual = tuple(np.shape(x))
    if not _shape_matches(actual, shape):
        dims = ["any" if s is None else str(s) for s in shape]
        want = "(" + ", ".join(dims) + ("," if len(dims) == 1 else "") + ")"
        raise ValueError(f"{name}: expected shape {want}, got {actual}")


def check_returns_shape(
    name: str, fn: Callable[..., Any], *args: Any, shape: tuple[int | None, ...]
) -> jax.ShapeDtypeStruct:
    """Require ``fn(*args)`` to return one array of shape ``shape``; return its shape and dtype.

    ``fn`` is traced abstractly (``jax.eval_shape``: nothing is computed), so this is cheap and works
    on tracers too.  ``name`` says which function is at fault, e.g. ``"plant 'trms': output(params, x)"``;
    the error reads ``"{name} returns shape (2,), expected (1,)"``.
    """
    out = jax.eval_shape(fn, *args)
    if not isinstance(out, jax.ShapeDtypeStruct):
        raise ValueError(f"{name} returns {type(out).__name__}, expected one array of shape {shape}")
    if not _shape_matches(tuple(out.shape), shape):
        raise ValueError(f"{name} returns shape {tuple(out.shape)}, expected {tuple(shape)}")
    return out


def check_finite(name: str, x: Any) -> None:
    """Require every leaf of ``x`` to be finite (no NaN or inf)."""
    if not is_concrete(x):
        return
    for leaf in jax.tree_util.tree_leaves(x):
        arr = np.asarray(leaf)
        if arr.dtype.kind in "fc" and not np.all(np.isfinite(arr)):
            raise ValueError(f"{name}: must be finite, got {arr!r}")


def check_positive(name: str, x: Any, *, allow_zero: bool = False) -> None:
    """Require ``x`` finite and > 0 (or ≥ 0 with ``allow_zero``) element-wise."""
    check_finite(name, x)
    if not is_concrete(x):
        return
    arr = np.asarray(x)
    bad = arr < 0 if allow_zero else arr <= 0
    if np.any(bad):
        rel = "non-negative" if allow_zero else "positive"
        raise ValueError(f"{name}: must be {rel}, got {arr!r}")


def check_real(name: str, x: Any) -> None:
    """Require a real numeric dtype (bool, integer or float; not complex).  Dtypes are static, so
    this check also runs on tracers."""
    dtype = np.dtype(x.dtype) if hasattr(x, "dtype") else np.asarray(x).dtype
    if dtype.kind not in "biuf":
        raise ValueError(f"{name}: must be real-valued, got dtype {dtype}")


def _static_real(name: str, x: Any, what: str) -> float:
    """``x`` as a ``float`` if it is a concrete real scalar (not a bool); else ``ValueError`` saying
    it must be ``what``."""
    if not is_concrete(x):
        raise ValueError(f"{name}: must be {what} (static configuration), got a traced value")
    if isinstance(x, (bool, np.bool_)) or np.ndim(x) != 0 or np.asarray(x).dtype.kind not in "iuf":
        raise ValueError(f"{name}: must be {what}, got {x!r}")
    return float(x)


def check_positive_scalar(name: str, x: Any) -> float:
    """Require a real, finite, positive Python or NumPy scalar (not a bool); return it as ``float``.
    For static configuration (a jit-static threshold), so ``x`` must be concrete."""
    value = _static_real(name, x, "a real positive scalar")
    if not math.isfinite(value) or value <= 0.0:
        raise ValueError(f"{name}: must be positive and finite, got {x!r}")
    return value


def check_int(name: str, x: Any, low: int = 1, high: int | None = None) -> int:
    """Require an integer in ``[low, high]`` (``high=None``: no upper bound) and return it as ``int``.

    Accepted: Python and NumPy integers, and integral floats such as ``4.0`` or ``1e6``; rejected:
    bools, non-integral or non-finite numbers, arrays, traced values (sizes and counts are static).
    The message names ``name`` and says what was wanted: ``"a positive integer"`` for the default
    range, else ``"an integer"`` then the range.
    """
    positive = low == 1 and high is None
    what = "a positive integer" if positive else "an integer"
    if isinstance(x, (int, np.integer)) and not isinstance(x, (bool, np.bool_)):
        value = int(x)  # exact, also beyond 2**53
    else:
        real = _static_real(name, x, what)
        if not math.isfinite(real) or real != math.floor(real):
            raise ValueError(f"{name}: must be {what}, got {x!r}")
        value = int(real)
    if value < low or (high is not None and value > high):
        if positive:
            raise ValueError(f"{name}: must be a positive integer, got {x!r}")
        rng = f"an integer ≥ {low}" if high is None else f"in [{low}, {high}]"
        raise ValueError(f"{name}: must be {rng}, got {x!r}")
    return value


def check_positive_int(name: str, x: Any) -> int:
    """Require a positive integer (a Python or NumPy integer, or an integral float such as ``4.0``;
    not a bool); return it as ``int``.  For static sizes, so ``x`` must be concrete.
    (:func:`check_int` with its default range.)"""
    return check_int(name, x)


def check_probabilities(name: str, p: Any) -> None:
    """Require finite, non-negative entries summing to 1 along the last axis (a probability vector,
    or a row-stochastic matrix), to a tolerance of ``max(1e-10, 16 ε)`` for the input's float type.

    Shape-agnostic; values only when concrete.
    """
    check_finite(name, p)
    if not is_concrete(p):
        return
    raw = np.asarray(p)
    eps = np.finfo(raw.dtype).eps if raw.dtype.kind == "f" else np.finfo(float).eps
    arr = raw.astype(float)
    if np.any(arr < 0):
        raise ValueError(f"{name}: probabilities must be non-negative, got {raw!r}")
    sums = arr.sum(axis=-1)
    if not np.allclose(sums, 1.0, rtol=0.0, atol=max(1e-10, 16 * eps)):
        raise ValueError(f"{name}: probabilities must sum to 1 along the last axis, got sums {sums.tolist()}")


def check_period_multiple(name: str, period: float, base: float, base_name: str) -> int:
    """Require ``period`` to be a positive integer multiple of ``base``; return the ratio."""
    check_positive(name, period)
    check_positive(base_name, base)
    ratio = float(period) / float(base)
    n = int(round(ratio))
    if n < 1 or not math.isclose(ratio, n, rel_tol=1e-9, abs_tol=1e-9):
        raise ValueError(
            f"{name}: must be an integer multiple of {base_name}={base!r}, got {period!r} (ratio {ratio:.6g})"
        )
    return n


def check_square(name: str, m: Any) -> None:
    """Require a square 2-D matrix."""
    shape = np.shape(m)
    if len(shape) != 2 or shape[0] != shape[1]:
        raise ValueError(f"{name}: expected a square matrix, got shape {tuple(shape)}")


def check_symmetric(name: str, m: Any) -> None:
    """Require a symmetric matrix to within ``100·eps·‖m‖₁`` (the rule of SciPy's Riccati solvers,
    which the toolkit's Riccati solvers share); values only when concrete.  For a covariance with a
    relative tolerance use :func:`check_covariance`."""
    if not is_concrete(m):
        return
    arr = np.asarray(m)
    tol = 100 * np.spacing(max(np.linalg.norm(arr, 1), np.finfo(float).tiny))
    if np.linalg.norm(arr - arr.T, 1) > tol:
        raise ValueError(f"{name}: must be symmetric, got {arr!r}")


def _symmetric_eigenvalues(m: Any) -> np.ndarray:
    arr = np.asarray(m)
    return np.linalg.eigvalsh(0.5 * (arr + arr.T))


def check_positive_definite(name: str, m: Any) -> None:
    """Require the symmetric part of ``m`` positive definite: smallest eigenvalue above
    ``10³·eps·λ_max`` (a Riccati weight ``R ≻ 0``); values only when concrete."""
    if not is_concrete(m):
        return
    w = _symmetric_eigenvalues(m)
    if w.size and w[0] <= w[-1] * 1e3 * np.finfo(float).eps:
        raise ValueError(f"{name}: must be symmetric positive definite, eigenvalues {w!r}")


def check_positive_semidefinite(name: str, m: Any) -> None:
    """Require the symmetric part of ``m`` positive semi-definite: no eigenvalue below
    ``−10³·eps·max(|λ_max|, 1)`` (a Riccati weight ``Q ⪰ 0``); values only when concrete."""
    if not is_concrete(m):
        return
    w = _symmetric_eigenvalues(m)
    if w.size and w[0] < -1e3 * np.finfo(float).eps * max(abs(w[-1]), 1.0):
        raise ValueError(f"{name}: must be symmetric positive semi-definite, eigenvalues {w!r}")


def check_covariance(
    name: str, m: Any, n: int | None = None, *, rtol: float = 1e-8, definite: bool = False, purpose: str = ""
) -> None:
    """Require a symmetric positive semi-definite ``(n, n)`` matrix (or a stack ``(..., n, n)``);
    with ``definite``, positive definite (smallest eigenvalue > ``rtol·max|λ|``); ``purpose`` says
    why in the message (``"must be positive definite for <purpose>"``).

    Shape is always checked; symmetry (to ``rtol`` of the largest entry) and the sign of the
    smallest eigenvalue (≥ ``−rtol·max|λ|``) only when ``m`` is concrete.
    """
    shape = tuple(np.shape(m))
    if len(shape) < 2 or shape[-1] != shape[-2] or (n is not None and shape[-1] != n):
        want = "(n, n)" if n is None else f"({n}, {n})"
        raise ValueError(f"{name}: expected a covariance of shape {want}, got {shape}")
    check_finite(name, m)
    if not is_concrete(m):
        return
    arr = np.asarray(m, dtype=float)
    scale = max(float(np.max(np.abs(arr), initial=0.0)), np.finfo(float).tiny)
    asym = float(np.max(np.abs(arr - np.swapaxes(arr, -1, -2)), initial=0.0))
    if asym > rtol * scale:
        raise ValueError(f"{name}: must be symmetric (max |M − Mᵀ| = {asym:.3g})")
    eig = np.linalg.eigvalsh(arr)
    lo, tol = float(np.min(eig)), rtol * max(float(np.max(np.abs(eig))), np.finfo(float).tiny)
    if definite and lo <= tol:
        why = f" for {purpose}" if purpose else ""
        raise ValueError(f"{name}: must be positive definite{why} (smallest eigenvalue {lo:.6g})")
    if lo < -tol:
        raise ValueError(f"{name}: must be positive semi-definite (smallest eigenvalue {lo:.3g})")
