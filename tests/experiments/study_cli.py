"""Run a study through the CLI, as a user would, and read its results.json."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from tests.conftest import ROOT


def run_quick_study(name: str, out: Path, timeout: float = 900) -> dict:
    """``python -m experiments run NAME --quick --out OUT``; asserts success, returns results.json."""
    proc = subprocess.run([sys.executable, "-m", "experiments", "run", name, "--quick", "--out", str(out)],
                          capture_output=True, text=True, cwd=ROOT, timeout=timeout)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads((Path(out) / "results.json").read_text())
