"""The pieces a study returns: :class:`StudyResult`, :func:`assumption` and :class:`PerRun`.

A study (:class:`experiments.runner.Study`) that can be swept (``python -m experiments sweep NAME``)
passes ``per_run=lambda config: PerRun(metric, nominal, uncertain)``: one run's metrics as a pure JAX
function of a key and a dict of named parameters.
``StudyResult`` holds everything the report writes: flat numeric ``metrics``, ``tables`` (name →
list of row dicts, written as CSV and into ``results.json``), ``assumptions`` (every value the paper
did not give: name → {"value", "why"}), and matplotlib ``figures`` (name → Figure, written as PNG).
"""

from __future__ import annotations

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
class PerRun:
    """What ``python -m experiments sweep`` needs from a study.

    ``metric(key, params) -> metrics pytree``: one run, pure JAX (jit/vmap-able); ``params`` maps every
    name of ``nominal`` (and of ``uncertain``) to a scalar; real leaves of the result get statistics,
    boolean leaves are events (probability with a Wilson interval).  ``nominal``: every parameter a
    ``--param`` may sweep, with its default value.  ``uncertain``: parameters drawn afresh for every
    run (``jaxsim.montecarlo`` distributions); they override ``nominal`` and cannot be swept.
    """

    metric: Callable[[Any, dict[str, Any]], Any]
    nominal: dict[str, float]
    uncertain: dict[str, Any] = field(default_factory=dict)


def assumption(value: Any, why: str) -> dict[str, Any]:
    """One entry of ``StudyResult.assumptions``."""
    return {"value": value, "why": why}
