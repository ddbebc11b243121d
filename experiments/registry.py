"""Discovery of studies, lazily: a study is a module of the ``experiments`` package that defines ``STUDY``.

``get_study(NAME)`` imports ``experiments.NAME`` alone (the convention: a study lives in the module
of its name) and scans the others only if that module does not define it; ``all_studies()`` and
:func:`discover` import every module, each in its own ``try``, so a broken study breaks only itself
(``list`` shows it as broken, with its error).
"""

from __future__ import annotations

import importlib
import pkgutil
import traceback

import experiments
from experiments.runner import Study, as_study

_INFRASTRUCTURE = {
    "cli",
    "registry",
    "study",
    "report",
    "progress",
    "config_overrides",
    "benchmarks",
    "sweep_command",
    "output_folder",
    "runner",
    "stages",
    "figures",
    "report_html",
}


def study_modules() -> list[str]:
    """Names of the modules that may hold a study (no import)."""
    return sorted(
        m.name
        for m in pkgutil.iter_modules(experiments.__path__)
        if not m.name.startswith("_") and m.name not in _INFRASTRUCTURE
    )


def _load(module: str) -> Study | None:
    study = getattr(importlib.import_module(f"experiments.{module}"), "STUDY", None)
    return None if study is None else as_study(study)


def discover() -> tuple[dict[str, Study], dict[str, str]]:
    """``(studies, broken)``: name → :class:`Study` for every module that imports, and module → the
    last line of its error for every module that does not."""
    found: dict[str, Study] = {}
    broken: dict[str, str] = {}
    for module in study_modules():
        try:
            study = _load(module)
        except Exception as exc:  # noqa: BLE001  (any failure of one study must not hide the others)
            broken[module] = traceback.format_exception_only(exc)[-1].strip()
            continue
        if study is None:
            continue
        if study.name in found:
            raise RuntimeError(f"two studies are named {study.name!r}")
        found[study.name] = study
    return dict(sorted(found.items())), broken


def all_studies() -> dict[str, Study]:
    """Name → :class:`Study` of every study that imports, sorted by name."""
    return discover()[0]


def get_study(name: str) -> Study:
    """The study ``name``: its own module is imported first, alone."""
    if name in study_modules():
        study = _load(name)  # an error here is this study's own: let it show
        if study is not None and study.name == name:
            return study
    studies, broken = discover()
    if name not in studies:
        hint = f"; broken modules: {', '.join(broken)}" if broken else ""
        raise ValueError(f"NAME: unknown study {name!r}; known: {', '.join(studies) or 'none'}{hint}")
    return studies[name]
