"""Reparametrisations: smooth bijections from unconstrained ``u`` to constrained parameters ``x``.

A tuner steps in ``u``-space, where every point is admissible, and the loss sees
``x = reparam.forward(u)``; so no gradient step, however large, can leave the constraint.  Each
reparametrisation has ``forward(u) -> x`` and ``inverse(x) -> u`` and is a frozen pytree dataclass
(bounds are array leaves, sizes and methods static fields):

* :class:`Positive` — ``x = floor + softplus(u)`` (or ``exp(u)``): ``x > floor``;
* :class:`Interval` — ``x = lo + (hi − lo)·sigmoid(u)``: ``lo < x < hi``;
* :class:`LogInterval` — ``log x = log lo + (log hi − log lo)·sigmoid(u)``: ``0 < lo < x < hi``,
  uniform steps in ``u`` move ``x`` by factors (gains, weights spanning decades);
* :class:`SortedBreakpoints` — ``x_i = lo + Σ_{j≤i} (min_gap + softplus(u_j))``: strictly
  increasing, ``x_0 > lo``, gaps ``≥ min_gap`` (fuzzy-set breakpoints stay ordered);
* :class:`SPDMatrix` — ``X = L Lᵀ + eps·I`` with ``L`` lower triangular, positive diagonal
  ``softplus(u_diag)``: symmetric positive definite (weights Q, R, covariances);
* :class:`Simplex` — ``x = softmax([u, 0])``: ``x > 0``, ``Σx = 1`` (mixing weights);
* :class:`Identity`.

In floating point the strict inequalities hold while ``|u|`` stays below about 30 (beyond that
``sigmoid``/``softplus`` round to their limits and ``x`` may touch a bound); use ``min_gap > 0`` or
``floor`` margins where touching matters.  ``L Lᵀ`` is positive definite in exact arithmetic but
can be numerically singular when ``L`` mixes tiny diagonals with large off-diagonals (|u| ≳ 5);
``SPDMatrix(n, eps)`` with ``eps > 0`` keeps every eigenvalue ``≥ eps``.

:func:`apply` and :func:`invert` map a pytree of reparametrisations over a matching pytree of
parameters; a reparametrisation placed over a sub-tree applies to each of its arrays, and ``None``
stands for :class:`Identity`.
"""

from __future__ import annotations

from typing import Any, Literal

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.core.pytree import pytree_dataclass, static_field
from jaxsim.core.validation import is_concrete


def softplus_inverse(y: jax.Array) -> jax.Array:
    """``u`` with ``softplus(u) = y`` for ``y > 0``; stable for tiny and large ``y``."""
    y = jnp.asarray(y, float) if not jnp.issubdtype(jnp.result_type(y), jnp.floating) else jnp.asarray(y)
    return y + jnp.log(-jnp.expm1(-y))


def _numeric(x: Any) -> np.ndarray | None:
    """``x`` as a float NumPy array when it holds concrete numbers (not tracers or placeholders)."""
    if x is None or not is_concrete(x):
        return None
    try:
        arr = np.asarray(x)
    except Exception:  # noqa: BLE001  (pytree placeholders during transformations)
        return None
    return arr.astype(float) if arr.dtype.kind in "fiub" else None


class Reparam:
    """Marker base class: ``forward(u) -> x``, ``inverse(x) -> u``, ``check(name, x)``."""

    def forward(self, u: jax.Array) -> jax.Array:
        raise NotImplementedError

    def inverse(self, x: jax.Array) -> jax.Array:
        raise NotImplementedError

    def check(self, name: str, x: Any) -> None:
        """Raise ``ValueError`` naming ``name`` when concrete ``x`` is outside the domain."""


@pytree_dataclass
class Identity(Reparam):
    """``x = u``."""

    def forward(self, u: jax.Array) -> jax.Array:
        return jnp.asarray(u)

    def inverse(self, x: jax.Array) -> jax.Array:
        return jnp.asarray(x)


@pytree_dataclass
class Positive(Reparam):
    """``x = floor + softplus(u)`` (``method="softplus"``) or ``floor + exp(u)``: ``x > floor``.

    ``exp`` suits scale parameters spanning decades (gains, covariances); ``softplus`` grows only
    linearly for large ``u``, so gradient steps stay proportionate.
    """

    floor: Any = 0.0
    method: Literal["softplus", "exp"] = static_field(default="softplus")

    def __post_init__(self) -> None:
        if self.method not in ("softplus", "exp"):
            raise ValueError(f"method: must be 'softplus' or 'exp', got {self.method!r}")
        f = _numeric(self.floor)
        if f is not None and not np.all(np.isfinite(f)):
            raise ValueError(f"floor: must be finite, got {self.floor!r}")

    def forward(self, u: jax.Array) -> jax.Array:
        u = jnp.asarray(u)
        return self.floor + (jax.nn.softplus(u) if self.method == "softplus" else jnp.exp(u))

    def inverse(self, x: jax.Array) -> jax.Array:
        y = jnp.asarray(x) - self.floor
        return softplus_inverse(y) if self.method == "softplus" else jnp.log(y)

    def check(self, name: str, x: Any) -> None:
        arr, f = _numeric(x), _numeric(self.floor)
        if arr is not None and f is not None and not np.all(arr > f):
            raise ValueError(f"{name}: must be > floor={self.floor!r} (Positive), got {x!r}")


def check_bounds(lo: Any, hi: Any, lo_name: str = "lo", hi_name: str = "hi") -> None:
    """Require finite ``lo < hi`` element-wise (concrete values only); error names both arguments."""
    a, b = _numeric(lo), _numeric(hi)
    if a is None or b is None:
        return
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
        raise ValueError(f"{lo_name}/{hi_name}: bounds must be finite, got {lo_name}={lo!r}, {hi_name}={hi!r}")
    try:
        ok = np.all(a < b)
    except ValueError:
        raise ValueError(f"{lo_name}/{hi_name}: shapes {a.shape} and {b.shape} do not broadcast") from None
    if not ok:
        raise ValueError(
            f"{lo_name}/{hi_name}: need {lo_name} < {hi_name} element-wise, got {lo_name}={lo!r}, {hi_name}={hi!r}"
        )


def check_inside(name: str, x: Any, lo: Any, hi: Any) -> None:
    """Require ``lo < x < hi`` (concrete values only)."""
    arr, a, b = _numeric(x), _numeric(lo), _numeric(hi)
    if arr is None or a is None or b is None:
        return
    if not np.all((arr > a) & (arr < b)):
        raise ValueError(f"{name}: must lie strictly inside the bounds ({lo!r}, {hi!r}), got {x!r}")


@pytree_dataclass
class Interval(Reparam):
    """``x = lo + (hi − lo)·sigmoid(u)``: ``lo < x < hi`` (bounds broadcast against ``u``)."""

    lo: Any
    hi: Any

    def __post_init__(self) -> None:
        check_bounds(self.lo, self.hi)

    def forward(self, u: jax.Array) -> jax.Array:
        return self.lo + (self.hi - self.lo) * jax.nn.sigmoid(jnp.asarray(u))

    def inverse(self, x: jax.Array) -> jax.Array:
        p = (jnp.asarray(x) - self.lo) / (self.hi - self.lo)
        return jnp.log(p) - jnp.log1p(-p)

    def check(self, name: str, x: Any) -> None:
        check_inside(name, x, self.lo, self.hi)


@pytree_dataclass
class LogInterval(Reparam):
    """``x = exp(log lo + (log hi − log lo)·sigmoid(u))``: ``0 < lo < x < hi``."""

    lo: Any
    hi: Any

    def __post_init__(self) -> None:
        check_bounds(self.lo, self.hi)
        a = _numeric(self.lo)
        if a is not None and not np.all(a > 0):
            raise ValueError(f"lo: LogInterval needs positive bounds, got lo={self.lo!r}")

    def forward(self, u: jax.Array) -> jax.Array:
        log_lo, log_hi = jnp.log(self.lo), jnp.log(self.hi)
        return jnp.exp(log_lo + (log_hi - log_lo) * jax.nn.sigmoid(jnp.asarray(u)))

    def inverse(self, x: jax.Array) -> jax.Array:
        log_lo, log_hi = jnp.log(self.lo), jnp.log(self.hi)
        p = (jnp.log(jnp.asarray(x)) - log_lo) / (log_hi - log_lo)
        return jnp.log(p) - jnp.log1p(-p)

    def check(self, name: str, x: Any) -> None:
        check_inside(name, x, self.lo, self.hi)


@pytree_dataclass
class SortedBreakpoints(Reparam):
    """``u`` ``(n,)`` → strictly increasing ``x`` ``(n,)``: ``x_0 > lo``, every gap ``≥ min_gap``.

    ``x_i = lo + Σ_{j≤i} (min_gap + softplus(u_j))`` — the cumulative softplus keeps fuzzy-set
    breakpoints ordered under any gradient step.
    """

    lo: Any = 0.0
    min_gap: Any = 0.0

    def __post_init__(self) -> None:
        g = _numeric(self.min_gap)
        if g is not None and not (np.all(np.isfinite(g)) and np.all(g >= 0)):
            raise ValueError(f"min_gap: must be finite and non-negative, got {self.min_gap!r}")

    def forward(self, u: jax.Array) -> jax.Array:
        return self.lo + jnp.cumsum(self.min_gap + jax.nn.softplus(jnp.asarray(u)), axis=-1)

    def inverse(self, x: jax.Array) -> jax.Array:
        x = jnp.asarray(x)
        prev = jnp.concatenate([jnp.broadcast_to(self.lo, x.shape[:-1] + (1,)), x[..., :-1]], axis=-1)
        return softplus_inverse(x - prev - self.min_gap)

    def check(self, name: str, x: Any) -> None:
        arr, lo, gap = _numeric(x), _numeric(self.lo), _numeric(self.min_gap)
        if arr is None or lo is None or gap is None:
            return
        if arr.ndim < 1:
            raise ValueError(f"{name}: breakpoints must be an array of shape (n,), got a scalar")
        d = np.diff(np.concatenate([np.broadcast_to(lo, arr.shape[:-1] + (1,)), arr], axis=-1), axis=-1)
        if not np.all(d > gap):
            raise ValueError(
                f"{name}: breakpoints must increase from lo={self.lo!r} with gaps > min_gap={self.min_gap!r}, got {x!r}"
            )


def _tril(n: int) -> tuple[np.ndarray, np.ndarray]:
    return np.tril_indices(n)


@pytree_dataclass
class SPDMatrix(Reparam):
    """``u`` ``(n(n+1)/2,)`` → symmetric positive-definite ``X = L Lᵀ + eps·I`` ``(n, n)``.

    ``L`` is lower triangular, filled row by row from ``u`` (NumPy's ``tril_indices`` order), with
    diagonal ``softplus(u_ii)``; ``eps ≥ 0`` is a floor on the eigenvalues of ``X``.
    """

    n: int = static_field()
    eps: Any = 0.0

    def __post_init__(self) -> None:
        if not isinstance(self.n, (int, np.integer)) or self.n < 1:
            raise ValueError(f"n: must be a positive integer, got {self.n!r}")
        e = _numeric(self.eps)
        if e is not None and not (np.all(np.isfinite(e)) and np.all(e >= 0)):
            raise ValueError(f"eps: must be finite and non-negative, got {self.eps!r}")

    def cholesky_factor(self, u: jax.Array) -> jax.Array:
        u = jnp.asarray(u)
        rows, cols = _tril(self.n)
        if u.shape[-1] != rows.size:
            raise ValueError(f"u: SPDMatrix({self.n}) needs {rows.size} entries, got shape {u.shape}")
        vals = jnp.where(rows == cols, jax.nn.softplus(u), u)
        return jnp.zeros(u.shape[:-1] + (self.n, self.n), u.dtype).at[..., rows, cols].set(vals)

    def forward(self, u: jax.Array) -> jax.Array:
        low = self.cholesky_factor(u)
        return low @ jnp.swapaxes(low, -1, -2) + self.eps * jnp.eye(self.n, dtype=low.dtype)

    def inverse(self, x: jax.Array) -> jax.Array:
        x = jnp.asarray(x)
        low = jnp.linalg.cholesky(x - self.eps * jnp.eye(self.n, dtype=x.dtype))
        rows, cols = _tril(self.n)
        vals = low[..., rows, cols]
        return jnp.where(rows == cols, softplus_inverse(jnp.maximum(vals, 1e-300)), vals)

    def check(self, name: str, x: Any) -> None:
        arr = _numeric(x)
        if arr is None:
            return
        if arr.shape[-2:] != (self.n, self.n):
            raise ValueError(f"{name}: expected an ({self.n}, {self.n}) matrix, got shape {arr.shape}")
        if not np.allclose(arr, np.swapaxes(arr, -1, -2), rtol=1e-10, atol=1e-12):
            raise ValueError(f"{name}: must be symmetric")
        eps = _numeric(self.eps)
        try:
            np.linalg.cholesky(arr - (0.0 if eps is None else eps) * np.eye(self.n))
        except np.linalg.LinAlgError:
            raise ValueError(f"{name}: must be positive definite with eigenvalues > eps={self.eps!r}") from None


@pytree_dataclass
class Simplex(Reparam):
    """Point of the probability simplex: ``x`` ``(n,)``, ``x > 0``, ``Σx = 1``.

    ``forward`` takes ``u`` of shape ``(n−1,)``: ``x = softmax([u, 0])`` (a bijection), or ``(n,)``:
    ``x = softmax(u)`` (invariant to a shift of ``u``).  ``inverse`` returns the ``(n−1,)`` form
    ``u_i = log x_i − log x_n`` by default, the zero-mean ``(n,)`` form with ``full=True``.
    """

    n: int = static_field()
    full: bool = static_field(default=False)

    def __post_init__(self) -> None:
        if not isinstance(self.n, (int, np.integer)) or self.n < 2:
            raise ValueError(f"n: must be an integer ≥ 2, got {self.n!r}")

    def forward(self, u: jax.Array) -> jax.Array:
        u = jnp.asarray(u)
        if u.ndim == 0 or u.shape[-1] not in (self.n - 1, self.n):
            raise ValueError(f"u: Simplex({self.n}) needs {self.n - 1} or {self.n} entries, got shape {u.shape}")
        if u.shape[-1] == self.n - 1:
            u = jnp.concatenate([u, jnp.zeros(u.shape[:-1] + (1,), u.dtype)], axis=-1)
        return jax.nn.softmax(u, axis=-1)

    def inverse(self, x: jax.Array) -> jax.Array:
        logx = jnp.log(jnp.asarray(x))
        if self.full:
            return logx - jnp.mean(logx, axis=-1, keepdims=True)
        return logx[..., :-1] - logx[..., -1:]

    def check(self, name: str, x: Any) -> None:
        arr = _numeric(x)
        if arr is None:
            return
        if arr.shape[-1:] != (self.n,) or not np.all(arr > 0) or not np.allclose(arr.sum(-1), 1.0, atol=1e-10):
            raise ValueError(f"{name}: must be ({self.n},) with positive entries summing to 1, got {x!r}")


def _is_reparam(node: Any) -> bool:
    return node is None or isinstance(node, Reparam)


def _map(reparams: Any, tree: Any, fn: Any) -> Any:
    if reparams is None:
        return tree

    def one(r: Any, sub: Any) -> Any:
        r = Identity() if r is None else r
        return jax.tree_util.tree_map(lambda leaf: fn(r, leaf), sub)

    try:
        return jax.tree_util.tree_map(one, reparams, tree, is_leaf=_is_reparam)
    except ValueError as err:
        raise ValueError(f"reparam: structure does not match the parameters ({err})") from None


def apply(reparams: Any, u: Any) -> Any:
    """``x = forward(u)`` leaf by leaf; ``reparams`` is a pytree prefix of ``u`` (None: identity)."""
    return _map(reparams, u, lambda r, leaf: r.forward(leaf))


def invert(reparams: Any, x: Any) -> Any:
    """``u = inverse(x)`` leaf by leaf (the inverse of :func:`apply`)."""
    return _map(reparams, x, lambda r, leaf: r.inverse(leaf))


def check_domain(reparams: Any, x: Any, name: str = "params0") -> None:
    """Raise ``ValueError`` naming ``name`` (and the offending leaf) if ``x`` is outside the domain."""
    if reparams is None:
        return

    def one(path: Any, r: Any, sub: Any) -> None:
        r = Identity() if r is None else r
        label = name + jax.tree_util.keystr(path)
        for p2, leaf in jax.tree_util.tree_leaves_with_path(sub):
            r.check(label + jax.tree_util.keystr(p2), leaf)

    jax.tree_util.tree_map_with_path(one, reparams, x, is_leaf=_is_reparam)
