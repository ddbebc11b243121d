"""Benchmark: evaluations per second of a two-input, 49-rule Mamdani fuzzy controller.

The system is the classic PD-type fuzzy controller: error and error rate each with seven
triangular terms (NB … PB, peaks at −1, −2/3, …, 1), a 7×7 rule table ``cons = clip(i + j − 3)``,
seven triangular output terms, min implication, max aggregation, centroid on a 101-point output
grid.  Everything is evaluated on the same grids by

* ours: ``jax.jit(jax.vmap(fuzzy.evaluate))`` over the whole batch, and ``fuzzy.evaluate_batch``
  (the same vmap over chunks of 1024 inputs, which keeps intermediates in cache) — float64,
  optionally float32;
* scikit-fuzzy: ``ControlSystemSimulation.compute()`` one input at a time, and its array mode
  (one ``compute()`` on arrays of inputs);
* simpful: ``Mamdani_inference`` one input at a time (it integrates on its own grid of
  ``subdivisions`` points, so its values differ slightly: the difference is printed).

Peers are timed on a subset and reported as evaluations per second; the agreement of ours with
scikit-fuzzy on that subset is printed next to the speed.

Usage: ``python -m experiments.benchmarks.fuzzy_inference [--n 100000] [--subset 200] [--repeats 3]``
"""

from __future__ import annotations

import argparse
import contextlib
import io
import time
import warnings

import jax
import jax.numpy as jnp
import numpy as np

import jaxsim  # noqa: F401  (float64)
from experiments.benchmarks.timing import median_time, write_json
from jaxsim.control import fuzzy as fz

T = 7
N_INPUT = 121  # input universe (the triangle corners lie on it, so scikit-fuzzy's interpolation is exact)
N_OUTPUT = 101


def system_definition():
    centres = np.linspace(-1.0, 1.0, T)
    w = centres[1] - centres[0]
    tri = np.stack([centres - w, centres, centres + w], axis=1)
    table = np.clip(np.add.outer(np.arange(T), np.arange(T)) - 3, 0, T - 1)
    return tri, table, np.linspace(-1.0, 1.0, N_INPUT), np.linspace(-1.5, 1.5, N_OUTPUT)


def ours_fn(dtype=jnp.float64, batch_size: int | None = None):
    """Jitted batch evaluation: one ``vmap`` over the whole batch, or over chunks (``evaluate_batch``)."""
    tri, table, _, grid = system_definition()
    fis = fz.mamdani([("triangular", tri), ("triangular", tri)], grid, ("triangular", tri), fz.grid_rule_base(table))
    fis = jax.tree_util.tree_map(lambda leaf: jnp.asarray(leaf, dtype), fis)
    if batch_size is None:
        return jax.jit(jax.vmap(lambda x: fz.evaluate(fis, x)))
    return jax.jit(lambda xs: fz.evaluate_batch(fis, xs, batch_size=batch_size))


def skfuzzy_sim():
    import skfuzzy as fuzz
    from skfuzzy import control as ctrl

    tri, table, universe, grid = system_definition()
    ants = [ctrl.Antecedent(universe, name) for name in ("e", "de")]
    for a in ants:
        for t in range(T):
            a[f"t{t}"] = fuzz.trimf(universe, tri[t])
    out = ctrl.Consequent(grid, "u")
    for t in range(T):
        out[f"t{t}"] = fuzz.trimf(grid, tri[t])
    rules = [
        ctrl.Rule(ants[0][f"t{i}"] & ants[1][f"t{j}"], out[f"t{table[i, j]}"], label=f"r{i}{j}")
        for i in range(T)
        for j in range(T)
    ]
    return ctrl.ControlSystemSimulation(ctrl.ControlSystem(rules))


def simpful_system(subdivisions: int):
    import simpful

    tri, table, _, _ = system_definition()
    with contextlib.redirect_stdout(io.StringIO()):
        fs = simpful.FuzzySystem(show_banner=False, verbose=False)
        for name in ("e", "de"):
            sets = [simpful.FuzzySet(function=simpful.Triangular_MF(*tri[t]), term=f"t{t}") for t in range(T)]
            fs.add_linguistic_variable(name, simpful.LinguisticVariable(sets, universe_of_discourse=[-1, 1]))
        sets = [simpful.FuzzySet(function=simpful.Triangular_MF(*tri[t]), term=f"t{t}") for t in range(T)]
        fs.add_linguistic_variable("u", simpful.LinguisticVariable(sets, universe_of_discourse=[-1.5, 1.5]))
        fs.add_rules(
            [f"IF (e IS t{i}) AND (de IS t{j}) THEN (u IS t{table[i, j]})" for i in range(T) for j in range(T)]
        )
    return fs


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=100_000, help="batch of inputs for ours")
    ap.add_argument("--subset", type=int, default=200, help="inputs timed for the peers")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--batch-size", type=int, default=1024, help="chunk of evaluate_batch")
    ap.add_argument("--subdivisions", type=int, default=1000, help="simpful's integration grid")
    ap.add_argument("--float32", action="store_true", help="also time our float32 fast path")
    ap.add_argument("--json", default=None, help="write the numbers to this file")
    args = ap.parse_args(argv)

    _, _, universe, _ = system_definition()
    rng = np.random.default_rng(0)
    x = universe[rng.integers(0, N_INPUT, size=(args.n, 2))]  # on the input universe (exact for all)
    out = {"n": args.n, "subset": args.subset, "devices": str(jax.devices())}

    xs = jnp.asarray(x)
    fn = ours_fn(batch_size=args.batch_size)
    start = time.perf_counter()
    ours = np.asarray(fn(xs).block_until_ready())
    out["ours_first_call_s"] = time.perf_counter() - start
    out["ours_evals_per_s"] = args.n / median_time(lambda: fn(xs).block_until_ready(), args.repeats)
    whole = ours_fn()
    np.testing.assert_allclose(np.asarray(whole(xs)), ours, rtol=0, atol=1e-12)
    out["ours_whole_batch_vmap_evals_per_s"] = args.n / median_time(lambda: whole(xs).block_until_ready(), args.repeats)
    if args.float32:
        fn32 = ours_fn(jnp.float32, batch_size=args.batch_size)
        x32 = jnp.asarray(x, jnp.float32)
        fn32(x32).block_until_ready()
        out["ours_float32_evals_per_s"] = args.n / median_time(lambda: fn32(x32).block_until_ready(), args.repeats)

    sub = x[: args.subset]
    sim = skfuzzy_sim()
    ref = np.empty(len(sub))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        start = time.perf_counter()
        for k, (e, de) in enumerate(sub):
            sim.input["e"], sim.input["de"] = e, de
            sim.compute()
            ref[k] = sim.output["u"]
        out["skfuzzy_evals_per_s"] = len(sub) / (time.perf_counter() - start)
        sim_arr = skfuzzy_sim()
        start = time.perf_counter()
        sim_arr.input["e"], sim_arr.input["de"] = sub[:, 0].copy(), sub[:, 1].copy()
        sim_arr.compute()
        ref_arr = np.asarray(sim_arr.output["u"])
        out["skfuzzy_array_evals_per_s"] = len(sub) / (time.perf_counter() - start)

    fs = simpful_system(args.subdivisions)
    n_sp = max(2, args.subset // 4)
    sp = np.empty(n_sp)
    with contextlib.redirect_stdout(io.StringIO()):
        start = time.perf_counter()
        for k, (e, de) in enumerate(sub[:n_sp]):
            fs.set_variable("e", float(e))
            fs.set_variable("de", float(de))
            sp[k] = fs.Mamdani_inference(["u"], subdivisions=args.subdivisions)["u"]
        out["simpful_evals_per_s"] = n_sp / (time.perf_counter() - start)

    out["ratio_vs_skfuzzy"] = out["ours_evals_per_s"] / out["skfuzzy_evals_per_s"]
    out["ratio_vs_skfuzzy_array"] = out["ours_evals_per_s"] / out["skfuzzy_array_evals_per_s"]
    out["ratio_vs_simpful"] = out["ours_evals_per_s"] / out["simpful_evals_per_s"]
    out["max_abs_diff_vs_skfuzzy"] = float(np.max(np.abs(ours[: args.subset] - ref)))
    out["max_abs_diff_vs_skfuzzy_array"] = float(np.max(np.abs(ours[: args.subset] - ref_arr)))
    out["max_abs_diff_vs_simpful"] = float(np.max(np.abs(ours[:n_sp] - sp)))

    print(f"Mamdani, 2 inputs × 7 terms, 49 rules, centroid on {N_OUTPUT} points; devices {out['devices']}")
    print(
        f"  ours (evaluate_batch: jit+vmap over chunks of {args.batch_size}, float64, {args.n} inputs): "
        f"{out['ours_evals_per_s']:,.0f} evals/s (median of {args.repeats}; first call incl. compile "
        f"{out['ours_first_call_s']:.2f} s)"
    )
    print(f"  ours (one vmap over all {args.n}):  {out['ours_whole_batch_vmap_evals_per_s']:,.0f} evals/s")
    if args.float32:
        print(f"  ours (float32):                 {out['ours_float32_evals_per_s']:,.0f} evals/s")
    print(f"  scikit-fuzzy, one compute per input: {out['skfuzzy_evals_per_s']:,.1f} evals/s ({args.subset} inputs)")
    print(f"  scikit-fuzzy, array inputs:          {out['skfuzzy_array_evals_per_s']:,.1f} evals/s")
    print(
        f"  simpful (subdivisions {args.subdivisions}):     {out['simpful_evals_per_s']:,.1f} evals/s ({n_sp} inputs)"
    )
    print(
        f"  speed-up: {out['ratio_vs_skfuzzy']:,.0f}x vs scikit-fuzzy, {out['ratio_vs_skfuzzy_array']:,.0f}x vs "
        f"its array mode, {out['ratio_vs_simpful']:,.0f}x vs simpful"
    )
    print(
        f"  max |ours − scikit-fuzzy| = {out['max_abs_diff_vs_skfuzzy']:.1e} (array mode "
        f"{out['max_abs_diff_vs_skfuzzy_array']:.1e}); |ours − simpful| = {out['max_abs_diff_vs_simpful']:.1e} "
        "(simpful integrates on its own grid)"
    )
    write_json(args.json, out)
    return out


if __name__ == "__main__":
    main()
