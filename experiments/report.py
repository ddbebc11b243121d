"""Write a :class:`~experiments.study.StudyResult` to an output folder.

``DIR/results.json`` (keys ``study``, ``config``, ``assumptions``, ``metrics``, ``tables``,
``notes``, and from the runner ``preset``, ``description``, ``reproduction``), one CSV per table
(``reproduction.csv`` among them) and one PNG per figure, each written atomically.  Non-finite numbers
in tables are written as the strings ``"inf"``, ``"-inf"``, ``"nan"`` so the JSON stays standard.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import json
import math
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


def report_file_names(result: StudyResult) -> list[str]:
    """Names of the files :func:`write_report` writes for ``result`` (``results.json`` first)."""
    return (
        ["results.json"]
        + [f"{name}.csv" for name, rows in result.tables.items() if rows]
        + [f"{name}.png" for name in result.figures]
    )


def _csv_bytes(rows: list[dict[str, Any]]) -> bytes:
    header = list(rows[0].keys())
    for row in rows[1:]:
        header += [k for k in row if k not in header]
    buf = io.StringIO(newline="")
    writer = csv.DictWriter(buf, fieldnames=header)
    writer.writeheader()
    for row in rows:
        writer.writerow(_plain(row))
    return buf.getvalue().encode()


def write_report(
    study_name: str, config: Any, result: StudyResult, out_dir: str | Path, extra: dict[str, Any] | None = None
) -> Path:
    """Write everything (files named by :func:`report_file_names`); returns the path of ``results.json``.

    ``extra``: further top-level keys of ``results.json`` (the runner's ``preset``, ``description``
    and ``reproduction``), written after ``study``.

    Every file is written atomically (temporary file, ``fsync``, rename), ``results.json`` last, so
    a reader never sees half a file.  The folder is created if needed; whether it may be written
    at all is the caller's question (:mod:`experiments.output_folder`).
    """
    from jaxsim.montecarlo.store import atomic_write_bytes  # not at import: `sweep --devices` sets up JAX first

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    for name, value in result.metrics.items():
        if not isinstance(value, (int, float, np.integer, np.floating)) or isinstance(value, bool):
            raise TypeError(f"metrics[{name!r}]: must be a number, got {type(value).__name__}")
    payload = {
        "study": study_name,
        **_plain(extra or {}),
        "config": _plain(dataclasses.asdict(config)),
        "assumptions": _plain(result.assumptions),
        "metrics": _plain(result.metrics),
        "tables": _plain(result.tables),
        "notes": list(result.notes),
    }
    for name, rows in result.tables.items():
        if rows:
            atomic_write_bytes(out / f"{name}.csv", _csv_bytes(rows))
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    for name, fig in result.figures.items():
        png = io.BytesIO()
        fig.savefig(png, format="png", dpi=120, bbox_inches="tight")
        plt.close(fig)
        atomic_write_bytes(out / f"{name}.png", png.getvalue())
    results_path = out / "results.json"
    atomic_write_bytes(results_path, (json.dumps(payload, indent=2, allow_nan=False) + "\n").encode())
    return results_path
