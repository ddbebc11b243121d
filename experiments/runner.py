"""What a study is, and how the runner resolves its config, checks its claims and reports.

A study module defines ``STUDY = Study(...)``::

    STUDY = Study(
        name="dc_motor_pi",
        description="PI of a DC motor: gradient vs PSO on equal budgets, Monte Carlo over ±20 % in K and T",
        config=Config,                                   # frozen dataclass; its defaults are the "full" preset
        presets={"quick": dict(budget=64, mc_runs=200)},  # named presets (field -> value)
        claims=[Claim("itae_gradient", paper=0.05, rel_tol=0.1, source="...")],
        assumptions={"loss": assumption("ITAE + 1e-3·energy", "why")},
        run=run,                                         # run(cfg, progress) -> StudyResult
    )

The runner resolves the config **once**: the preset's values over the defaults, then every
``--set key=value`` on top; ``run`` receives that object, and ``results.json["config"]`` is exactly
it (``results.json["preset"]`` names the preset).  After the run, every :class:`Claim` is checked on
``result.metrics``: ``results.json["reproduction"]`` (and ``reproduction.csv``) has one row per claim,
``{metric, ours, paper, tolerance, verdict, source, note}`` with verdict ``"reproduced"``,
``"differs"`` or ``"not computed"`` (the run did not produce the metric, e.g. a quick preset).
"""

from __future__ import annotations

import dataclasses
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Sequence

from experiments.config_overrides import apply_overrides
from experiments.study import PerRun, StudyResult, assumption

__all__ = ["Claim", "PerRun", "Study", "StudyResult", "as_study", "assumption", "check_claims", "paper_facts"]

PAPERS = Path(__file__).parent / "papers"

VERDICTS = ("reproduced", "differs", "not computed")


@dataclass(frozen=True)
class Claim:
    """A number the study should reproduce: ``metric`` (a key of ``StudyResult.metrics``) against
    ``paper`` — the value claimed by the paper, or by an independent reference named in ``source``.

    Tolerance: ``rel_tol`` and/or ``abs_tol`` (reproduced iff ``|ours − paper| ≤ abs_tol +
    rel_tol·|paper|``), or ``band=(lo, hi)`` (reproduced iff ``lo ≤ ours ≤ hi``; e.g. a value the
    paper reads off a plot).  ``source``: where the claim is (paper, table, line); ``note``: free text.
    """

    metric: str
    paper: float
    rel_tol: float | None = None
    abs_tol: float | None = None
    band: tuple[float, float] | None = None
    source: str = ""
    note: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.metric, str) or not self.metric:
            raise ValueError(f"Claim.metric: must be a non-empty metric name, got {self.metric!r}")
        if self.band is None and self.rel_tol is None and self.abs_tol is None:
            raise ValueError(f"Claim {self.metric!r}: give rel_tol and/or abs_tol, or band")
        if self.band is not None and (self.rel_tol is not None or self.abs_tol is not None):
            raise ValueError(f"Claim {self.metric!r}: band excludes rel_tol/abs_tol")
        for name in ("rel_tol", "abs_tol"):
            v = getattr(self, name)
            if v is not None and not (math.isfinite(v) and v >= 0):
                raise ValueError(f"Claim {self.metric!r}.{name}: must be finite and non-negative, got {v!r}")
        if self.band is not None:
            lo, hi = self.band
            if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
                raise ValueError(f"Claim {self.metric!r}.band: need finite lo ≤ hi, got {self.band!r}")
        if not math.isfinite(float(self.paper)):
            raise ValueError(f"Claim {self.metric!r}.paper: must be finite, got {self.paper!r}")

    @property
    def tolerance(self) -> str:
        """The tolerance as text (``"rel 0.01"``, ``"abs 1e-09 + rel 0.01"``, ``"band [0.3, 0.5]"``)."""
        if self.band is not None:
            return f"band [{self.band[0]:g}, {self.band[1]:g}]"
        parts = []
        if self.abs_tol is not None:
            parts.append(f"abs {self.abs_tol:g}")
        if self.rel_tol is not None:
            parts.append(f"rel {self.rel_tol:g}")
        return " + ".join(parts)

    def verdict(self, ours: float | None) -> str:
        if ours is None or not math.isfinite(ours):
            return "not computed" if ours is None else "differs"
        if self.band is not None:
            return "reproduced" if self.band[0] <= ours <= self.band[1] else "differs"
        limit = (self.abs_tol or 0.0) + (self.rel_tol or 0.0) * abs(float(self.paper))
        return "reproduced" if abs(ours - float(self.paper)) <= limit else "differs"

    def row(self, metrics: dict[str, Any]) -> dict[str, Any]:
        value = metrics.get(self.metric)
        ours = None if value is None else float(value)
        return {
            "metric": self.metric,
            "ours": ours,
            "paper": float(self.paper),
            "tolerance": self.tolerance,
            "verdict": self.verdict(ours),
            "source": self.source,
            "note": self.note,
        }


def check_claims(claims: Sequence[Claim], metrics: dict[str, Any]) -> list[dict[str, Any]]:
    """One reproduction row per claim (see :class:`Claim`)."""
    return [c.row(metrics) for c in claims]


def paper_facts(study: str, folder: Path = PAPERS) -> tuple[list[Claim], dict[str, dict[str, Any]]]:
    """``(claims, assumptions)`` of a study from ``folder/<study>.toml``: ``[[claims]]`` tables with
    the fields of :class:`Claim` (``band`` as a two-element array) and ``[assumptions.<name>]`` tables
    with ``value`` and ``why`` — the paper's facts as data, beside the study's code."""
    path = Path(folder) / f"{study}.toml"
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, tomllib.TOMLDecodeError) as err:
        raise ValueError(f"paper facts of study {study!r}: cannot read {path}: {err}") from err
    claims = []
    for i, c in enumerate(data.get("claims", [])):
        unknown = set(c) - {f.name for f in dataclasses.fields(Claim)}
        if unknown:
            raise ValueError(f"{path}: claims[{i}] has unknown field(s) {', '.join(sorted(unknown))}")
        claims.append(Claim(**{**c, "band": tuple(c["band"]) if "band" in c else None}))
    assumptions = {}
    for name, a in data.get("assumptions", {}).items():
        if set(a) != {"value", "why"}:
            raise ValueError(f"{path}: assumptions.{name} must have exactly 'value' and 'why', got {sorted(a)}")
        assumptions[name] = assumption(a["value"], a["why"])
    return claims, assumptions


@dataclass(frozen=True)
class Study:
    """A study: see the module docstring.  ``per_run(config) -> PerRun`` (optional) enables
    ``python -m experiments sweep``."""

    name: str
    description: str
    config: type
    run: Callable[[Any, Callable[..., Any]], StudyResult]
    presets: dict[str, dict[str, Any]] = field(default_factory=dict)
    claims: Sequence[Claim] = ()
    assumptions: dict[str, dict[str, Any]] = field(default_factory=dict)
    per_run: Callable[[Any], PerRun] | None = None

    def __post_init__(self) -> None:
        if not dataclasses.is_dataclass(self.config):
            raise ValueError(f"study {self.name!r}: config must be a dataclass, got {self.config!r}")
        names = {f.name for f in dataclasses.fields(self.config)}
        if "quick" in names:
            raise ValueError(f"study {self.name!r}: no `quick` field in the config; declare a 'quick' preset")
        if "full" in self.presets:
            raise ValueError(f"study {self.name!r}: 'full' is the config's defaults, not a preset to declare")
        for preset, values in self.presets.items():
            unknown = sorted(set(values) - names)
            if unknown:
                raise ValueError(
                    f"study {self.name!r}: preset {preset!r} sets unknown config field(s) {', '.join(unknown)}"
                )
        for c in self.claims:
            if not isinstance(c, Claim):
                raise ValueError(f"study {self.name!r}: claims must be Claim objects, got {type(c).__name__}")

    @property
    def preset_names(self) -> tuple[str, ...]:
        return ("full", *self.presets)

    def resolve(self, preset: str | None = None, overrides: Sequence[str] = ()) -> tuple[str, Any]:
        """``(preset name, config)``: the preset over the defaults, then ``key=value`` overrides."""
        preset = "full" if preset is None else preset
        if preset not in self.preset_names:
            raise ValueError(
                f"--preset {preset}: unknown preset of study {self.name!r}; known: {', '.join(self.preset_names)}"
            )
        config = self.config()
        if preset != "full":
            config = dataclasses.replace(config, **self.presets[preset])
        return preset, apply_overrides(config, list(overrides))

    def default_config(self, quick: bool = False) -> Any:
        """The full config, or the quick preset's."""
        return self.resolve("quick" if quick and "quick" in self.presets else None)[1]

    def finalize(self, result: StudyResult, preset: str) -> tuple[StudyResult, dict[str, Any]]:
        """The result with the study's assumptions merged in (the run's own win) and the reproduction
        table added as ``tables["reproduction"]``; and the extra ``results.json`` keys (preset,
        description, reproduction)."""
        rows = check_claims(self.claims, result.metrics)
        tables = dict(result.tables)
        if rows:
            tables["reproduction"] = rows
        merged = dataclasses.replace(result, assumptions={**self.assumptions, **result.assumptions}, tables=tables)
        extra = {"preset": preset, "description": self.description, "reproduction": rows}
        return merged, extra


def as_study(study: Any) -> Study:
    """``study`` if it is a :class:`Study`; anything else (a module's ``STUDY`` of another type) is refused."""
    if isinstance(study, Study):
        return study
    raise ValueError(f"STUDY: expected an experiments.runner.Study, got {type(study).__name__}")
