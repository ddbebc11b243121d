"""Progress bars for library loops (``progress=True`` on ``optim.tune``/``pso``, ``jaxsim.montecarlo``).

``progress`` may be ``False``/``None`` (silent), ``True`` (a tqdm bar on stderr) or a factory
``progress(total=, desc=, unit=, initial=, unit_scale=)`` returning an object with ``update(k)`` and
``close()`` (``experiments.progress.bar``, a tqdm class, a test double).
"""

from __future__ import annotations

import sys
from typing import Any


class NullBar:
    """A bar that shows nothing."""

    def update(self, *_: Any) -> None: ...

    def set_postfix_str(self, *_: Any, **__: Any) -> None: ...

    def close(self) -> None: ...


def progress_bar(progress: Any, *, total: int, desc: str, unit: str, initial: int = 0, unit_scale: bool = False) -> Any:
    """The bar ``progress`` asks for (see the module docstring)."""
    if progress is None or progress is False:
        return NullBar()
    if progress is True:
        from tqdm.auto import tqdm

        return tqdm(
            total=total,
            desc=desc,
            unit=unit,
            initial=initial,
            unit_scale=unit_scale,
            file=sys.stderr,
            dynamic_ncols=True,
        )
    if not callable(progress):
        raise ValueError(f"progress: must be a bool or a bar factory, got {type(progress).__name__}")
    return progress(total=total, desc=desc, unit=unit, initial=initial, unit_scale=unit_scale)


def postfix(bar: Any, text: str) -> None:
    """Show ``text`` beside the bar when it supports it (tqdm does)."""
    setter = getattr(bar, "set_postfix_str", None)
    if setter is not None:
        setter(text, refresh=False)
