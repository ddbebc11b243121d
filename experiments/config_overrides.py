"""Parse ``--set key=value`` overrides against a config dataclass's field types."""

from __future__ import annotations

import dataclasses
import json
import typing
from typing import Any


def _convert(name: str, raw: str, current: Any, annotation: Any) -> Any:
    target = type(current) if current is not None else annotation
    try:
        if target is bool or annotation in (bool, "bool"):
            low = raw.strip().lower()
            if low in ("1", "true", "yes", "on"):
                return True
            if low in ("0", "false", "no", "off"):
                return False
            raise ValueError("expected true/false")
        if target is int or annotation in (int, "int"):
            return int(raw)
        if target is float or annotation in (float, "float"):
            return float(raw)
        if target is str or annotation in (str, "str"):
            return raw
        if isinstance(current, (tuple, list)):
            value = json.loads(raw if raw.strip().startswith("[") else f"[{raw}]")
            return type(current)(value)
        return json.loads(raw)
    except (ValueError, json.JSONDecodeError) as exc:
        raise ValueError(
            f"--set {name}={raw}: cannot convert to {getattr(target, '__name__', target)} ({exc})"
        ) from None


def apply_overrides(config: Any, overrides: list[str]) -> Any:
    """Return ``config`` with each ``key=value`` applied; unknown keys raise ``ValueError``."""
    fields = {f.name: f for f in dataclasses.fields(config)}
    try:
        hints = typing.get_type_hints(type(config))
    except Exception:  # noqa: BLE001 - forward refs we cannot resolve: fall back to the raw type
        hints = {}
    changes: dict[str, Any] = {}
    for item in overrides:
        if "=" not in item:
            raise ValueError(f"--set {item!r}: expected key=value")
        key, raw = item.split("=", 1)
        key = key.strip()
        if key not in fields:
            raise ValueError(f"--set {key}: unknown config key; known: {', '.join(sorted(fields))}")
        changes[key] = _convert(key, raw, getattr(config, key), hints.get(key, fields[key].type))
    return dataclasses.replace(config, **changes)
