"""``python -m experiments report [DIR]``: one static HTML page over every study's results.

Every ``DIR/*/results.json`` (a ``run`` or ``sweep`` output) becomes one section: the description and
preset, the reproduction table (metric, ours, paper, tolerance, verdict, source; coloured by verdict),
the figures (the folder's PNGs, linked in place: relative paths, nothing copied), the config, the
assumptions with their reasons, and the metrics.  A summary table at the top counts the verdicts
per study.  The page is written atomically to ``DIR/report.html``; every ``<img src>`` and
``<a href>`` in it points at a file that exists (tested with ``html.parser``).
"""

from __future__ import annotations

import html
import json
import math
from pathlib import Path
from typing import Any

_STYLE = """
body { font-family: system-ui, sans-serif; margin: 2em auto; max-width: 1200px; color: #222; }
table { border-collapse: collapse; margin: 0.5em 0 1.2em; font-size: 0.9em; }
th, td { border: 1px solid #ccc; padding: 0.25em 0.6em; text-align: left; vertical-align: top; }
th { background: #f3f3f3; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
.reproduced { background: #d9f2d9; } .differs { background: #f8d0d0; } .not-computed { background: #eee; color: #666; }
section { border-top: 2px solid #888; margin-top: 2em; padding-top: 0.5em; }
figure { display: inline-block; margin: 0.5em; } figure img { max-width: 560px; border: 1px solid #ddd; }
figcaption { font-size: 0.85em; color: #555; }
details { margin: 0.5em 0; }
"""


def _e(x: Any) -> str:
    return html.escape(str(x), quote=True)


def _fmt(v: Any) -> str:
    if isinstance(v, bool) or v is None:
        return "—" if v is None else str(v)
    if isinstance(v, float):
        return f"{v:.6g}" if math.isfinite(v) else str(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_fmt(x) for x in v) + "]"
    return str(v)


def _cell(v: Any, cls: str = "") -> str:
    numeric = isinstance(v, (int, float)) and not isinstance(v, bool)
    classes = " ".join(c for c in (cls, "num" if numeric else "") if c)
    attr = f' class="{classes}"' if classes else ""
    return f"<td{attr}>{_e(_fmt(v))}</td>"


def _table(rows: list[dict[str, Any]], columns: list[str], row_class: str | None = None) -> str:
    head = "".join(f"<th>{_e(c)}</th>" for c in columns)
    body = []
    for r in rows:
        cls = str(r.get(row_class, "")).replace(" ", "-") if row_class else ""
        body.append("<tr>" + "".join(_cell(r.get(c), cls if c == row_class else "") for c in columns) + "</tr>")
    return f"<table><tr>{head}</tr>{''.join(body)}</table>"


def _key_values(d: dict[str, Any], title: str) -> str:
    rows = [{"name": k, "value": v} for k, v in d.items()]
    return f"<details><summary>{_e(title)} ({len(rows)})</summary>{_table(rows, ['name', 'value'])}</details>"


def _assumptions(d: dict[str, Any]) -> str:
    rows = [
        {
            "name": k,
            "value": (v or {}).get("value") if isinstance(v, dict) else v,
            "why": (v or {}).get("why", "") if isinstance(v, dict) else "",
        }
        for k, v in d.items()
    ]
    table = _table(rows, ["name", "value", "why"])
    return f"<details open><summary>assumptions ({len(rows)})</summary>{table}</details>"


def _verdicts(rows: list[dict[str, Any]]) -> dict[str, int]:
    out = {"reproduced": 0, "differs": 0, "not computed": 0}
    for r in rows:
        out[r.get("verdict", "not computed")] = out.get(r.get("verdict", "not computed"), 0) + 1
    return out


def _section(folder: Path, rel: str, res: dict[str, Any]) -> str:
    name = res.get("study", folder.name)
    parts = [f'<section id="{_e(rel)}"><h2>{_e(name)}</h2>']
    if res.get("description"):
        parts.append(f"<p>{_e(res['description'])}</p>")
    links = [f'<a href="{_e(rel)}/results.json">results.json</a>']
    links += [f'<a href="{_e(rel)}/{_e(p.name)}">{_e(p.name)}</a>' for p in sorted(folder.glob("*.csv"))]
    parts.append(f"<p>preset: <b>{_e(res.get('preset', '?'))}</b> · files: {' · '.join(links)}</p>")
    rows = res.get("reproduction") or []
    if rows:
        parts.append("<h3>reproduction</h3>")
        parts.append(
            _table(rows, ["metric", "ours", "paper", "tolerance", "verdict", "source", "note"], row_class="verdict")
        )
    else:
        parts.append("<p><i>no claims declared</i></p>")
    pngs = sorted(folder.glob("*.png"))
    if pngs:
        figs = "".join(
            f'<figure><a href="{_e(rel)}/{_e(p.name)}"><img src="{_e(rel)}/{_e(p.name)}" '
            f'alt="{_e(p.stem)}"></a><figcaption>{_e(p.stem)}</figcaption></figure>'
            for p in pngs
        )
        parts.append(f"<h3>figures</h3><div>{figs}</div>")
    parts.append(_key_values(res.get("config", {}), "config"))
    parts.append(_assumptions(res.get("assumptions", {})))
    parts.append(_key_values(res.get("metrics", {}), "metrics"))
    for note in res.get("notes", []):
        parts.append(f"<p><small>{_e(note)}</small></p>")
    parts.append("</section>")
    return "\n".join(parts)


def find_results(results_dir: Path) -> list[tuple[Path, dict[str, Any]]]:
    """``(folder, results.json content)`` of every ``results_dir/*/results.json`` that parses, by name."""
    found = []
    for path in sorted(Path(results_dir).glob("*/results.json")):
        try:
            found.append((path.parent, json.loads(path.read_text())))
        except (OSError, ValueError):
            continue
    return found


def render(results_dir: str | Path) -> str:
    """The report page of ``results_dir`` as a string (links relative to ``results_dir``)."""
    root = Path(results_dir)
    studies = find_results(root)
    summary = []
    for folder, res in studies:
        rel = folder.relative_to(root).as_posix()
        counts = _verdicts(res.get("reproduction") or [])
        summary.append(
            {"study": res.get("study", folder.name), "preset": res.get("preset", "?"), **counts, "_anchor": rel}
        )
    head = "".join(f"<th>{_e(c)}</th>" for c in ("study", "preset", "reproduced", "differs", "not computed"))
    rows = "".join(
        f'<tr><td><a href="#{_e(s["_anchor"])}">{_e(s["study"])}</a></td><td>{_e(s["preset"])}</td>'
        f'<td class="num reproduced">{s["reproduced"]}</td><td class="num differs">{s["differs"]}</td>'
        f'<td class="num not-computed">{s["not computed"]}</td></tr>'
        for s in summary
    )
    sections = "\n".join(_section(folder, folder.relative_to(root).as_posix(), res) for folder, res in studies)
    empty = "" if studies else f"<p>No study results found under {_e(root)} (expected */results.json).</p>"
    return (
        f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8"><title>jaxsim studies</title>'
        f"<style>{_STYLE}</style></head><body>\n<h1>Studies: paper vs ours</h1>\n{empty}"
        f"<table><tr>{head}</tr>{rows}</table>\n{sections}\n</body></html>\n"
    )


def write_html_report(results_dir: str | Path) -> Path:
    """Write ``results_dir/report.html`` atomically; ``ValueError`` if ``results_dir`` is not a folder."""
    from jaxsim.montecarlo.store import atomic_write_bytes

    root = Path(results_dir)
    if not root.is_dir():
        raise ValueError(f"DIR: {root} is not a folder of study results")
    path = root / "report.html"
    atomic_write_bytes(path, render(root).encode())
    return path
