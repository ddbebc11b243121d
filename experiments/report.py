"""Write a :class:`~experiments.study.StudyResult` to an output folder.

``DIR/results.json`` (keys ``study``, ``config``, ``assumptions``, ``metrics``, ``tables``,
``notes``), one CSV per table and one PNG per figure.  Non-finite numbers in tables are written as
the strings ``"inf"``, ``"-inf"``, ``"nan"`` so the JSON stays standard.
"""

from __future__ import annotations

import csv
import dataclasses
import json
import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from experiments.study import StudyResult


def _plain(x: Any) -> Any:
    if isinstance(x, dict):
        return {str(k): _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    if isinstance(x, (np.ndarray,)) or hasattr(x, "__array__") and not isinstance(x, (str, bytes)):
        arr = np.asarray(x)
        return _plain(arr.item()) if arr.ndim == 0 else _plain(arr.tolist())
    if isinstance(x, (np.bool_, bool)):
        return bool(x)
    if isinstance(x, (np.integer, int)):
        return int(x)
    if isinstance(x, (np.floating, float)):
        v = float(x)
        return v if math.isfinite(v) else ("nan" if math.isnan(v) else ("inf" if v > 0 else "-inf"))
    return x


def _atomic_write_text(path: Path, text: str) -> None:
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text)
    os.replace(tmp, path)


def write_report(study_name: str, config: Any, result: StudyResult, out_dir: str | Path) -> Path:
    """Write everything; returns the path of ``results.json``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    for name, value in result.metrics.items():
        if not isinstance(value, (int, float, np.integer, np.floating)) or isinstance(value, bool):
            raise TypeError(f"metrics[{name!r}]: must be a number, got {type(value).__name__}")
    payload = {
        "study": study_name,
        "config": _plain(dataclasses.asdict(config)),
        "assumptions": _plain(result.assumptions),
        "metrics": _plain(result.metrics),
        "tables": _plain(result.tables),
        "notes": list(result.notes),
    }
    for name, rows in result.tables.items():
        if not rows:
            continue
        header = list(rows[0].keys())
        for row in rows[1:]:
            header += [k for k in row if k not in header]
        path = out / f"{name}.csv"
        with open(path.with_name(path.name + ".tmp"), "w", newline="") as fh:
            writer = csv.DictWriter(fh, fieldnames=header)
            writer.writeheader()
            for row in rows:
                writer.writerow(_plain(row))
        os.replace(path.with_name(path.name + ".tmp"), path)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    for name, fig in result.figures.items():
        fig.savefig(out / f"{name}.png", dpi=120, bbox_inches="tight")
        plt.close(fig)
    results_path = out / "results.json"
    _atomic_write_text(results_path, json.dumps(payload, indent=2, allow_nan=False) + "\n")
    return results_path
