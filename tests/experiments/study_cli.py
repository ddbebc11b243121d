"""Run a study through the CLI, as a user would, and read its results.json."""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
from pathlib import Path

from tests.conftest import ROOT, child_env


def run_quick_study(name: str, out: Path, *extra: str, preset: str = "quick", timeout: float = 900) -> dict:
    """``python -m experiments run NAME --preset PRESET [EXTRA...] --out OUT``; asserts success, returns
    results.json.  ``extra``: further arguments, e.g. ``"--set", "budget=64"``."""
    proc = subprocess.run(
        [sys.executable, "-m", "experiments", "run", name, "--preset", preset, *extra, "--out", str(out)],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=timeout,
        env=child_env(),
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads((Path(out) / "results.json").read_text())


def recorded_config(config) -> dict:
    """A study's resolved ``config`` (a dataclass) as ``results.json`` records it: tuples become lists."""
    return json.loads(json.dumps(dataclasses.asdict(config)))


def assert_verdicts_follow_the_tolerances(res: dict, claims) -> None:
    """Every row of ``res["reproduction"]`` says ``reproduced`` exactly when the study's metric lies within
    its claim's band or ``abs_tol + rel_tol·|paper|`` (re-derived here, independently of the runner)."""
    m = res["metrics"]
    for row in res["reproduction"]:
        claim = next(c for c in claims if c.metric == row["metric"])
        ours = m[claim.metric]
        if claim.band is not None:
            ok = claim.band[0] <= ours <= claim.band[1]
        else:
            ok = abs(ours - claim.paper) <= (claim.abs_tol or 0.0) + (claim.rel_tol or 0.0) * abs(claim.paper)
        assert row["verdict"] == ("reproduced" if ok else "differs"), row
