"""Membership functions and the terms of a linguistic variable.

Each membership function (MF) is a pure function ``mu(x, *params)`` of a real input, broadcasting
over arrays, differentiable in ``x`` and every parameter (almost everywhere for the piecewise-linear
kinds: not at their corners).  Definitions and parameter order follow scikit-fuzzy's generators so
the two can be compared point for point:

============== ======================== ===================================================
kind           params                   mu(x)
============== ======================== ===================================================
triangular     a ≤ b ≤ c                0 outside (a, c), 1 at b, linear in between
trapezoidal    a ≤ b ≤ c ≤ d            0 outside (a, d), 1 on [b, c], linear in between
gaussian       mean, sigma > 0          exp(−(x − mean)² / (2 sigma²))
bell           width > 0, slope > 0, c  1 / (1 + |(x − c)/width|^(2 slope))   (generalised bell)
sigmoid        center, slope            1 / (1 + exp(−slope (x − center)))
piecewise      x_1 < … < x_k, y_1 … y_k linear interpolation through (x_j, y_j), constant
 _linear                                beyond the ends (so the end segments act as shoulders)
============== ======================== ===================================================

A degenerate edge (``a == b`` of a triangle) is a vertical edge: ``mu = 0`` left of it, ``1`` at it
(scikit-fuzzy's convention).  Shoulders are written as trapezoids whose outer corners lie beyond
the range of interest, or as piecewise-linear MFs.

:class:`Terms` holds the MFs of one linguistic variable: one ``kind`` for all its terms and a
parameter array ``params`` of shape ``(T, P)`` (``T`` terms, ``P`` parameters each).
"""

from __future__ import annotations

from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.pytree import pytree_dataclass, static_field
from jaxsim.core.validation import check_finite, is_concrete


def _safe_div(num: jax.Array, den: jax.Array) -> jax.Array:
    """``num/den`` where ``den != 0``; 0 elsewhere (with a finite gradient)."""
    ok = den != 0
    return jnp.where(ok, num / jnp.where(ok, den, 1.0), 0.0)


def triangular(x: Any, a: Any, b: Any, c: Any) -> jax.Array:
    """Triangle with feet ``a``, ``c`` and peak ``b`` (``a ≤ b ≤ c``)."""
    rising = jnp.where(x > a, _safe_div(x - a, b - a), 0.0)
    falling = jnp.where(x < c, _safe_div(c - x, c - b), 0.0)
    return jnp.where(x < b, rising, jnp.where(x > b, falling, 1.0))


def trapezoidal(x: Any, a: Any, b: Any, c: Any, d: Any) -> jax.Array:
    """Trapezoid with feet ``a``, ``d`` and plateau ``[b, c]`` (``a ≤ b ≤ c ≤ d``)."""
    rising = jnp.where(x > a, _safe_div(x - a, b - a), 0.0)
    falling = jnp.where(x < d, _safe_div(d - x, d - c), 0.0)
    return jnp.where(x < b, rising, jnp.where(x > c, falling, 1.0))


def gaussian(x: Any, mean: Any, sigma: Any) -> jax.Array:
    """Gaussian bell of centre ``mean`` and standard deviation ``sigma > 0``."""
    return jnp.exp(-((x - mean) ** 2) / (2.0 * sigma**2))


def bell(x: Any, width: Any, slope: Any, center: Any) -> jax.Array:
    """Generalised bell ``1/(1 + |(x − center)/width|^(2·slope))`` (``width, slope > 0``)."""
    z2 = ((x - center) / width) ** 2
    pos = z2 > 0
    power = jnp.where(pos, jnp.where(pos, z2, 1.0) ** slope, 0.0)  # |z|^(2 slope), grad-safe at 0
    return 1.0 / (1.0 + power)


def sigmoid(x: Any, center: Any, slope: Any) -> jax.Array:
    """Logistic ``1/(1 + exp(−slope·(x − center)))``; increasing for ``slope > 0``."""
    return jax.nn.sigmoid(slope * (x - center))


def piecewise_linear(x: Any, *params: Any) -> jax.Array:
    """Linear interpolation through ``(x_j, y_j)``; ``params = (x_1..x_k, y_1..y_k)``, ``x`` increasing."""
    k = len(params) // 2
    xs, ys = jnp.stack(params[:k]), jnp.stack(params[k:])
    return jnp.interp(jnp.asarray(x), xs, ys)


MF_FUNCTIONS: dict[str, Callable[..., jax.Array]] = {
    "triangular": triangular,
    "trapezoidal": trapezoidal,
    "gaussian": gaussian,
    "bell": bell,
    "sigmoid": sigmoid,
    "piecewise_linear": piecewise_linear,
}
N_PARAMS = {"triangular": 3, "trapezoidal": 4, "gaussian": 2, "bell": 3, "sigmoid": 2}


@pytree_dataclass
class Terms:
    """The ``T`` terms of one linguistic variable: ``params`` ``(T, P)`` of MFs of one ``kind``."""

    params: Any
    kind: str = static_field(default="triangular")

    @property
    def n_terms(self) -> int:
        return int(jnp.shape(self.params)[0])

    def __call__(self, x: Any) -> jax.Array:
        """Memberships of ``x`` (any shape ``S``) in every term: shape ``S + (T,)``."""
        p = jnp.asarray(self.params)
        if self.kind == "piecewise_linear":  # interpolation tables: one per term
            return jax.vmap(lambda row: piecewise_linear(x, *row), out_axes=-1)(p)
        return MF_FUNCTIONS[self.kind](jnp.asarray(x)[..., None], *(p[:, j] for j in range(p.shape[1])))


def _validate_row(kind: str, row: np.ndarray, t: int) -> None:
    where = f"params[{t}]"
    if kind == "triangular" and not (row[0] <= row[1] <= row[2]):
        raise ValueError(f"params: triangular term {t} needs a ≤ b ≤ c, got {where} = {row.tolist()}")
    if kind == "trapezoidal" and not (row[0] <= row[1] <= row[2] <= row[3]):
        raise ValueError(f"params: trapezoidal term {t} needs a ≤ b ≤ c ≤ d, got {where} = {row.tolist()}")
    if kind == "gaussian" and not row[1] > 0:
        raise ValueError(f"params: gaussian term {t} needs sigma > 0, got {where} = {row.tolist()}")
    if kind == "bell" and not (row[0] > 0 and row[1] > 0):
        raise ValueError(f"params: bell term {t} needs width > 0 and slope > 0, got {where} = {row.tolist()}")
    if kind == "piecewise_linear":
        k = row.size // 2
        xs, ys = row[:k], row[k:]
        if np.any(np.diff(xs) <= 0):
            raise ValueError(f"params: piecewise_linear term {t} needs increasing x, got {where} = {row.tolist()}")
        if np.any((ys < 0) | (ys > 1)):
            raise ValueError(f"params: piecewise_linear term {t} needs 0 ≤ y ≤ 1, got {where} = {row.tolist()}")


def terms(kind: str, params: Any) -> Terms:
    """Validated :class:`Terms`: ``params`` shape ``(T, P)`` (one row per term, order as in the table).

    Raises:
        ValueError: unknown ``kind``; wrong number of parameters; parameters out of order
            (a triangle's ``a > b``…), non-positive widths; NaN/inf.
    """
    if kind not in MF_FUNCTIONS:
        raise ValueError(f"kind: must be one of {sorted(MF_FUNCTIONS)}, got {kind!r}")
    arr = jnp.asarray(params, dtype=float)
    if arr.ndim != 2 or arr.shape[0] < 1:
        raise ValueError(f"params: expected shape (n_terms, n_params) with n_terms ≥ 1, got {arr.shape}")
    want = N_PARAMS.get(kind)
    if want is not None and arr.shape[1] != want:
        raise ValueError(f"params: a {kind} MF has {want} parameters, got {arr.shape[1]} per term")
    if kind == "piecewise_linear" and (arr.shape[1] % 2 or arr.shape[1] < 4):
        raise ValueError(f"params: piecewise_linear needs (x_1..x_k, y_1..y_k) with k ≥ 2, got {arr.shape[1]} values")
    check_finite("params", arr)
    if is_concrete(arr):
        host = np.asarray(arr)
        for t, row in enumerate(host):
            _validate_row(kind, row, t)
    return Terms(arr, kind)
