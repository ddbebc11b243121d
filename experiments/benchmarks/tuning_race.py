"""Benchmark: the tuning race — seconds to get within 1 % and 0.1 % of the best known loss, cold and warm.

Every tuner runs on the same :class:`~jaxsim.problem.Problem`, each problem in its own budget
(:class:`Budget`):

* ``pid`` — :func:`experiments.pid_tuning_comparison.problem_of` (PID of the fuzzy-PID paper's static
  plant, ``J = ∫ e² + 0.01 u² dt``, 3 gains);
* ``fuzzy`` — the fuzzy-PID study's three-section characteristic ``(a, b, c, d)`` at its four
  operating points, smooth surrogate, with the constraints folded into the loss as the study's
  quadratic penalty (so gradient tuners and swarms minimise the same scalar);
* ``trms`` — the TRMS LQG tracker's 16 log-weights (:func:`experiments.trms_lqr_tuning.problems_of`),
  horizon ``--trms-t-final`` (30 s: the study's quick preset).

Tuners: ``adam`` (:func:`optim.tune`, 1 start), ``adam_x8`` (8 vmapped starts), ``lbfgs``
(:func:`optim.lbfgs`: backtracking trials as the tuner's own steps), ``lbfgs_x8`` (the same from 8
vmapped starts: start 0 the problem's initial point, the others spread around it),
``pso`` (:func:`optim.pso`), ``pyswarms`` (``GlobalBestPSO`` on the jitted batched loss), ``random``
(:func:`optim.random_search`), ``cmaes`` (:func:`optim.cmaes.cmaes`) and ``hybrid``
(:func:`optim.hybrid.hybrid`: a short swarm, then L-BFGS) and ``lm``
(:func:`optim.least_squares.levenberg_marquardt`, on problems whose loss is a sum of squares: ``pid``;
the others report why not).

Each round runs every tuner twice, in an order rotated from round to round (interleaved):

* **cold** — after ``jax.clear_caches()`` and :func:`optim.compile_cache.clear_all` (the tuners'
  own caches of compiled steps), with JAX's persistent compilation cache off: the time
  includes tracing and compilation;
* **warm** — the same call again (same key, so the same iterates): whatever the tuner caches across
  calls is reused.

Time to a target: each tuner's :class:`~optim.results.History` gives the best loss so far and the
seconds of stepping after each step (compile excluded, chunks interpolated linearly).  The time of
step ``i`` is ``(T − wall_s[-1]) + wall_s[i]``, ``T`` the call's wall time measured here: every
second spent outside the stepping (setup, compilation — for ``hybrid`` also the polishing phase's —
and the result's assembly) is charged before the first step, which slightly over-counts.  Targets
are ``L* + 1 %·|L*|`` and ``L* + 0.1 %·|L*|``, ``L*`` the lowest loss any run reached (or
``--reference``).  Reported: medians over ``--rounds`` rounds (round ``r`` seeds the stochastic
tuners with key ``seed + r``), how many rounds reached each target, and ratios tuner / ``pso`` of
the median times (below 1: faster than the swarm; ``never``: the tuner never got there; ``pso∞``:
it did and the swarm never did).

Writes ``tuning_race.json`` (settings, machine load, every run, the summary), ``tuning_race.csv``
(the summary) and ``tuning_race.png`` (best − L* against seconds, round 0, cold solid and warm
dashed) into ``--out``.

Usage: ``python -m experiments.benchmarks.tuning_race [--quick] [--problems pid fuzzy trms]
[--tuners ...] [--rounds 3] [--trms-t-final 30] [--mode auto|forward|reverse|measure]
[--budget PROBLEM.FIELD=N ...] [--out results/tuning_race]`` (``--mode``: the gradient tuners' AD mode,
:func:`optim.tune`'s ``mode``; with ``measure`` the cold call includes compiling and timing both modes;
``--budget``: one count of a problem's :class:`Budget`, e.g. ``fuzzy.particles=16 fuzzy.iters=16``)
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import dataclasses
import json
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterator

import jax
import numpy as np
import optax

import jaxsim  # noqa: F401  (float64)
from jaxsim.problem import Problem
from optim.compile_cache import clear_all
from optim.results import TuneResult

TARGETS = (0.01, 0.001)
TUNERS = ("adam", "adam_x8", "lbfgs", "lbfgs_x8", "lm", "pso", "pyswarms", "random", "cmaes", "hybrid")
PROBLEMS = ("pid", "fuzzy", "trms")


@dataclass(frozen=True)
class Budget:
    """Sizes of every tuner on one problem (steps, particles × iterations, points)."""

    adam_lr: float = 0.05
    adam_steps: int = 200
    adam_x8_steps: int = 100
    lbfgs_steps: int = 100
    particles: int = 32
    iters: int = 30
    random_n: int = 1024
    cma_popsize: int = 16
    cma_iters: int = 60
    hybrid_popsize: int = 16
    hybrid_iters: int = 5
    hybrid_steps: int = 60

    def scaled(self, f: float) -> "Budget":
        """Every count times ``f`` (at least 1; learning rate unchanged)."""
        return dataclasses.replace(
            self,
            **{
                k.name: max(1, int(round(getattr(self, k.name) * f)))
                for k in dataclasses.fields(self)
                if k.type == "int" and k.name not in ("particles", "cma_popsize", "hybrid_popsize")
            },
        )


BUDGETS = {
    "pid": Budget(),
    # a swarm of 16 × 16 ends in another basin (J ≈ 0.0156); 64 × 150 finds the best one (J ≈ 0.0124885),
    # as L-BFGS from the paper's controller does after 235 (forward mode) to 257 (reverse) steps
    "fuzzy": Budget(
        particles=64,
        iters=150,
        lbfgs_steps=400,
        random_n=1024,
        cma_popsize=16,
        cma_iters=100,
        hybrid_popsize=64,
        hybrid_iters=40,
    ),
    "trms": Budget(
        adam_lr=0.1,
        adam_steps=100,
        adam_x8_steps=50,
        lbfgs_steps=80,
        particles=30,
        iters=20,
        random_n=600,
        cma_popsize=16,
        cma_iters=40,
        hybrid_popsize=10,
        hybrid_iters=4,
    ),
}


# ------------------------------------------------------------------------------------------ problems
def pid_problem() -> Problem:
    from experiments.pid_tuning_comparison import Config, problem_of

    return problem_of(Config())


def fuzzy_problem() -> Problem:
    """The study's smooth characteristic with its constraint penalty folded into the loss."""
    from experiments.fuzzy_pid_tuning import Config
    from jaxsim.problem import penalised
    from jaxsim.problem.fuzzy_tuning import FuzzyPTuning, three_section_of

    cfg = Config()
    loop = FuzzyPTuning(cfg)

    def loss(p, draw, key):
        f, h, _ = loop.terms(three_section_of(p, cfg.smooth_temperature, "smooth"), smooth=True, with_details=False)
        return penalised(f, h, cfg.penalty_weight)

    return Problem.from_loss("fuzzy_p_smooth_penalised", loop.three_section_space(), loss)


def trms_problem(t_final: float) -> Problem:
    from experiments.trms_lqr_tuning import Config, problems_of, tuning_of

    cfg = Config(t_final=t_final)
    return problems_of(cfg, tuning_of(cfg))[0]


def build_problems(names: list[str], trms_t_final: float) -> dict[str, Problem]:
    makers = {"pid": pid_problem, "fuzzy": fuzzy_problem, "trms": lambda: trms_problem(trms_t_final)}
    return {n: makers[n]() for n in names}


# ------------------------------------------------------------------------------------------ tuners
def lbfgs() -> optax.GradientTransformation:
    from optim.lbfgs import lbfgs as trial_lbfgs

    return trial_lbfgs(max_backtracking_steps=20)


def tuner_runs(b: Budget, mode: str = "auto") -> dict[str, Callable[[Problem, int], TuneResult]]:
    """name → ``run(problem, seed)``; only public arguments of each tuner; ``mode``: the AD mode of
    the gradient tuners (``adam*``, ``lbfgs*``, ``hybrid``'s polisher)."""
    from experiments.stages import pyswarms_search
    from optim import pso, random_search, tune
    from optim.cmaes import cmaes
    from optim.hybrid import hybrid
    from optim.least_squares import levenberg_marquardt

    key = jax.random.PRNGKey
    return {
        "adam": lambda pb, s: tune(pb, optimizer=optax.adam(b.adam_lr), steps=b.adam_steps, mode=mode),
        "adam_x8": lambda pb, s: tune(
            pb,
            optimizer=optax.adam(b.adam_lr),
            steps=b.adam_x8_steps,
            n_starts=8,
            key=key(s),
            init_spread=0.5,
            mode=mode,
        ),
        "lbfgs": lambda pb, s: tune(pb, optimizer=lbfgs(), steps=b.lbfgs_steps, gtol=1e-9, patience=20, mode=mode),
        "lbfgs_x8": lambda pb, s: tune(
            pb,
            optimizer=lbfgs(),
            steps=b.lbfgs_steps,
            n_starts=8,
            key=key(s),
            init_spread=0.5,
            gtol=1e-9,
            patience=20,
            mode=mode,
        ),
        "pso": lambda pb, s: pso(pb, n_particles=b.particles, n_iters=b.iters, key=key(s)),
        "pyswarms": lambda pb, s: pyswarms_search(pb, b.particles, b.iters, seed=s),
        "random": lambda pb, s: random_search(pb, n=b.random_n, key=key(s), batch_size=min(256, b.random_n)),
        "cmaes": lambda pb, s: cmaes(pb, popsize=b.cma_popsize, iters=b.cma_iters, key=key(s)),
        "hybrid": lambda pb, s: hybrid(
            pb,
            popsize=b.hybrid_popsize,
            iters=b.hybrid_iters,
            key=key(s),
            steps=b.hybrid_steps,
            tune_options=dict(gtol=1e-9, patience=20, mode=mode),
        ),
        "lm": lambda pb, s: levenberg_marquardt(pb, max_steps=b.lbfgs_steps),
    }


# ------------------------------------------------------------------------------------------ timing
@contextlib.contextmanager
def persistent_cache_off() -> Iterator[None]:
    """JAX's persistent compilation cache disabled inside the block (restored after)."""
    before = jax.config.jax_enable_compilation_cache
    jax.config.update("jax_enable_compilation_cache", False)
    try:
        yield
    finally:
        jax.config.update("jax_enable_compilation_cache", before)


def step_times(result: TuneResult, total_s: float) -> np.ndarray:
    """Seconds since the call began at the end of each history step (module docstring)."""
    wall = np.asarray(result.history.wall_s, float)
    return (total_s - wall[-1]) + wall


def time_to(best_loss: np.ndarray, times: np.ndarray, target: float) -> float:
    """First time the best-so-far loss is ≤ ``target`` (``inf`` if never)."""
    hit = np.nonzero(np.asarray(best_loss) <= target)[0]
    return float(times[hit[0]]) if hit.size else float("inf")


def target_of(best_known: float, frac: float) -> float:
    return best_known + frac * abs(best_known)


def one_run(run: Callable[[], TuneResult], cold: bool) -> dict[str, Any]:
    """One timed call; ``cold`` clears JAX's in-memory caches first."""
    if cold:
        jax.clear_caches()
        clear_all()  # the tuners' own caches of compiled steps, too
    t0 = time.perf_counter()
    try:
        res = run()
    except Exception as err:  # noqa: BLE001  (a tuner the current code rejects is reported, not fatal)
        return {"error": f"{type(err).__name__}: {err}"}
    total = time.perf_counter() - t0
    return {
        "loss": float(res.loss),
        "total_s": total,
        "compile_s": float(res.compile_s),
        "n_sims": int(res.n_sims),
        "best_loss": np.asarray(res.history.best_loss, float),
        "times": step_times(res, total),
    }


def race(
    problems: dict[str, Problem],
    tuners: list[str],
    rounds: int,
    seed: int = 0,
    budgets: dict[str, Budget] | None = None,
    log: Callable[[str], Any] = print,
    mode: str = "auto",
) -> list[dict[str, Any]]:
    """Every (problem, round, tuner): a cold and a warm run, tuner order rotated per round
    (``mode``: the gradient tuners' AD mode)."""
    budgets = BUDGETS if budgets is None else budgets
    records = []
    with persistent_cache_off():
        for name, pb in problems.items():
            runs = tuner_runs(budgets.get(name, Budget()), mode)
            for r in range(rounds):
                order = tuners[r % len(tuners) :] + tuners[: r % len(tuners)]
                for t in order:
                    fn = lambda: runs[t](pb, seed + r)  # noqa: E731
                    cold = one_run(fn, cold=True)
                    warm = one_run(fn, cold=False) if "error" not in cold else dict(cold)
                    records.append({"problem": name, "tuner": t, "round": r, "cold": cold, "warm": warm})
                    msg = cold.get("error") or f"loss {cold['loss']:.6g}, cold {cold['total_s']:.2f} s"
                    log(
                        f"  {name} round {r} {t}: {msg}"
                        + ("" if "error" in warm else f", warm {warm['total_s']:.2f} s")
                    )
    return records


def best_known(records: list[dict[str, Any]], problem: str) -> float:
    losses = [
        rec[k]["loss"] for rec in records if rec["problem"] == problem for k in ("cold", "warm") if "loss" in rec[k]
    ]
    return float(min(losses)) if losses else float("nan")


def summarise(records: list[dict[str, Any]], reference: dict[str, float] | None = None) -> list[dict[str, Any]]:
    """One row per (problem, tuner): medians over rounds and ratios against ``pso``."""
    rows = []
    for problem in dict.fromkeys(rec["problem"] for rec in records):
        best = (reference or {}).get(problem, best_known(records, problem))
        by_tuner: dict[str, list] = {}
        for rec in records:
            if rec["problem"] == problem:
                by_tuner.setdefault(rec["tuner"], []).append(rec)
        for tuner, recs in by_tuner.items():
            row: dict[str, Any] = {"problem": problem, "tuner": tuner, "best_known": best, "rounds": len(recs)}
            ok = [r for r in recs if "error" not in r["cold"]]
            if not ok:
                row["error"] = recs[0]["cold"]["error"]
                rows.append(row)
                continue
            row["final_loss"] = float(np.median([r["cold"]["loss"] for r in ok]))
            row["cold_total_s"] = float(np.median([r["cold"]["total_s"] for r in ok]))
            row["warm_total_s"] = float(np.median([r["warm"]["total_s"] for r in ok]))
            row["compile_s"] = float(np.median([r["cold"]["compile_s"] for r in ok]))
            for frac in TARGETS:
                tgt = target_of(best, frac)
                for kind in ("cold", "warm"):
                    ts = [time_to(r[kind]["best_loss"], r[kind]["times"], tgt) for r in ok]
                    row[f"t_{frac:g}_{kind}_s"] = float(np.median(ts))
                    row[f"reached_{frac:g}_{kind}"] = int(np.sum(np.isfinite(ts)))
            rows.append(row)
        pso_row = next((r for r in rows if r["problem"] == problem and r["tuner"] == "pso" and "error" not in r), None)
        for row in rows:
            if row["problem"] != problem or pso_row is None or "error" in row:
                continue
            for frac in TARGETS:
                for kind in ("cold", "warm"):
                    k = f"t_{frac:g}_{kind}_s"
                    num, den = row[k], pso_row[k]
                    row[f"ratio_{frac:g}_{kind}"] = (
                        float("nan") if not np.isfinite(den) and not np.isfinite(num) else num / den
                    )
    return rows


def format_table(rows: list[dict[str, Any]]) -> str:
    head = (
        f"{'problem':8} {'tuner':9} {'loss':>12} {'compile':>8} "
        f"{'1% cold':>9} {'0.1% cold':>10} {'1% warm':>9} {'0.1% warm':>10} {'×pso 0.1% c/w':>15} {'reached':>8}"
    )
    lines = [head, "-" * len(head)]
    for r in rows:
        if "error" in r:
            lines.append(f"{r['problem']:8} {r['tuner']:9} error: {r['error'][:90]}")
            continue

        def s(x):
            return "never" if not np.isfinite(x) else f"{x:.3g}"

        def ratio_of(kind):
            x = r.get(f"ratio_0.001_{kind}", np.nan)
            return "pso∞" if x == 0 and np.isfinite(r[f"t_0.001_{kind}_s"]) else s(x)  # pso never got there

        ratio = f"{ratio_of('cold')}/{ratio_of('warm')}"
        lines.append(
            f"{r['problem']:8} {r['tuner']:9} {r['final_loss']:12.6g} {r['compile_s']:8.2f} "
            f"{s(r['t_0.01_cold_s']):>9} {s(r['t_0.001_cold_s']):>10} {s(r['t_0.01_warm_s']):>9} "
            f"{s(r['t_0.001_warm_s']):>10} {ratio:>15} {r['reached_0.001_cold']}/{r['rounds']:<6}"
        )
    return "\n".join(lines)


def plot(records: list[dict[str, Any]], rows: list[dict[str, Any]], path: Path) -> None:
    """Best − L* against seconds, one panel per problem, round 0: cold solid, warm dashed."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    problems = list(dict.fromkeys(rec["problem"] for rec in records))
    fig, axes = plt.subplots(1, len(problems), figsize=(5.5 * len(problems), 4), squeeze=False)
    for ax, problem in zip(axes[0], problems):
        best = next(r["best_known"] for r in rows if r["problem"] == problem)
        floor = 1e-6 * max(abs(best), 1e-300)
        for i, rec in enumerate(r for r in records if r["problem"] == problem and r["round"] == 0):
            color = f"C{i % 10}"
            for kind, style in (("cold", "-"), ("warm", "--")):
                run = rec[kind]
                if "error" in run:
                    continue
                gap = np.maximum(run["best_loss"] - best, floor)
                ax.step(
                    run["times"], gap, style, where="post", color=color, label=rec["tuner"] if kind == "cold" else None
                )
        for frac in TARGETS:
            ax.axhline(frac * abs(best), color="grey", lw=0.7, ls=":")
        ax.set(xscale="log", yscale="log", xlabel="seconds since the call (cold: compile included)", title=problem)
        ax.grid(alpha=0.3, which="both")
    axes[0][0].set_ylabel("best loss − best known (floor 1e-6·|L*|)")
    axes[0][-1].legend(fontsize=8)
    fig.suptitle("tuning race: cold (solid), warm (dashed); dotted: 1 % and 0.1 % gaps", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _jsonable(records: list[dict[str, Any]]) -> list[dict[str, Any]]:
    def conv(run: dict[str, Any]) -> dict[str, Any]:
        return {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in run.items()}

    return [{**rec, "cold": conv(rec["cold"]), "warm": conv(rec["warm"])} for rec in records]


def write_outputs(out: Path, settings: dict[str, Any], records: list, rows: list) -> None:
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "tuning_race.json", "w") as fh:
        json.dump({"settings": settings, "summary": rows, "runs": _jsonable(records)}, fh, indent=1, default=float)
    keys = list(dict.fromkeys(k for r in rows for k in r))
    with open(out / "tuning_race.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, keys)
        w.writeheader()
        w.writerows(rows)
    plot(records, rows, out / "tuning_race.png")


def with_overrides(budgets: dict[str, Budget], overrides: list[str]) -> dict[str, Budget]:
    """``budgets`` with each ``"problem.field=value"`` applied (a positive count, or the float
    ``adam_lr``)."""
    out = dict(budgets)
    fields = {f.name: f.type for f in dataclasses.fields(Budget)}
    for item in overrides:
        name, _, value = item.partition("=")
        problem, _, field = name.partition(".")
        if problem not in out or field not in fields or not value:
            raise ValueError(
                f"{item!r}: expected PROBLEM.FIELD=N with PROBLEM in {sorted(out)}, FIELD in {sorted(fields)}"
            )
        try:
            number = float(value) if fields[field] == "float" else int(value)
        except ValueError:
            raise ValueError(f"{item!r}: {value!r} is not a valid {fields[field]}") from None
        if number <= 0:
            raise ValueError(f"{item!r}: must be positive")
        out[problem] = dataclasses.replace(out[problem], **{field: number})
    return out


def main(argv: list[str] | None = None) -> list[dict[str, Any]]:
    ap = argparse.ArgumentParser(
        description=__doc__.split("\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__
    )
    ap.add_argument("--quick", action="store_true", help="tiny: the PID problem only, 1 round, half budgets")
    ap.add_argument("--problems", nargs="+", choices=PROBLEMS, default=None, help="default: all three")
    ap.add_argument("--tuners", nargs="+", choices=TUNERS, default=None, help="default: all")
    ap.add_argument("--rounds", type=int, default=None, help="interleaved rounds (default 3; --quick: 1)")
    ap.add_argument("--trms-t-final", type=float, default=30.0, help="TRMS horizon, s (the study's quick: 30)")
    ap.add_argument(
        "--mode",
        choices=["auto", "forward", "reverse", "measure"],
        default="auto",
        help="AD mode of the gradient tuners (optim.tune's mode; 'measure' times both on the first call)",
    )
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--reference", type=float, nargs="*", default=None, help="best known loss per problem, in order")
    ap.add_argument(
        "--budget",
        nargs="+",
        default=[],
        metavar="PROBLEM.FIELD=N",
        help="override one count of a problem's Budget, e.g. fuzzy.particles=16 fuzzy.iters=16",
    )
    ap.add_argument("--out", default="results/tuning_race", help="folder for the JSON, CSV and PNG")
    args = ap.parse_args(argv)
    problems = args.problems or (["pid"] if args.quick else list(PROBLEMS))
    tuners = args.tuners or list(TUNERS)
    rounds = args.rounds or (1 if args.quick else 3)
    if rounds < 1:
        ap.error("--rounds: must be ≥ 1")
    budgets = {k: b.scaled(0.5) for k, b in BUDGETS.items()} if args.quick else dict(BUDGETS)
    try:
        budgets = with_overrides(budgets, args.budget)
    except ValueError as err:
        ap.error(f"--budget: {err}")
    reference = dict(zip(problems, args.reference)) if args.reference else None
    load = os.getloadavg()
    print(f"tuning race: {problems} × {tuners}, {rounds} round(s); load average {load[0]:.2f} on {os.cpu_count()} cpus")
    built = build_problems(problems, args.trms_t_final)
    records = race(built, tuners, rounds, args.seed, budgets, mode=args.mode)
    rows = summarise(records, reference)
    print(format_table(rows))
    settings = {
        "problems": problems,
        "tuners": tuners,
        "rounds": rounds,
        "seed": args.seed,
        "mode": args.mode,
        "trms_t_final": args.trms_t_final,
        "quick": args.quick,
        "budgets": {k: dataclasses.asdict(budgets[k]) for k in problems},
        "load_average_before": load,
        "load_average_after": os.getloadavg(),
        "cpus": os.cpu_count(),
        "devices": [str(d) for d in jax.devices()],
        "jax": jax.__version__,
    }
    write_outputs(Path(args.out), settings, records, rows)
    print(f"wrote {args.out}/tuning_race.json, .csv, .png")
    return rows


if __name__ == "__main__":
    main()
