"""Progress bars for long runs (tqdm on stderr); ``silent`` for tests and library use."""

from __future__ import annotations

import sys
from typing import Any, Iterable

from tqdm.auto import tqdm


def bar(iterable: Iterable[Any] | None = None, **kwargs: Any) -> Any:
    """A tqdm progress bar on stderr (``desc``, ``total``, ``unit`` as in tqdm)."""
    kwargs.setdefault("file", sys.stderr)
    kwargs.setdefault("dynamic_ncols", True)
    return tqdm(iterable, **kwargs)


def silent(iterable: Iterable[Any] | None = None, **kwargs: Any) -> Any:
    """Same interface as :func:`bar`, prints nothing."""
    kwargs["disable"] = True
    return tqdm(iterable, **kwargs)
