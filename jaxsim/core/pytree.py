"""Frozen dataclasses registered as JAX pytrees.

``@pytree_dataclass`` makes a frozen dataclass whose fields are pytree children (arrays a user may
tune or vmap over) unless declared with :func:`static_field` (sizes, functions, flags), which become
hashable metadata — they are part of the jit cache key, never traced.
"""

from __future__ import annotations

import dataclasses
from typing import Any, Callable, TypeVar

import jax

T = TypeVar("T")


def static_field(default: Any = dataclasses.MISSING, **kwargs: Any) -> Any:
    """A dataclass field treated as static pytree metadata."""
    metadata = {**kwargs.pop("metadata", {}), "static": True}
    return dataclasses.field(default=default, metadata=metadata, **kwargs)


def pytree_dataclass(cls: type[T] | None = None) -> Any:
    """Decorator: ``dataclass(frozen=True)`` + ``jax.tree_util.register_dataclass``."""

    def wrap(c: type[T]) -> type[T]:
        dc = dataclasses.dataclass(frozen=True)(c)
        fields = dataclasses.fields(dc)
        meta = [f.name for f in fields if f.metadata.get("static", False)]
        data = [f.name for f in fields if not f.metadata.get("static", False)]
        return jax.tree_util.register_dataclass(dc, data_fields=data, meta_fields=meta)

    return wrap if cls is None else wrap(cls)


def replace(obj: T, **changes: Any) -> T:
    """``dataclasses.replace`` re-exported for frozen pytree dataclasses."""
    return dataclasses.replace(obj, **changes)  # type: ignore[type-var]


Fn = Callable[..., Any]
