"""Command line: ``python -m experiments list``, ``run NAME`` and ``sweep NAME`` (see
:mod:`experiments.sweep_command`).

``run NAME --out DIR`` refuses, before computing anything, a folder that holds anything but this
study's previous output or that cannot be written (:mod:`experiments.output_folder`), writes the
report into a fresh folder beside ``DIR`` and swaps it in at the end: a failed or interrupted run
leaves the previous output intact.  Every refusal and every ``OSError`` ends with one
``error: ...`` line on stderr and exit code 2.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

from experiments.config_overrides import apply_overrides
from experiments.output_folder import staged_output
from experiments.progress import bar
from experiments.registry import all_studies, get_study
from experiments.report import write_report
from experiments.sweep_command import add_parser as add_sweep_parser, run_sweep_command


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m experiments",
        description="Run the toolkit's studies (each reproduces a seed paper's system).",
    )
    sub = p.add_subparsers(dest="command", required=True)
    sub.add_parser("list", help="list the studies and their default configs")
    run = sub.add_parser("run", help="run one study and write results.json, CSV tables and PNG plots")
    run.add_argument("name", metavar="NAME", help="study name (see `list`)")
    run.add_argument("--quick", action="store_true", help="small, fast version (CI smoke runs)")
    run.add_argument("--out", default=None, help="output folder (default: results/NAME)")
    run.add_argument(
        "--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
        help="override a config field (repeatable), e.g. --set t_final=20",
    )
    add_sweep_parser(sub)
    return p


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    try:
        if args.command == "sweep":  # first: --devices must act before JAX initialises
            return run_sweep_command(args)
        if args.command == "list":
            for name, study in all_studies().items():
                sweepable = " [sweep]" if study.per_run is not None else ""
                print(f"{name:28s} {study.description}{sweepable}")
                for f in dataclasses.fields(study.config_cls):
                    print(f"    {f.name} = {getattr(study.default_config(), f.name)!r}")
            return 0
        study = get_study(args.name)
        config = apply_overrides(study.default_config(quick=args.quick), args.overrides)
        out = Path(args.out) if args.out else Path("results") / study.name
        print(f"[{study.name}] config: {config}", file=sys.stderr)
        start = time.perf_counter()
        with staged_output(out, study.name) as staging:  # refuses a foreign/unwritable folder first
            result = study.run(config, bar)
            write_report(study.name, config, result, staging)
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
    return 0
