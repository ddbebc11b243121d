"""A small module-level cache of compiled tuner functions, keyed on what the compiled code depends on.

:func:`optim.tune.tune` builds its step from closures (the loss, the optimiser, the
reparametrisation); a fresh closure is a fresh ``jax.jit`` cache entry, so without this cache every
``tune`` call traced and compiled again.  Keys are built by :func:`fingerprint`:

* numbers, strings, ``None`` by value; NumPy/JAX arrays by dtype, shape and bytes;
* pytrees (tuples, dicts, dataclasses registered as pytrees, optax states) by tree structure and
  the fingerprints of their leaves;
* functions by their code object, defaults, the values in their closure cells and the values of
  the module globals their code names (globals that are functions, classes or modules by identity),
  so two ``optax.adam(0.05)`` built by separate calls share a key while ``optax.adam(0.1)`` does not;
* :class:`ByIdentity`-wrapped objects by identity (:func:`callable_key`: how the tuner keys its
  loss and constraint functions — the same object, as ``jax.jit`` would);
* bound methods by their function and ``__self__`` (by its own ``==``/``hash``: a frozen
  dataclass by value, a :class:`~jaxsim.problem.Problem` by identity);
* anything else hashable as itself (identity unless it defines ``__eq__``); unhashable, or nested
  deeper than :data:`MAX_DEPTH`: :class:`Unkeyable` (the caller then does not cache).

The cache holds at most :data:`MAX_ENTRIES` entries, least recently used first out.  Its entries
hold the compiled functions and, through their closures, the loss they were built from: a strong
reference, bounded by the size (a weak key cannot work here, since the value refers to the key).
"""

from __future__ import annotations

import collections
import functools
import types
import weakref
from typing import Any, Callable

import jax
import numpy as np

MAX_ENTRIES = 32
"""Most compiled tuners kept (each holds its executables and its loss)."""

MAX_DEPTH = 12
"""Deepest nesting :func:`fingerprint` follows before giving up."""


class Unkeyable(Exception):
    """Raised by :func:`fingerprint` for objects it cannot key safely."""


_SCALARS = (type(None), bool, int, float, complex, str, bytes)


def _code_names(code: types.CodeType) -> set[str]:
    names = set(code.co_names)
    for const in code.co_consts:
        if isinstance(const, types.CodeType):
            names |= _code_names(const)
    return names


def _cell(cell: types.CellType, depth: int) -> Any:
    try:
        contents = cell.cell_contents
    except ValueError:  # an empty cell (a name assigned later in the enclosing scope)
        raise Unkeyable("an empty closure cell") from None
    return fingerprint(contents, depth)


def _function(fn: types.FunctionType, depth: int) -> tuple:
    cells = tuple(_cell(c, depth + 1) for c in fn.__closure__ or ())
    globs = []
    for name in sorted(_code_names(fn.__code__)):
        if name not in fn.__globals__:
            continue
        value = fn.__globals__[name]
        if isinstance(value, (types.FunctionType, types.ModuleType, type, types.BuiltinFunctionType)):
            globs.append((name, "id", id(value), value))
        else:
            globs.append((name, fingerprint(value, depth + 1)))
    return (
        "fn",
        fn.__code__,
        fingerprint(fn.__defaults__, depth + 1),
        fingerprint(fn.__kwdefaults__, depth + 1),
        cells,
        tuple(globs),
    )


def fingerprint(obj: Any, depth: int = 0) -> Any:
    """A hashable key that is equal for objects that compile to the same code (module docstring)."""
    if depth > MAX_DEPTH:
        raise Unkeyable("nested too deeply")
    if isinstance(obj, ByIdentity):
        return ("id", obj)
    if isinstance(obj, _SCALARS):
        return (type(obj).__name__, obj)
    if isinstance(obj, (np.ndarray, np.generic, jax.Array)):
        if isinstance(obj, jax.core.Tracer):
            raise Unkeyable("a traced value")
        a = np.asarray(obj)
        return ("array", a.dtype.str, a.shape, a.tobytes())
    if isinstance(obj, types.FunctionType):
        return _function(obj, depth)
    if isinstance(obj, types.MethodType):
        return ("method", fingerprint(obj.__func__, depth + 1), _hashable(obj.__self__))
    if isinstance(obj, functools.partial):
        return ("partial", fingerprint(obj.func, depth + 1), fingerprint(obj.args, depth + 1),
                fingerprint(obj.keywords, depth + 1))  # fmt: skip
    if isinstance(obj, (types.ModuleType, type, types.BuiltinFunctionType)):
        return ("id", obj)
    leaves, treedef = jax.tree_util.tree_flatten(obj)
    if not (len(leaves) == 1 and leaves[0] is obj):
        return ("tree", treedef, tuple(fingerprint(leaf, depth + 1) for leaf in leaves))
    return ("obj", _hashable(obj))


def _hashable(obj: Any) -> Any:
    try:
        hash(obj)
    except TypeError:
        raise Unkeyable(f"unhashable {type(obj).__name__}") from None
    return obj


class ByIdentity:
    """Wraps an object so that :func:`fingerprint` keys it by identity (equal only to itself)."""

    __slots__ = ("obj",)

    def __init__(self, obj: Any) -> None:
        self.obj = obj

    def __eq__(self, other: Any) -> bool:
        return isinstance(other, ByIdentity) and other.obj is self.obj

    def __hash__(self) -> int:
        return id(self.obj)


def callable_key(fn: Any) -> Any:
    """Key of a loss or constraint function: the object itself (identity, as ``jax.jit`` keys a
    function), a bound method by its function and ``__self__`` (so ``PIDTuning().loss`` built twice
    with equal settings shares the key), ``None`` by value."""
    if fn is None:
        return None
    if isinstance(fn, types.MethodType):
        owner = fn.__self__
        try:
            hash(owner)
        except TypeError:
            owner = ByIdentity(owner)
        return ("method", ByIdentity(fn.__func__), owner)
    return ByIdentity(fn)


_ALL_CACHES: "weakref.WeakSet[LRUCache]" = weakref.WeakSet()


class LRUCache:
    """``get_or_build(key, build)`` with at most ``size`` entries (least recently used evicted)."""

    def __init__(self, size: int = MAX_ENTRIES) -> None:
        self.size = size
        self._data: collections.OrderedDict[Any, Any] = collections.OrderedDict()
        _ALL_CACHES.add(self)

    def get_or_build(self, key: Any, build: Callable[[], Any]) -> Any:
        if key is None:
            return build()
        if key in self._data:
            self._data.move_to_end(key)
            return self._data[key]
        value = build()
        self._data[key] = value
        while len(self._data) > self.size:
            self._data.popitem(last=False)
        return value

    def clear(self) -> None:
        self._data.clear()

    def __len__(self) -> int:
        return len(self._data)


def key_or_none(*parts: Any) -> Any:
    """``fingerprint(parts)``, or ``None`` (do not cache) when some part cannot be keyed."""
    try:
        key = fingerprint(parts)
        hash(key)
        return key
    except (Unkeyable, TypeError, RecursionError):
        return None


def clear_all() -> None:
    """Empty every :class:`LRUCache` (the tuners' compiled functions): with ``jax.clear_caches()``,
    the next tuner call traces and compiles from scratch (a cold start, as in a new process)."""
    for cache in list(_ALL_CACHES):
        cache.clear()
