"""``python -m experiments sweep NAME``: Monte Carlo / parameter sweep of a study's per-run metric.

    python -m experiments sweep NAME --param key=lo:hi:n [--param ...] --runs N
        [--design grid|lhs|sobol] [--points M] [--seed S] [--chunk C] [--devices K]
        [--out DIR] [--resume] [--preset P | --quick] [--set k=v ...] [--keep-runs K]
        [--coordinator HOST:PORT --num-processes P --process-id I]

``--devices K`` uses K devices; on a CPU it makes JAX expose K host devices
(``--xla_force_host_platform_device_count``), which only works before JAX initialises — so it is
applied first thing, before any study module is imported.  ``--coordinator`` joins a multi-process
run (``jax.distributed.initialize``): start the same command on every machine with its own
``--process-id``; process 0 writes ``--out``.

Writes ``DIR/results.json``, ``DIR/sweep.csv`` (one row per point), ``DIR/sweep_<metric>.png``
(or ``distribution.png`` for a single point) and the checkpoint folder's ``manifest.json`` and
``chunks/``.  ``DIR`` is the checkpoint folder too, so it is written as the sweep goes; before
anything is computed it is refused if it holds anything but this study's previous sweep output or
cannot be written (:mod:`experiments.output_folder`; whether its checkpoint is this very sweep —
same parameters, same per-run computation — and whether ``--resume`` is needed is checked by
:mod:`jaxsim.montecarlo.store`).  The report files are written atomically, then the folder's
marker ``jaxsim-output.json``.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import re
import sys
from pathlib import Path
from typing import Any

_DEVICE_FLAG = "--xla_force_host_platform_device_count"


def add_parser(sub: Any) -> None:
    sw = sub.add_parser(
        "sweep",
        help="Monte Carlo / parameter sweep of a study's per-run metric (resumable, sharded over devices and hosts)",
    )
    sw.add_argument("name", metavar="NAME", help="study name (one that exposes a per-run metric)")
    sw.add_argument(
        "--param",
        action="append",
        default=[],
        metavar="KEY=LO:HI[:N]",
        help="swept parameter (repeatable); N points per axis for --design grid",
    )
    sw.add_argument("--runs", type=int, required=True, help="Monte-Carlo runs per point")
    sw.add_argument("--design", choices=("grid", "lhs", "sobol"), default="grid")
    sw.add_argument("--points", type=int, default=None, help="number of points for lhs/sobol")
    sw.add_argument("--seed", type=int, default=0, help="PRNG seed (runs and lhs/sobol points)")
    sw.add_argument("--chunk", type=int, default=None, help="runs per chunk (checkpoint granularity)")
    sw.add_argument("--devices", type=int, default=None, help="number of devices (CPU: host devices)")
    sw.add_argument("--out", default=None, help="output + checkpoint folder (default results/NAME-sweep)")
    sw.add_argument("--resume", action="store_true", help="continue the sweep already in --out")
    from experiments.cli import add_preset_arguments

    add_preset_arguments(sw)
    sw.add_argument("--keep-runs", type=int, default=0, help="keep the first K runs verbatim (raw_runs.csv)")
    sw.add_argument("--coordinator", default=None, metavar="HOST:PORT", help="jax.distributed coordinator")
    sw.add_argument("--num-processes", type=int, default=None)
    sw.add_argument("--process-id", type=int, default=None)


def configure_devices(k: int | None) -> None:
    """Make JAX expose ``k`` CPU devices; must run before JAX initialises its backends."""
    if k is None:
        return
    if k < 1:
        raise ValueError(f"--devices: must be ≥ 1, got {k}")
    flags = re.sub(rf"{_DEVICE_FLAG}=\S+", "", os.environ.get("XLA_FLAGS", "")).strip()
    os.environ["XLA_FLAGS"] = f"{flags} {_DEVICE_FLAG}={k}".strip()
    if "jax" in sys.modules:  # imported already: the config option still works if not initialised
        import jax

        try:
            jax.config.update("jax_num_cpu_devices", k)
        except RuntimeError:
            pass  # initialised: checked against the visible devices below


def _design(args: argparse.Namespace, nominal: dict[str, float]):
    import jaxsim.montecarlo as mc

    parsed = [mc.parse_range(text) for text in args.param]
    names = [p[0] for p in parsed]
    for name in names:
        if name not in nominal:
            raise ValueError(
                f"--param {name}: unknown parameter; this study's parameters: {', '.join(sorted(nominal))}"
            )
    if len(set(names)) != len(names):
        raise ValueError(f"--param: a parameter is given twice ({', '.join(names)})")
    if not parsed:
        return mc.single_point()
    if args.design == "grid":
        missing = [p[0] for p in parsed if p[3] is None]
        if missing:
            raise ValueError(f"--param {missing[0]}: a grid needs lo:hi:n (number of points)")
        return mc.grid({name: (lo, hi, n) for name, lo, hi, n in parsed})
    if args.points is None:
        raise ValueError(f"--points: required with --design {args.design}")
    ranges = {name: (lo, hi) for name, lo, hi, _ in parsed}
    make = mc.latin_hypercube if args.design == "lhs" else mc.sobol
    return make(ranges, args.points, seed=args.seed)


def run_sweep_command(args: argparse.Namespace) -> int:
    if args.runs < 1:
        raise ValueError(f"--runs: must be ≥ 1, got {args.runs}")
    configure_devices(args.devices)
    distributed = [args.coordinator, args.num_processes, args.process_id]
    if any(v is not None for v in distributed):
        if any(v is None for v in distributed):
            raise ValueError("--coordinator, --num-processes and --process-id go together")
        import jax

        jax.distributed.initialize(args.coordinator, args.num_processes, args.process_id)

    import jax

    import jaxsim.montecarlo as mc
    from experiments.cli import preset_of
    from experiments.output_folder import check_output_folder, write_marker
    from experiments.progress import bar
    from experiments.registry import all_studies, get_study
    from experiments.report import report_file_names, write_report
    from experiments.runner import as_study
    from experiments.study import StudyResult
    from jaxsim.montecarlo.plots import plot_distribution, plot_sweep

    if args.devices is not None and len(jax.devices()) < args.devices:
        raise ValueError(
            f"--devices: {args.devices} requested but JAX sees {len(jax.devices())} "
            "(it was initialised before the flag could take effect)"
        )
    study = as_study(get_study(args.name))
    if study.per_run is None:
        able = [n for n, s in all_studies().items() if s.per_run is not None]
        raise ValueError(
            f"NAME: study {study.name!r} exposes no per-run metric; studies that do: {', '.join(able) or 'none'}"
        )
    preset, config = study.resolve(preset_of(args), args.overrides)
    spec = study.per_run(config)
    design = _design(args, spec.nominal)
    space = {**spec.nominal, **spec.uncertain}
    out = Path(args.out) if args.out else Path("results") / f"{study.name}-sweep"
    main = jax.process_index() == 0
    if main:  # process 0 alone writes --out
        check_output_folder(out, study.name, "sweep")  # foreign or unwritable: refused before computing
        print(
            f"[{study.name}] sweep: {len(design)} point(s) × {args.runs} runs on "
            f"{len(jax.devices()) if args.devices is None else args.devices} device(s), "
            f"{jax.process_count()} process(es) → {out}",
            file=sys.stderr,
        )
    result = mc.sweep(
        spec.metric,
        space,
        design,
        args.runs,
        args.seed,
        chunk_size=args.chunk,
        keep_runs=args.keep_runs,
        devices=args.devices if jax.process_count() == 1 else None,
        out=out,
        resume=args.resume,
        name=f"study:{study.name}",
        extra={"config": dataclasses.asdict(config)},
        progress=bar,
    )
    if not main:
        return 0
    wall = sum(r.wall_s for r in result.points)
    computed_runs = sum(r.runs_computed for r in result.points)
    metrics = {
        "n_points": len(design),
        "runs_per_point": args.runs,
        "runs_total": len(design) * args.runs,
        "devices": result.points[0].devices,
        "processes": result.points[0].processes,
        "chunks_computed": result.chunks_computed,
        "chunks_loaded": result.chunks_loaded,
        "chunks_rejected": len(result.rejected_chunks),
        "wall_s": wall,
    }
    if computed_runs:
        metrics["runs_per_s"] = computed_runs / max(wall, 1e-9)
    tables = {"sweep": result.table()}
    if len(design) == 1:
        metrics.update({k: v for k, v in tables["sweep"][0].items() if isinstance(v, float)})
        figures = {"distribution": plot_distribution(result.points[0])}
    else:
        figures = plot_sweep(result)
    raws = [r.raw for r in result.points if r.raw is not None]
    if raws:
        tables["raw_runs"] = _raw_rows(result)
    notes = [
        f"design {design.kind} over {', '.join(design.names) or '(no parameter)'}; "
        f"uncertain: {', '.join(spec.uncertain) or 'none'}; seed {args.seed}; "
        f"same key at every point (common random numbers)",
        f"fingerprint {result.fingerprint}",
    ]
    notes += [f"damaged chunk recomputed: {f} ({why})" for f, why in result.rejected_chunks]
    study_result = StudyResult(metrics=metrics, tables=tables, figures=figures, notes=notes)
    files = report_file_names(study_result)
    write_marker(out, study.name, "sweep", files, final=False)  # listed before they exist: crash-safe
    path = write_report(f"{study.name} (sweep)", config, study_result, out, {"preset": preset})
    write_marker(out, study.name, "sweep", files)  # stale files of an earlier report removed
    print(
        f"[{study.name}] sweep done in {wall:.1f} s ({result.chunks_computed} chunk(s) computed, "
        f"{result.chunks_loaded} loaded); wrote {path}",
        file=sys.stderr,
    )
    return 0


def _raw_rows(result: Any) -> list[dict[str, Any]]:
    import jax
    import numpy as np

    from jaxsim.montecarlo.kernel import leaf_name

    rows = []
    for p, r in enumerate(result.points):
        if r.raw is None:
            continue
        params = {k: np.asarray(v) for k, v in r.raw.params.items()} if isinstance(r.raw.params, dict) else {}
        metrics = jax.tree_util.tree_leaves_with_path(r.raw.metrics)
        for i, idx in enumerate(r.raw.index):
            row: dict[str, Any] = {"point": p, "run": int(idx)}
            row.update({k: float(v[i]) for k, v in params.items() if np.ndim(v[i]) == 0})
            for path, v in metrics:
                if np.ndim(v[i]) == 0:
                    row[leaf_name(path)] = v[i].item()
            rows.append(row)
    return rows
