"""Mamdani inference against scikit-fuzzy's control API on random systems (agreement 1e-6).

scikit-fuzzy fuzzifies an input by interpolating each term sampled on the input's universe, so the
test inputs are universe points (where the interpolation is exact for every MF kind).  Its output
set is built on the output universe with the cut points inserted and defuzzified as a
piecewise-linear function: the same semantics as ours on the same grid.
"""

import warnings
from functools import partial

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.optimize
import skfuzzy as fuzz
from skfuzzy import control as ctrl
from skfuzzy.control.controlsystem import CrispValueCalculator

from jaxsim.control import fuzzy as fz
from jaxsim.control.fuzzy import defuzzify as dfz

SK_MF = {
    "triangular": lambda x, p: fuzz.trimf(x, p),
    "trapezoidal": lambda x, p: fuzz.trapmf(x, p),
    "gaussian": lambda x, p: fuzz.gaussmf(x, p[0], p[1]),
    "bell": lambda x, p: fuzz.gbellmf(x, p[0], p[1], p[2]),
    "piecewise_linear": lambda x, p: np.interp(x, p[: p.size // 2], p[p.size // 2 :]),
}


def _term_params(kind, n_terms, rng, lo=-1.6, hi=1.6):
    centres = np.sort(rng.uniform(lo, hi, n_terms))
    rows = []
    for c in centres:
        w = rng.uniform(0.4, 1.2, 2)
        if kind == "triangular":
            rows.append([c - w[0], c + rng.uniform(-0.1, 0.1), c + w[1]])
        elif kind == "trapezoidal":
            rows.append([c - w[0], c - 0.2 * w[0], c + 0.2 * w[1], c + w[1]])
        elif kind == "gaussian":
            rows.append([c, 0.5 * w[0]])
        elif kind == "bell":
            rows.append([0.6 * w[0], rng.uniform(1.0, 3.0), c])
        else:  # piecewise-linear, possibly two-humped
            xs = np.sort(c + rng.uniform(-1.0, 1.0, 4))
            rows.append(np.concatenate([xs, rng.uniform(0.0, 1.0, 4)]))
    rows = np.array(rows, float)
    if kind == "triangular":
        rows.sort(axis=1)
    return rows


def _random_system(seed):
    rng = np.random.default_rng(seed)
    in_kinds = [
        ["triangular", "gaussian"],
        ["trapezoidal", "bell"],
        ["gaussian", "triangular"],
        ["bell", "trapezoidal"],
    ][seed % 4]
    out_kind = ["triangular", "gaussian", "trapezoidal", "piecewise_linear"][seed % 4]
    n_terms = [int(rng.integers(3, 5)), int(rng.integers(3, 5))]
    inputs = [(k, _term_params(k, n, rng)) for k, n in zip(in_kinds, n_terms)]
    n_out = int(rng.integers(3, 6))
    out_params = _term_params(out_kind, n_out, rng)
    grid = np.linspace(-2.5, 2.5, int(rng.integers(41, 81)))
    connective = "or" if seed % 3 == 2 else "and"
    ant = [(i, j) for i in range(n_terms[0]) for j in range(n_terms[1])]
    ant = [a for a in ant if rng.uniform() < 0.8]
    ant += [(int(rng.integers(n_terms[0])), -1), (-1, int(rng.integers(n_terms[1])))]  # rules testing one input
    cons = rng.integers(0, n_out, len(ant))
    options = dict(and_norm="product" if seed % 2 else "min", accumulation="probor" if seed % 4 == 3 else "max")
    return inputs, (out_kind, out_params), grid, fz.rule_base(ant, cons, connective), options


def _skfuzzy_system(inputs, output, grid, rules, options, defuzzifier):
    universes = [np.linspace(-2.5, 2.5, 101) for _ in inputs]
    ants = [ctrl.Antecedent(u, f"x{i}") for i, u in enumerate(universes)]
    for a, (kind, params) in zip(ants, inputs):
        for t, row in enumerate(params):
            a[f"t{t}"] = SK_MF[kind](a.universe, row)
    con = ctrl.Consequent(grid, "z", defuzzify_method=defuzzifier)
    for t, row in enumerate(output[1]):
        con[f"t{t}"] = SK_MF[output[0]](grid, row)
    if options["accumulation"] == "probor":
        con.accumulation_method = lambda a, b: a + b - a * b
    and_func = np.multiply if options["and_norm"] == "product" else np.fmin
    sk_rules = []
    for k, (row, c) in enumerate(zip(rules.antecedents, rules.consequents)):
        tests = [ants[i][f"t{j}"] for i, j in enumerate(row) if j >= 0]
        expr = tests[0]
        for term in tests[1:]:
            expr = (expr & term) if rules.connective == "and" else (expr | term)
        sk_rules.append(ctrl.Rule(expr, con[f"t{c}"], label=f"r{k}", and_func=and_func))
    return ctrl.ControlSystemSimulation(ctrl.ControlSystem(sk_rules)), universes, con


def _bisector_by_root_finding(xs, mu):
    """The bisector of the piecewise-linear set, by bracketing the half-area point (an oracle)."""
    seg = 0.5 * np.diff(xs) * (mu[1:] + mu[:-1])
    cum = np.concatenate([[0.0], np.cumsum(seg)])

    def area_left_of(t):
        k = np.clip(np.searchsorted(xs, t, side="right") - 1, 0, len(xs) - 2)
        yt = np.interp(t, xs, mu)
        return cum[k] + 0.5 * (t - xs[k]) * (mu[k] + yt)

    return scipy.optimize.brentq(lambda t: area_left_of(t) - 0.5 * cum[-1], xs[0], xs[-1], xtol=1e-14)


def _skfuzzy_bisector_is_ill_conditioned(xs, mu):
    """scikit-fuzzy solves the bisecting segment with x1 − (y1 − sqrt(y1² + 2m·A))/m, which cancels
    catastrophically when the slope m is tiny but not zero (y1 and y2 a rounding error apart)."""
    seg = 0.5 * np.diff(xs) * (mu[1:] + mu[:-1])
    k = int(np.argmax(np.cumsum(seg) >= 0.5 * seg.sum()))
    return 0 < abs(mu[k + 1] - mu[k]) < 1e-9 * max(mu[k], mu[k + 1])


@pytest.mark.parametrize("seed", range(4))
def test_mamdani_equals_skfuzzy_on_random_systems(seed):
    inputs, output, grid, rules, options = _random_system(seed)
    rng = np.random.default_rng(100 + seed)
    ours = {
        name: jax.jit(partial(fz.evaluate, fz.mamdani(inputs, grid, output, rules, defuzzifier=name, **options)))
        for name in ("centroid", "bisector")
    }
    output_set = jax.jit(partial(fz.output_set, fz.mamdani(inputs, grid, output, rules, **options)))
    sim, universes, con = _skfuzzy_system(inputs, output, grid, rules, options, "centroid")
    compared = 0
    for _ in range(12):
        x = np.array([u[rng.integers(10, len(u) - 10)] for u in universes])
        xs, mu = (np.asarray(v) for v in output_set(jnp.asarray(x)))
        if np.trapezoid(mu, xs) < 1e-9:
            continue  # no rule fires (scikit-fuzzy raises), or a 1e-35 Gaussian tail it divides by eps
        sim.input["x0"], sim.input["x1"] = x
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            sim.compute()
        # the output set itself: scikit-fuzzy's upsampled universe and membership
        ref_x, ref_mu, _ = CrispValueCalculator(con, sim).find_memberships()
        distinct = np.concatenate([[True], np.diff(xs) > 0])
        np.testing.assert_allclose(xs[distinct], ref_x, atol=1e-12)
        np.testing.assert_allclose(mu[distinct], ref_mu, atol=1e-12)
        # defuzzified: the control API's centroid; its bisector is defuzz() of the same set
        assert float(ours["centroid"](jnp.asarray(x))) == pytest.approx(sim.output["z"], abs=1e-6, rel=0)
        ref = fuzz.defuzz(ref_x, ref_mu, "bisector")
        if _skfuzzy_bisector_is_ill_conditioned(ref_x, ref_mu):
            ref = _bisector_by_root_finding(ref_x, ref_mu)
        assert float(ours["bisector"](jnp.asarray(x))) == pytest.approx(ref, abs=1e-6, rel=0), x
        compared += 1
    assert compared >= 8


@jax.jit
def _all_defuzzified(grid, term_mf, levels):
    general = dfz.clipped_points(grid, term_mf, levels)
    merged = dfz.clipped_points_unimodal(grid, term_mf, levels)
    names = ("centroid", "bisector", "mom", "som", "lom")
    return (
        dfz.centroid_clipped_unimodal(grid, term_mf, levels),
        jnp.stack([dfz.DEFUZZIFIERS[n](*general) for n in names]),
        jnp.stack([dfz.DEFUZZIFIERS[n](*merged) for n in names]),
    )


def test_fast_unimodal_centroid_equals_the_general_construction():
    rng = np.random.default_rng(7)
    grid = jnp.linspace(-2.0, 2.0, 57)
    for kind in ("triangular", "trapezoidal", "gaussian", "bell"):
        term_mf = fz.terms(kind, _term_params(kind, 5, rng))(grid).T
        for levels in (rng.uniform(0, 1, 5), np.array([0.0, 1.0, 0.3, 0.3, 0.0]), np.ones(5)):
            fast, general, merged = _all_defuzzified(grid, term_mf, jnp.asarray(levels))
            assert float(fast) == pytest.approx(float(general[0]), abs=1e-13)
            np.testing.assert_allclose(merged, general, atol=1e-12)


def test_maximum_defuzzifiers_on_a_clipped_trapezoid():
    # one rule firing a trapezoid (a, b, c, d) at level α: the plateau is [a + α(b−a), d − α(d−c)]
    a, b, c, d = -0.83, -0.21, 0.37, 1.12
    grid = np.linspace(-2.0, 2.0, 41)
    fis_of = lambda name: fz.mamdani(  # noqa: E731
        [("triangular", [[-1.0, 0.0, 1.0]])],
        grid,
        ("trapezoidal", [[a, b, c, d]]),
        fz.rule_base([[0]], [0]),
        defuzzifier=name,
    )
    x = 0.35  # membership 0.65 in the input triangle
    alpha = 0.65
    lo, hi = a + alpha * (b - a), d - alpha * (d - c)
    plateau = np.concatenate([[lo], grid[(grid > lo) & (grid < hi)], [hi]])
    ev = jax.jit(fz.evaluate)
    assert float(ev(fis_of("som"), jnp.asarray([x]))) == pytest.approx(lo, abs=1e-12)
    assert float(ev(fis_of("lom"), jnp.asarray([x]))) == pytest.approx(hi, abs=1e-12)
    assert float(ev(fis_of("mom"), jnp.asarray([x]))) == pytest.approx(plateau.mean(), abs=1e-12)


def test_larsen_and_maximum_defuzzifiers_equal_skfuzzy_defuzz():
    # Larsen (product implication) has no cut points: the output set is max_t α_t μ_t on the grid,
    # which scikit-fuzzy's defuzz() takes directly.
    rng = np.random.default_rng(3)
    inputs, output, grid, rules, options = _random_system(5)
    ev = jax.jit(fz.evaluate)
    activations = jax.jit(lambda fis, x: fz.term_activations(fis, fz.firing_strengths(fis, x)))
    for name in ("centroid", "bisector", "mom", "som", "lom"):
        fis = fz.larsen(inputs, grid, output, rules, defuzzifier=name, **options)
        for _ in range(6):
            x = jnp.asarray(rng.uniform(-1.2, 1.2, 2))
            alpha = np.asarray(activations(fis, x))
            mu = np.max(alpha[:, None] * np.stack([SK_MF[output[0]](grid, r) for r in output[1]]), axis=0)
            if mu.max() == 0:
                continue
            ref = fuzz.defuzz(grid, mu, name)
            assert float(ev(fis, x)) == pytest.approx(ref, abs=1e-9), name


def test_empty_output_set_returns_the_grid_middle():
    fis = fz.mamdani(
        [("triangular", [[-1.0, 0.0, 1.0]])],
        np.linspace(-1.0, 3.0, 21),
        ("triangular", [[0.0, 1.0, 2.0]]),
        fz.rule_base([[0]], [0]),
    )
    assert float(jax.jit(fz.evaluate)(fis, jnp.asarray([5.0]))) == pytest.approx(1.0)


@pytest.mark.parametrize("n", [1, 2, 5, 14, 16, 37, 70])
def test_sort_along_first_axis_equals_a_sort(n):
    rng = np.random.default_rng(n)
    keys = rng.uniform(-1, 1, (n, 3))
    keys[n // 2] = keys[0]  # ties
    rows = np.repeat(np.arange(n, dtype=np.int32)[:, None], 3, axis=1)  # payload: each key's original row
    ks, moved = jax.jit(dfz.sort_along_first_axis)(jnp.asarray(keys), jnp.asarray(rows))
    np.testing.assert_array_equal(ks, np.sort(keys, axis=0))
    np.testing.assert_array_equal(keys[np.asarray(moved), np.arange(3)], ks)  # payload moved with its key
    assert moved.dtype == jnp.asarray(rows).dtype


def test_fast_centroid_when_cut_points_fall_on_grid_nodes():
    # Triangles with corners on a 1/30 lattice, evaluated at lattice inputs: many cut points land
    # exactly on output-grid nodes and on each other (ties the fast path must not divide by).
    c = np.linspace(-1.0, 1.0, 7)
    tri = np.stack([c - 1 / 3, c, c + 1 / 3], axis=1)
    table = np.clip(np.add.outer(np.arange(7), np.arange(7)) - 3, 0, 6)
    fis = fz.mamdani(
        [("triangular", tri)] * 2, np.linspace(-1.5, 1.5, 101), ("triangular", tri), fz.grid_rule_base(table)
    )
    xs = np.stack(np.meshgrid(np.linspace(-1, 1, 61), np.linspace(-1, 1, 61)), -1).reshape(-1, 2)
    # the same system with piecewise-linear output terms takes the general (per-interval sort) path
    p = np.asarray(fis.output.terms.params)
    pl = np.concatenate([p, np.tile([0.0, 1.0, 0.0], (p.shape[0], 1))], axis=1)
    general_fis = fz.mamdani(list(fis.inputs), fis.output.grid, ("piecewise_linear", pl), fis.rules)
    batch = lambda f: jax.jit(jax.vmap(lambda x: fz.evaluate(f, x)))(jnp.asarray(xs))  # noqa: E731
    np.testing.assert_allclose(batch(fis), batch(general_fis), atol=1e-12)
