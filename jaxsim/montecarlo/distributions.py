"""Distributions of uncertain parameters, and drawing one sample of a parameter space.

A *parameter space* is a pytree (usually a dict of named parameters) whose leaves are either
distributions from this module or fixed values (numbers, arrays).  :func:`draw` turns it into one
sample of the same structure.  Each distribution's parameters may be arrays; the sample then has
their broadcast shape.

* :class:`Normal` ``N(mean, std²)``;
* :class:`Uniform` on ``[low, high)``;
* :class:`LogNormal` ``exp(N(mu, sigma²))`` — ``mu``/``sigma`` are those of ``log X`` (NumPy's
  ``lognormal(mean, sigma)``, SciPy's ``lognorm(s=sigma, scale=exp(mu))``);
* :class:`TruncatedNormal` ``N(mean, std²)`` conditioned on ``[low, high]``;
* :class:`Deviation` — the seed papers' "nominal ± Δ": uniform on ``[nominal − Δ, nominal + Δ]``
  (``relative=False``) or on ``nominal·[1 − Δ, 1 + Δ]`` (``relative=True``, Δ a fraction: 0.2 = ±20 %).

The lower-case factories (:func:`normal`, :func:`uniform`, :func:`lognormal`,
:func:`truncated_normal`, :func:`deviation`) validate their arguments and raise ``ValueError``
naming the one at fault (``Normal.std: must be positive ...``); the classes themselves do not
validate (they are pytrees, rebuilt on every unflatten), but :func:`validate_space` — called by the
Monte-Carlo entry points — checks every distribution of a space before anything runs.  Each leaf of a space draws from its own key,
``fold_in(key, crc32(path))`` with ``path`` the leaf's pytree path, so adding or removing a
parameter never changes the draws of the others.
"""

from __future__ import annotations

import zlib
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

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
        _check("Uniform", "high", self.high, np.asarray(self.high) > np.asarray(self.low),
               f"greater than low={np.asarray(self.low).tolist()!r}")

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


@pytree_dataclass
class TruncatedNormal(Distribution):
    """``N(mean, std²)`` restricted to ``[low, high]`` (``low < high``; either may be ±inf)."""

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
            _check("TruncatedNormal", "high", self.high, hi > lo,
                   f"greater than low={lo.tolist()!r}")

    def sample(self, key: jax.Array) -> jax.Array:
        a = (self.low - self.mean) / self.std
        b = (self.high - self.mean) / self.std
        z = jax.random.truncated_normal(key, a, b, self.shape, _dtype())
        return jnp.clip(self.mean + self.std * z, self.low, self.high)


@pytree_dataclass
class Deviation(Distribution):
    """"Nominal ± Δ": uniform on ``nominal ± delta`` or, with ``relative=True``, ``nominal·(1 ± delta)``.

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
            _check("Deviation", "delta", self.delta, np.asarray(self.delta) < 1,
                   "below 1 for a relative deviation (a fraction: 0.2 means ±20 %)")

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
            raise ValueError(f"space{jax.tree_util.keystr(path)}: must be a finite number or a "
                             f"distribution, got {leaf!r}")


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
