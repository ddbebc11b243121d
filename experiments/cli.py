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

JAX's persistent compilation cache is on for every command (:func:`enable_compilation_cache`): compiled
programs are kept in ``$JAXSIM_CACHE_DIR`` (default ``~/.cache/jaxsim/jax``, under
``$XDG_CACHE_HOME`` if set), so a second run of a study skips most of its compilation.
``JAXSIM_CACHE_DIR=`` (empty) turns it off; a ``JAX_COMPILATION_CACHE_DIR`` set by the caller (the
tests give each spawned CLI theirs) is respected when ``JAXSIM_CACHE_DIR`` is not set.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
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

CACHE_HELP = (
    "JAX's persistent compilation cache is on: compiled programs are kept in $JAXSIM_CACHE_DIR "
    "(default ~/.cache/jaxsim/jax, or $XDG_CACHE_HOME/jaxsim/jax), so repeated runs skip most compilation; "
    "JAXSIM_CACHE_DIR= (empty) turns it off; without JAXSIM_CACHE_DIR, a JAX_COMPILATION_CACHE_DIR already "
    "set in the environment is used instead."
)


def cache_dir() -> Path | None:
    """The persistent-cache folder the CLI uses (``None``: off, or left to ``JAX_COMPILATION_CACHE_DIR``)."""
    if "JAXSIM_CACHE_DIR" in os.environ:
        value = os.environ["JAXSIM_CACHE_DIR"].strip()
        return Path(value).expanduser() if value else None
    if os.environ.get("JAX_COMPILATION_CACHE_DIR"):
        return None  # JAX reads it itself
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base).expanduser() / "jaxsim" / "jax"


def enable_compilation_cache() -> None:
    """Turn on JAX's persistent compilation cache (folder: :func:`cache_dir`) before anything compiles.

    Only the config is set (no backend is initialised, so ``sweep --devices`` still acts first)."""
    import jax

    folder = cache_dir()
    if folder is None and "JAXSIM_CACHE_DIR" in os.environ:
        jax.config.update("jax_enable_compilation_cache", False)
        return
    if folder is not None:
        jax.config.update("jax_compilation_cache_dir", str(folder))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.5)
    jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)


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
        epilog=CACHE_HELP,
    )
    sub = p.add_subparsers(dest="command", required=True)
    sub.add_parser("list", help="list the studies, their presets and default configs")
    run = sub.add_parser(
        "run", help="run one study and write results.json, CSV tables and PNG plots", epilog=CACHE_HELP
    )
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
    enable_compilation_cache()
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
