"""A content hash of a traced computation: what a sweep's checkpoint must match to be resumed.

:func:`jaxpr_hash` walks a :class:`jax.extend.core.ClosedJaxpr` (from :func:`jax.make_jaxpr`) and
hashes, in order: every equation's primitive and parameters (sub-jaxprs of ``jit``, ``scan``,
``cond``, ``while``, ``custom_jvp_call``, ... recursively), the abstract value (dtype, shape, weak
type) of every variable, the **values** of every literal and of every closed-over constant (NumPy or
JAX arrays, byte for byte: large arrays are not elided as they are in the printed jaxpr), and the
wiring of variables (numbered by first appearance).  It never reads source locations, names of the
Python frames, file paths or object addresses, so the same code traced on the same shapes gives the
same hash in every process and every run; a changed operation, constant or configuration value
closed over by the traced function changes it.

Not covered (documented limits): Python callables stored as equation parameters — the rules of
``custom_jvp``/``custom_vjp`` and host callbacks — are hashed by their qualified name only (the
derivative rules do not change what a forward run computes); and a JAX version that traces the same
code differently gives a different hash.
"""

from __future__ import annotations

import functools
import hashlib
import inspect
import re
from typing import Any

import jax
import numpy as np
from jax.extend import core as jcore

_ADDRESS = re.compile(r"\s+at\s+0x[0-9a-fA-F]+|0x[0-9a-fA-F]{6,}")


class _Hasher:
    def __init__(self) -> None:
        self._h = hashlib.sha256()

    def token(self, *parts: str) -> None:
        for p in parts:
            self._h.update(p.encode())
            self._h.update(b"\x00")

    def array(self, x: Any) -> None:
        if hasattr(x, "dtype") and jax.dtypes.issubdtype(x.dtype, jax.dtypes.prng_key):
            self.token("key", str(jax.random.key_impl(x)))
            x = jax.random.key_data(x)
        a = np.ascontiguousarray(np.asarray(x))
        self.token("array", a.dtype.str, repr(a.shape))
        self._h.update(a.tobytes())

    def hexdigest(self) -> str:
        return self._h.hexdigest()


def _is_function(x: Any) -> bool:
    return inspect.isroutine(x) or isinstance(x, functools.partial) or type(x).__name__ == "WrappedFun"


def _value(h: _Hasher, x: Any) -> None:
    """One equation parameter (recursively)."""
    if isinstance(x, jcore.ClosedJaxpr):
        _jaxpr(h, x.jaxpr, x.consts)
    elif isinstance(x, jcore.Jaxpr):
        _jaxpr(h, x, [])
    elif isinstance(x, (np.ndarray, np.generic, jax.Array)):
        h.array(x)
    elif x is None or isinstance(x, (bool, int, float, complex, str, bytes)):
        h.token(type(x).__name__, repr(x))
    elif isinstance(x, (tuple, list)):
        h.token(type(x).__name__, str(len(x)))
        for v in x:
            _value(h, v)
    elif isinstance(x, dict):
        h.token("dict", str(len(x)))
        for k in sorted(x, key=repr):
            h.token(repr(k))
            _value(h, x[k])
    elif _is_function(x):  # derivative rules, thunks, callbacks: by name (see module docstring)
        h.token("function", type(x).__name__, getattr(x, "__qualname__", ""))
    else:  # dtypes, enums, dimension numbers, meshes, shardings: their repr, addresses removed
        h.token(type(x).__name__, _ADDRESS.sub("", repr(x)))


def _jaxpr(h: _Hasher, jaxpr: jcore.Jaxpr, consts: Any) -> None:
    names: dict[Any, int] = {}

    def var(v: Any) -> None:
        if isinstance(v, jcore.Literal):
            h.token("literal", str(v.aval))
            h.array(v.val)
            return
        if v not in names:
            names[v] = len(names)
            h.token("new", str(v.aval))
        h.token("var", str(names[v]))

    h.token("jaxpr", str(len(jaxpr.constvars)), str(len(jaxpr.invars)), str(len(jaxpr.eqns)))
    for v, c in zip(jaxpr.constvars, consts):
        var(v)
        h.array(c)
    for v in jaxpr.constvars[len(consts) :]:  # an open jaxpr's constants: positions only
        var(v)
    for v in jaxpr.invars:
        var(v)
    for eqn in jaxpr.eqns:
        h.token("eqn", eqn.primitive.name, str(len(eqn.invars)), str(len(eqn.outvars)))
        for k in sorted(eqn.params):
            h.token("param", k)
            _value(h, eqn.params[k])
        for v in eqn.invars:
            var(v)
        for v in eqn.outvars:
            var(v)
    h.token("out", str(len(jaxpr.outvars)))
    for v in jaxpr.outvars:
        var(v)


def jaxpr_hash(closed: jcore.ClosedJaxpr) -> str:
    """SHA-256 (hex) of a closed jaxpr's operations, types, wiring, literals and constants' values."""
    if not isinstance(closed, jcore.ClosedJaxpr):
        raise ValueError(f"closed: expected a ClosedJaxpr (jax.make_jaxpr(f)(...)), got {type(closed).__name__}")
    h = _Hasher()
    _jaxpr(h, closed.jaxpr, closed.consts)
    return h.hexdigest()
