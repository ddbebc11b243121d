"""What a study is: a config dataclass, ``run(config, progress) -> StudyResult``, and a report.

A study module defines ``STUDY = Study(name, description, Config, run)``; the CLI discovers it.
``StudyResult`` holds everything the report writes: flat numeric ``metrics``, ``tables`` (name →
list of row dicts, written as CSV and into ``results.json``), ``assumptions`` (every value the paper
did not give: name → {"value", "why"}), and matplotlib ``figures`` (name → Figure, written as PNG).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any, Callable


@dataclass
class StudyResult:
    metrics: dict[str, float] = field(default_factory=dict)
    tables: dict[str, list[dict[str, Any]]] = field(default_factory=dict)
    assumptions: dict[str, dict[str, Any]] = field(default_factory=dict)
    figures: dict[str, Any] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)


@dataclass(frozen=True)
class Study:
    name: str
    description: str
    config_cls: type
    run: Callable[[Any, Callable[..., Any]], StudyResult]

    def default_config(self, quick: bool = False) -> Any:
        cfg = self.config_cls()
        if quick and any(f.name == "quick" for f in dataclasses.fields(cfg)):
            cfg = dataclasses.replace(cfg, quick=True)
        return cfg


def assumption(value: Any, why: str) -> dict[str, Any]:
    """One entry of ``StudyResult.assumptions``."""
    return {"value": value, "why": why}
