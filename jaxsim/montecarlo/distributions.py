"""Distributions of uncertain parameters, and drawing one sample of a parameter space.

A *parameter space* is a pytree (usually a dict of named parameters) whose leaves are either
distributions from this module or fixed values (numbers, arrays).  :func:`draw` turns it into one
sample of the same structure.  Each distribution's parameters may be arrays; the sample then has
their broadcast shape.

* :class:`Normal` ``N(mean, std²)``;
* :class:`Uniform` on ``[low, high)``;
* :class:`LogNormal` ``exp(N(mu, sigma²))`` — ``mu``/``sigma`` are those of ``log X`` (NumPy's
  ``lognormal(mean, sigma)``, SciPy's ``lognorm(s=sigma, scale=exp(mu))``);
* :class:`TruncatedNormal` ``N(mean, std²)`` conditioned on ``[low, high]`` — sampled by inverting
  the normal's log-survival function, so windows far out in a tail (10σ, 50σ, …) are sampled
  correctly (see :func:`standard_truncated_normal`);
* :class:`Deviation` — the seed papers' "nominal ± Δ": uniform on ``[nominal − Δ, nominal + Δ]``
  (``relative=False``) or on ``nominal·[1 − Δ, 1 + Δ]`` (``relative=True``, Δ a fraction: 0.2 = ±20 %).

The lower-case factories (:func:`normal`, :func:`uniform`, :func:`lognormal`,
:func:`truncated_normal`, :func:`deviation`) validate their arguments and raise ``ValueError``
naming the one at fault (``Normal.std: must be positive ...``); the classes themselves do not
validate (they are pytrees, rebuilt on every unflatten), but :func:`validate_space` — called by the
Monte-Carlo entry points — checks every distribution of a space before anything runs.  Each leaf of a space draws
from its own key,
``fold_in(key, crc32(path))`` with ``path`` the leaf's pytree path, so adding or removing a
parameter never changes the draws of the others.
"""

from __future__ import annotations

import math
import zlib
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from jax.scipy.special import log_ndtr, ndtri

from jaxsim.core.pytree import pytree_dataclass, static_field
from jaxsim.core.validation import is_concrete


def _check(cls: str, name: str, value: Any, ok: Any, what: str) -> None:
    if is_concrete(value) and not bool(np.all(ok)):
        raise ValueError(f"{cls}.{name}: must be {what}, got {np.asarray(value)!r}")


def _finite(cls: str, **values: Any) -> None:
    for name, v in values.items():
        if is_concrete(v):
            _check(cls, name, v, np.isfinite(np.asarray(v, float)), "finite")


class Distribution:
    """Base class: ``sample(key) -> array`` of shape :attr:`shape`; ``validate()`` raises ``ValueError``."""

    def sample(self, key: jax.Array) -> jax.Array:  # pragma: no cover - abstract
        raise NotImplementedError

    def validate(self) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    @property
    def shape(self) -> tuple[int, ...]:
        leaves = jax.tree_util.tree_leaves(self)
        return tuple(np.broadcast_shapes(*(np.shape(v) for v in leaves)))

    def describe(self) -> dict[str, Any]:
        """Type and parameter values (JSON-friendly), used in sweep fingerprints and reports."""
        fields = {k: np.asarray(v).tolist() for k, v in vars(self).items() if not k.startswith("_")}
        return {"type": type(self).__name__, **fields}


def _dtype() -> Any:
    return jnp.result_type(float)


@pytree_dataclass
class Normal(Distribution):
    """Normal ``N(mean, std²)``; ``std > 0``."""

    mean: Any = 0.0
    std: Any = 1.0

    def validate(self) -> None:
        _finite("Normal", mean=self.mean, std=self.std)
        _check("Normal", "std", self.std, np.asarray(self.std) > 0, "positive")

    def sample(self, key: jax.Array) -> jax.Array:
        return self.mean + self.std * jax.random.normal(key, self.shape, _dtype())


@pytree_dataclass
class Uniform(Distribution):
    """Uniform on ``[low, high)``; ``low < high``."""

    low: Any = 0.0
    high: Any = 1.0

    def validate(self) -> None:
        _finite("Uniform", low=self.low, high=self.high)
        _check(
            "Uniform",
            "high",
            self.high,
            np.asarray(self.high) > np.asarray(self.low),
            f"greater than low={np.asarray(self.low).tolist()!r}",
        )

    def sample(self, key: jax.Array) -> jax.Array:
        return jax.random.uniform(key, self.shape, _dtype(), self.low, self.high)


@pytree_dataclass
class LogNormal(Distribution):
    """``exp(N(mu, sigma²))``; ``mu``, ``sigma > 0`` are the mean and std of ``log X``."""

    mu: Any = 0.0
    sigma: Any = 1.0

    def validate(self) -> None:
        _finite("LogNormal", mu=self.mu, sigma=self.sigma)
        _check("LogNormal", "sigma", self.sigma, np.asarray(self.sigma) > 0, "positive")

    def sample(self, key: jax.Array) -> jax.Array:
        return jnp.exp(self.mu + self.sigma * jax.random.normal(key, self.shape, _dtype()))


_NEWTON_STEPS = 3
_LOG_2PI = math.log(2 * math.pi)  # Python floats keep float32 arithmetic in float32


def _log_pdf(x: jax.Array) -> jax.Array:
    return -0.5 * x * x - 0.5 * _LOG_2PI


def inverse_log_survival(log_p: jax.Array) -> jax.Array:
    """The standard normal quantile ``x`` with ``log P(Z > x) = log_p`` (``log_p ≤ 0``).

    For ``x < 0`` (``log_p > log ½``): ``x = Φ⁻¹(−expm1(log_p))``, exact to rounding.  For ``x ≥ 0``:
    a first guess ``−Φ⁻¹(e^{log_p})`` while ``e^{log_p}`` is a normal float, else the tail asymptote
    ``log P(Z > x) ≈ −x²/2 − log(x √(2π))``; then Newton steps on ``log P(Z > x)`` (concave in
    ``x``, so they converge from any start), which keep the answer accurate where ``e^{log_p}``
    underflows (beyond ≈ 37σ in float64).
    """
    log_p = jnp.asarray(log_p)
    log_half = -math.log(2.0)
    lower = log_p > log_half
    x_lower = ndtri(-jnp.expm1(jnp.minimum(log_p, 0.0)))
    floor = float(np.log(jnp.finfo(log_p.dtype).tiny)) + 1.0
    lp = jnp.minimum(log_p, log_half)  # upper branch only; keeps its arithmetic finite
    y = -2.0 * lp
    x_asym = jnp.sqrt(y)
    for _ in range(2):
        x_asym = jnp.sqrt(y - _LOG_2PI - 2.0 * jnp.log(x_asym))
    x = jnp.where(lp > floor, -ndtri(jnp.exp(jnp.maximum(lp, floor))), x_asym)
    x = jnp.maximum(x, 0.0)
    for _ in range(_NEWTON_STEPS):
        log_sf = log_ndtr(-x)
        x = x + (log_sf - lp) * jnp.exp(log_sf - _log_pdf(x))  # d log S/dx = −φ/S
    return jnp.where(lower, x_lower, x)


def _log_diff(log_big: jax.Array, log_small: jax.Array) -> jax.Array:
    """``log(e^{log_big} − e^{log_small})`` for ``log_small ≤ log_big``."""
    return log_big + jnp.log(-jnp.expm1(log_small - log_big))


@jax.custom_jvp
def _truncated_by_survival(u: jax.Array, a: jax.Array, b: jax.Array) -> jax.Array:
    """``x`` in ``[a, b]`` with ``(S(a) − S(x)) / (S(a) − S(b)) = u``, ``S = 1 − Φ`` (log space)."""
    log_sa, log_sb = log_ndtr(-a), log_ndtr(-b)
    log_p = log_sa + jnp.log1p(u * jnp.expm1(log_sb - log_sa))
    return jnp.clip(inverse_log_survival(log_p), a, b)


@_truncated_by_survival.defjvp
def _truncated_by_survival_jvp(primals, tangents):
    # Implicit differentiation of (S(a) − S(x)) / (S(a) − S(b)) = u at fixed u (not through Newton):
    # ∂x/∂a = φ(a)/φ(x) · (S(x) − S(b))/(S(a) − S(b)),  ∂x/∂b = φ(b)/φ(x) · (S(a) − S(x))/(S(a) − S(b)).
    u, a, b = primals
    _, a_dot, b_dot = tangents
    x = _truncated_by_survival(u, a, b)
    log_sa, log_sb, log_sx = log_ndtr(-a), log_ndtr(-b), log_ndtr(-x)
    log_mass = _log_diff(log_sa, log_sb)
    dx_da = jnp.exp(_log_pdf(a) - _log_pdf(x) + _log_diff(log_sx, log_sb) - log_mass)
    dx_db = jnp.exp(_log_pdf(b) - _log_pdf(x) + _log_diff(log_sa, log_sx) - log_mass)
    return x, dx_da * a_dot + dx_db * b_dot


def standard_truncated_normal(key: jax.Array, a: Any, b: Any, shape: tuple[int, ...], dtype: Any) -> jax.Array:
    """Draws of ``N(0, 1)`` conditioned on ``[a, b]`` (``a < b``, either may be infinite), shape ``shape``.

    Inverse-CDF sampling through the log-survival function ``log S = log(1 − Φ)``:
    ``log S(x) = log S(a) + log(1 − u·(1 − S(b)/S(a)))`` with ``u ~ U[0, 1)``, inverted by
    :func:`inverse_log_survival`.  Windows with ``a + b < 0`` are mirrored into the upper tail first,
    so both tails are handled in the precise direction; no probability is formed outside log space,
    hence a window 50σ out (``S ≈ 1e-545``) is sampled as accurately as one at the centre.
    Derivatives in ``a`` and ``b`` are the implicit (reparametrisation) ones at fixed ``u``.
    """
    a = jnp.broadcast_to(jnp.asarray(a, dtype), shape)
    b = jnp.broadcast_to(jnp.asarray(b, dtype), shape)
    flip = (a + b) < 0  # NaN for (−inf, inf): False
    u = jax.random.uniform(key, shape, dtype)
    z = _truncated_by_survival(u, jnp.where(flip, -b, a), jnp.where(flip, -a, b))
    return jnp.where(flip, -z, z)


def _standardise(bound: Any, mean: Any, std: Any) -> jax.Array:
    """``(bound − mean)/std``; an infinite bound stays infinite with a zero derivative (not ∞·0)."""
    infinite = jnp.isinf(bound)
    finite = jnp.where(infinite, 0.0, bound)  # so that reverse mode never forms 0·∞
    return jnp.where(infinite, bound, (finite - mean) / std)


@pytree_dataclass
class TruncatedNormal(Distribution):
    """``N(mean, std²)`` restricted to ``[low, high]`` (``low < high``; either may be ±inf).

    Sampled by :func:`standard_truncated_normal`: accurate for windows anywhere, however far out in
    a tail (``jax.random.truncated_normal``, used before, returned ±1.8e308 for every draw of a
    one-sided window beyond ≈ 8σ and the far bound for a two-sided one).
    """

    mean: Any = 0.0
    std: Any = 1.0
    low: Any = -np.inf
    high: Any = np.inf

    def validate(self) -> None:
        _finite("TruncatedNormal", mean=self.mean, std=self.std)
        _check("TruncatedNormal", "std", self.std, np.asarray(self.std) > 0, "positive")
        if is_concrete((self.low, self.high)):
            lo, hi = np.asarray(self.low, float), np.asarray(self.high, float)
            _check("TruncatedNormal", "low", self.low, ~np.isnan(lo), "a number")
            _check("TruncatedNormal", "high", self.high, hi > lo, f"greater than low={lo.tolist()!r}")

    def sample(self, key: jax.Array) -> jax.Array:
        a = _standardise(self.low, self.mean, self.std)
        b = _standardise(self.high, self.mean, self.std)
        z = standard_truncated_normal(key, a, b, self.shape, _dtype())
        return jnp.clip(self.mean + self.std * z, self.low, self.high)


@pytree_dataclass
class Deviation(Distribution):
    """ "Nominal ± Δ": uniform on ``nominal ± delta`` or, with ``relative=True``, ``nominal·(1 ± delta)``.

    ``delta ≥ 0`` (``delta = 0`` gives the nominal value); relative deviations need ``delta < 1``
    so the sign of the parameter cannot flip.  ``relative`` must be a Python bool.
    """

    nominal: Any = 0.0
    delta: Any = 0.0
    relative: bool = static_field(default=False)

    def validate(self) -> None:
        if not isinstance(self.relative, (bool, np.bool_)):
            raise ValueError(f"Deviation.relative: must be True or False, got {self.relative!r}")
        _finite("Deviation", nominal=self.nominal, delta=self.delta)
        _check("Deviation", "delta", self.delta, np.asarray(self.delta) >= 0, "non-negative")
        if self.relative:
            _check(
                "Deviation",
                "delta",
                self.delta,
                np.asarray(self.delta) < 1,
                "below 1 for a relative deviation (a fraction: 0.2 means ±20 %)",
            )

    def sample(self, key: jax.Array) -> jax.Array:
        u = jax.random.uniform(key, self.shape, _dtype(), -1.0, 1.0)
        spread = self.delta * jnp.abs(self.nominal) if bool(self.relative) else self.delta
        return self.nominal + spread * u

    @property
    def low(self) -> Any:
        return self.nominal - (self.delta * np.abs(self.nominal) if bool(self.relative) else self.delta)

    @property
    def high(self) -> Any:
        return self.nominal + (self.delta * np.abs(self.nominal) if bool(self.relative) else self.delta)


def is_distribution(x: Any) -> bool:
    return isinstance(x, Distribution)


def _leaf_key(key: jax.Array, path: Any) -> jax.Array:
    tag = zlib.crc32(jax.tree_util.keystr(path).encode()) & 0xFFFFFFFF
    return jax.random.fold_in(key, np.uint32(tag))


def draw(space: Any, key: jax.Array) -> Any:
    """One sample of ``space``: every distribution leaf replaced by a draw, fixed values kept.

    Pure and vmappable over ``key``.  Fixed leaves are returned as arrays.
    """

    def one(path: Any, leaf: Any) -> Any:
        if is_distribution(leaf):
            return leaf.sample(_leaf_key(key, path))
        return jnp.asarray(leaf)

    return jax.tree_util.tree_map_with_path(one, space, is_leaf=is_distribution)


def describe_space(space: Any) -> Any:
    """JSON-friendly description of a space (distributions as dicts, fixed values as lists)."""

    def one(leaf: Any) -> Any:
        return leaf.describe() if is_distribution(leaf) else np.asarray(leaf).tolist()

    return jax.tree_util.tree_map(one, space, is_leaf=is_distribution)


def validate_space(space: Any) -> None:
    """Validate every distribution of ``space``; fixed leaves must be finite numbers."""
    for path, leaf in jax.tree_util.tree_flatten_with_path(space, is_leaf=is_distribution)[0]:
        if is_distribution(leaf):
            leaf.validate()
            continue
        arr = np.asarray(leaf)
        if arr.dtype.kind not in "biuf" or (arr.dtype.kind == "f" and not np.all(np.isfinite(arr))):
            raise ValueError(
                f"space{jax.tree_util.keystr(path)}: must be a finite number or a distribution, got {leaf!r}"
            )


def _made(dist: Distribution) -> Any:
    dist.validate()
    return dist


def normal(mean: Any = 0.0, std: Any = 1.0) -> Normal:
    """Validated :class:`Normal` (``std > 0``)."""
    return _made(Normal(mean, std))


def uniform(low: Any = 0.0, high: Any = 1.0) -> Uniform:
    """Validated :class:`Uniform` (``low < high``)."""
    return _made(Uniform(low, high))


def lognormal(mu: Any = 0.0, sigma: Any = 1.0) -> LogNormal:
    """Validated :class:`LogNormal` (``sigma > 0``; ``mu``, ``sigma`` of ``log X``)."""
    return _made(LogNormal(mu, sigma))


def truncated_normal(mean: Any = 0.0, std: Any = 1.0, low: Any = -np.inf, high: Any = np.inf) -> TruncatedNormal:
    """Validated :class:`TruncatedNormal` (``std > 0``, ``low < high``)."""
    return _made(TruncatedNormal(mean, std, low, high))


def deviation(nominal: Any, delta: Any, relative: bool = False) -> Deviation:
    """Validated :class:`Deviation`: ``nominal ± delta`` (or ``nominal·(1 ± delta)`` if ``relative``)."""
    return _made(Deviation(nominal, delta, relative))
