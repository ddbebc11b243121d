"""Arithmetic-operation tally of a JAX function, read from its jaxpr (seed 004 part 4 §B4, Table 1).

:func:`count_operations` traces ``fn(*args)`` and walks the jaxpr (into nested ``jit``, custom-JVP and
``scan`` bodies, the latter times their length), adding up *element* operations on real
(floating-point) values by category — integer index arithmetic is not counted:

* ``mul``: ``mul``, ``div``, ``integer_pow`` (``x^k`` as ``k − 1`` products), ``square``, and the
  products of a ``dot_general`` (``M·N·K``);
* ``add``: ``add``, ``sub``, the sums of a ``dot_general`` (``M·N·(K − 1)``), ``reduce_sum`` and
  ``cumsum``;
* ``exp``, ``log``, ``compare`` (``lt``, ``le``, ``gt``, ``ge``, ``eq``, ``ne``, ``max``, ``min`` of
  real operands),
  ``sort`` (number of sort calls) and ``sort_elements``;
* calls named in ``opaque`` (e.g. ``{"map_lookup": "interpolation"}``, and by default the random
  draws ``_normal`` → ``gaussian``, ``_uniform`` → ``uniform``) count their output elements in their
  category and are not entered.

A ``while`` loop body is counted once and reported in ``while_loops`` (its trip count is unknown).
"""

from __future__ import annotations

from collections import Counter
from typing import Any, Callable

import jax
import jax.extend.core as jex
import numpy as np

DEFAULT_OPAQUE = {"_normal": "gaussian", "_uniform": "uniform"}
_MUL = {"mul", "div", "square"}
_ADD = {"add", "sub", "add_any"}
_CMP = {"lt", "le", "gt", "ge", "eq", "ne", "max", "min"}


def _size(aval: Any) -> int:
    return int(np.prod(aval.shape)) if hasattr(aval, "shape") else 1


def _inexact(aval: Any) -> bool:
    try:
        return bool(np.issubdtype(aval.dtype, np.inexact))
    except (AttributeError, TypeError):  # PRNG key types
        return False


def _sub_jaxprs(params: dict) -> list:
    out = []
    for v in params.values():
        for item in v if isinstance(v, (tuple, list)) else (v,):
            if isinstance(item, jex.ClosedJaxpr):
                out.append(item.jaxpr)
            elif isinstance(item, jex.Jaxpr):
                out.append(item)
    return out


def _walk(jaxpr: Any, scale: int, opaque: dict[str, str], tally: Counter) -> None:
    for eqn in jaxpr.eqns:
        name = eqn.primitive.name
        size = _size(eqn.outvars[0].aval) if eqn.outvars else 0
        call = eqn.params.get("name")
        if call in opaque:
            tally[opaque[call]] += scale * sum(_size(v.aval) for v in eqn.outvars)
            continue
        real = bool(eqn.outvars) and _inexact(eqn.outvars[0].aval)
        if name in _CMP:
            if eqn.invars and _inexact(eqn.invars[0].aval):
                tally["compare"] += scale * size
        elif not real:
            pass
        elif name in _MUL:
            tally["mul"] += scale * size
        elif name == "integer_pow":
            tally["mul"] += scale * size * (abs(int(eqn.params["y"])) - 1)
        elif name in _ADD:
            tally["add"] += scale * size
        elif name in ("exp", "log"):
            tally[name] += scale * size
        elif name == "reduce_sum":
            tally["add"] += scale * (_size(eqn.invars[0].aval) - size)
        elif name == "cumsum":
            tally["add"] += scale * (size - size // max(1, eqn.invars[0].aval.shape[eqn.params["axis"]]))
        elif name == "sort":
            tally["sort"] += scale
            tally["sort_elements"] += scale * size
        elif name == "dot_general":
            (lc, _), _ = eqn.params["dimension_numbers"]
            k = int(np.prod([eqn.invars[0].aval.shape[i] for i in lc])) if lc else 1
            tally["mul"] += scale * size * k
            tally["add"] += scale * size * (k - 1)
        if name == "scan":
            _walk(eqn.params["jaxpr"].jaxpr, scale * int(eqn.params["length"]), opaque, tally)
            continue
        if name == "while":
            tally["while_loops"] += 1
        for sub in _sub_jaxprs(eqn.params):
            _walk(sub, scale, opaque, tally)


def count_operations(fn: Callable[..., Any], *args: Any, opaque: dict[str, str] | None = None) -> dict[str, int]:
    """Element-operation tally of ``fn(*args)`` by category (see the module docstring)."""
    ops = dict(DEFAULT_OPAQUE)
    ops.update(opaque or {})
    tally: Counter = Counter()
    _walk(jax.make_jaxpr(fn)(*args).jaxpr, 1, ops, tally)
    return dict(tally)
