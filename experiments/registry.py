"""Discovery of studies: every module of the ``experiments`` package that defines ``STUDY``."""

from __future__ import annotations

import importlib
import pkgutil

import experiments
from experiments.study import Study

_INFRASTRUCTURE = {"cli", "registry", "study", "report", "progress", "config_overrides", "benchmarks",
                   "sweep_command", "output_folder"}


def all_studies() -> dict[str, Study]:
    """Name → :class:`Study`, sorted by name."""
    found: dict[str, Study] = {}
    for mod in pkgutil.iter_modules(experiments.__path__):
        if mod.name.startswith("_") or mod.name in _INFRASTRUCTURE:
            continue
        module = importlib.import_module(f"experiments.{mod.name}")
        study = getattr(module, "STUDY", None)
        if isinstance(study, Study):
            if study.name in found:
                raise RuntimeError(f"two studies are named {study.name!r}")
            found[study.name] = study
    return dict(sorted(found.items()))


def get_study(name: str) -> Study:
    studies = all_studies()
    if name not in studies:
        raise ValueError(f"NAME: unknown study {name!r}; known: {', '.join(studies) or 'none'}")
    return studies[name]
