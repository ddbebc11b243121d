"""Command line: ``python -m experiments list``, ``run NAME``, ``sweep NAME`` (see
:mod:`experiments.sweep_command`) and ``report [DIR]`` (see :mod:`experiments.report_html`).

``run NAME [--preset P | --quick] [--set key=value ...] [--out DIR]``: the config is the study's
preset (``full`` = the defaults; ``--quick`` = ``--preset quick``) with every ``--set`` applied on
top, resolved once (:meth:`experiments.runner.Study.resolve`); ``results.json`` records that config,
the preset and the reproduction table of the study's claims.

``run`` refuses, before computing anything, a folder that holds anything but this study's previous
output or that cannot be written (:mod:`experiments.output_folder`), writes the report into a fresh
folder beside ``DIR`` and swaps it in at the end: a failed or interrupted run leaves the previous
output intact.  Every refusal and every ``OSError`` ends with one ``error: ...`` line on stderr and
exit code 2.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

from experiments.output_folder import staged_output
from experiments.progress import bar
from experiments.registry import discover, get_study
from experiments.report import write_report
from experiments.runner import as_study
from experiments.sweep_command import add_parser as add_sweep_parser
from experiments.sweep_command import run_sweep_command


def add_preset_arguments(parser: argparse.ArgumentParser) -> None:
    """``--preset P`` / ``--quick`` (one of them) and repeatable ``--set KEY=VALUE``."""
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--preset", default=None, help="named config preset of the study (default: full)")
    group.add_argument("--quick", action="store_true", help="the study's 'quick' preset (= --preset quick)")
    parser.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override a config field after the preset (repeatable), e.g. --set t_final=20",
    )


def preset_of(args: argparse.Namespace) -> str | None:
    return "quick" if getattr(args, "quick", False) else getattr(args, "preset", None)


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m experiments",
        description="Run the toolkit's studies (each reproduces a seed paper's system).",
    )
    sub = p.add_subparsers(dest="command", required=True)
    sub.add_parser("list", help="list the studies, their presets and default configs")
    run = sub.add_parser("run", help="run one study and write results.json, CSV tables and PNG plots")
    run.add_argument("name", metavar="NAME", help="study name (see `list`)")
    add_preset_arguments(run)
    run.add_argument("--out", default=None, help="output folder (default: results/NAME)")
    add_sweep_parser(sub)
    rep = sub.add_parser("report", help="one static HTML page over every study's results (DIR/report.html)")
    rep.add_argument("dir", nargs="?", default="results", metavar="DIR", help="results folder (default results/)")
    return p


def _list() -> int:
    studies, broken = discover()
    for name, study in studies.items():
        sweepable = " [sweep]" if study.per_run is not None else ""
        print(f"{name:28s} {study.description}{sweepable}")
        print(f"    presets: {', '.join(study.preset_names)}; claims: {len(study.claims)}")
        defaults = study.config()
        for f in dataclasses.fields(study.config):
            print(f"    {f.name} = {getattr(defaults, f.name)!r}")
    for module, error in broken.items():
        print(f"{module:28s} BROKEN: {error}")
    return 0


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    try:
        if args.command == "sweep":  # first: --devices must act before JAX initialises
            return run_sweep_command(args)
        if args.command == "list":
            return _list()
        if args.command == "report":
            from experiments.report_html import write_html_report

            path = write_html_report(args.dir)
            print(f"wrote {path}", file=sys.stderr)
            return 0
        study = as_study(get_study(args.name))
        preset, config = study.resolve(preset_of(args), args.overrides)
        out = Path(args.out) if args.out else Path("results") / study.name
        print(f"[{study.name}] preset {preset}; config: {config}", file=sys.stderr)
        start = time.perf_counter()
        with staged_output(out, study.name) as staging:  # refuses a foreign/unwritable folder first
            result = study.run(config, bar)
            result, extra = study.finalize(result, preset)
            write_report(study.name, config, result, staging, extra)
        path = out / "results.json"
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:  # e.g. the disk filled up or a folder was made read-only while running
        where = f" ({exc.filename})" if exc.filename else ""
        print(f"error: {exc.strerror or exc}{where}", file=sys.stderr)
        return 2
    print(f"[{study.name}] done in {time.perf_counter() - start:.1f} s; wrote {path}", file=sys.stderr)
    for key, value in result.metrics.items():
        print(f"  {key} = {value:.6g}")
    for row in extra["reproduction"]:
        ours = "—" if row["ours"] is None else f"{row['ours']:.6g}"
        print(f"  claim {row['metric']}: ours {ours}, paper {row['paper']:.6g} ({row['tolerance']}): {row['verdict']}")
    return 0
