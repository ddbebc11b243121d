"""Sugeno inference against simpful on random systems (agreement 1e-6); Tsukamoto invariants."""

import contextlib
import io

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.optimize
import simpful

from jaxsim.control import fuzzy as fz

SIMPFUL_MF = {
    "triangular": lambda p: simpful.Triangular_MF(*p),
    "trapezoidal": lambda p: simpful.Trapezoidal_MF(*p),
    "gaussian": lambda p: simpful.Gaussian_MF(p[0], p[1]),
    "sigmoid": lambda p: simpful.Sigmoid_MF(p[0], p[1]),
}


def _params(kind, n, rng):
    c = np.sort(rng.uniform(-1.5, 1.5, n))
    if kind == "triangular":
        return np.stack([c - rng.uniform(0.5, 1.2, n), c, c + rng.uniform(0.5, 1.2, n)], 1)
    if kind == "trapezoidal":
        return np.stack([c - 1.0, c - 0.3, c + 0.2, c + rng.uniform(0.6, 1.2, n)], 1)
    if kind == "gaussian":
        return np.stack([c, rng.uniform(0.3, 0.9, n)], 1)
    return np.stack([c, rng.choice([-1, 1], n) * rng.uniform(1.0, 5.0, n)], 1)


def _random_sugeno(seed):
    rng = np.random.default_rng(seed)
    kinds = [
        ("triangular", "gaussian"),
        ("trapezoidal", "sigmoid"),
        ("gaussian", "triangular"),
        ("sigmoid", "trapezoidal"),
    ][seed % 4]
    n_terms = [3, 4]
    inputs = [(k, _params(k, n, rng)) for k, n in zip(kinds, n_terms)]
    n_out = 4
    order = seed % 2  # zero or first order
    coef = rng.uniform(-2, 2, (n_out, 1 if order == 0 else 3))
    ant = [(i, j) for i in range(3) for j in range(4) if rng.uniform() < 0.85] + [(1, -1), (-1, 2)]
    connective = "or" if seed % 3 == 2 else "and"
    rules = fz.rule_base(ant, rng.integers(0, n_out, len(ant)), connective)
    and_norm = "product" if seed in (1, 2) else "min"
    return inputs, coef, rules, and_norm


def _simpful_system(inputs, coef, rules, and_norm):
    with contextlib.redirect_stdout(io.StringIO()):
        fs = simpful.FuzzySystem(
            show_banner=False, verbose=False, operators=["AND_PRODUCT"] if and_norm == "product" else None
        )
        for i, (kind, params) in enumerate(inputs):
            sets = [simpful.FuzzySet(function=SIMPFUL_MF[kind](row), term=f"t{t}") for t, row in enumerate(params)]
            fs.add_linguistic_variable(f"x{i}", simpful.LinguisticVariable(sets, universe_of_discourse=[-3, 3]))
        for m, row in enumerate(coef):
            if row.size == 1:
                fs.set_crisp_output_value(f"o{m}", float(row[0]))
            else:
                c0, c1, c2 = (repr(float(v)) for v in row)
                fs.set_output_function(f"o{m}", f"{c0} + ({c1})*x0 + ({c2})*x1")
        joint = " AND " if rules.connective == "and" else " OR "
        texts = []
        for ant, c in zip(rules.antecedents, rules.consequents):
            tests = [f"(x{i} IS t{j})" for i, j in enumerate(ant) if j >= 0]
            texts.append(f"IF {joint.join(tests)} THEN (z IS o{c})")
        fs.add_rules(texts)
    return fs


@pytest.mark.parametrize("seed", range(6))
def test_sugeno_equals_simpful_on_random_systems(seed):
    inputs, coef, rules, and_norm = _random_sugeno(seed)
    fis = fz.sugeno(inputs, coef, rules, and_norm=and_norm)
    ev = jax.jit(fz.evaluate)
    fs = _simpful_system(inputs, coef, rules, and_norm)
    rng = np.random.default_rng(50 + seed)
    for _ in range(15):
        x = rng.uniform(-2.0, 2.0, 2)
        with contextlib.redirect_stdout(io.StringIO()):
            fs.set_variable("x0", float(x[0]))
            fs.set_variable("x1", float(x[1]))
            ref = fs.Sugeno_inference(["z"], ignore_warnings=True)["z"]
        assert float(ev(fis, jnp.asarray(x))) == pytest.approx(ref, abs=1e-6, rel=0), x


def test_sugeno_with_no_firing_rule_returns_zero_like_simpful():
    fis = fz.sugeno([("triangular", [[0.0, 1.0, 2.0]])], [3.0], fz.rule_base([[0]], [0]))
    assert float(fz.evaluate(fis, jnp.asarray([5.0]))) == 0.0


def test_tsukamoto_rule_outputs_invert_their_terms():
    # Each rule's output z_r satisfies μ_cons(r)(z_r) = w_r, and the result is Σ w z / Σ w.
    rng = np.random.default_rng(4)
    inputs = [("triangular", _params("triangular", 3, rng)), ("gaussian", _params("gaussian", 3, rng))]
    rules = fz.rule_base([(i, j) for i in range(3) for j in range(3)], rng.integers(0, 3, 9))
    for out_kind, out_params in (
        ("piecewise_linear", [[-1.0, 0.5, 0.0, 1.0], [0.0, 2.0, 1.0, 0.0], [-2.0, -1.0, 0.0, 1.0]]),
        ("sigmoid", [[0.0, 3.0], [1.0, -2.0], [-0.5, 5.0]]),
    ):
        fis = fz.tsukamoto(inputs, (out_kind, out_params), rules)
        ev = jax.jit(fz.evaluate)
        for _ in range(10):
            x = jnp.asarray(rng.uniform(-1.0, 1.0, 2))
            w = np.asarray(fz.firing_strengths(fis, x))
            if w.sum() == 0:
                continue
            cons = np.asarray(rules.consequents)
            z = np.array([_invert_numerically(fis.output.terms, c, wr) for c, wr in zip(cons, w)])
            expected = np.sum(w * z) / np.sum(w)
            assert float(ev(fis, x)) == pytest.approx(expected, abs=1e-8)


def _invert_numerically(terms, c, w):
    """Solve μ_c(z) = w by bracketing on the monotone term (an independent inverse, in NumPy)."""
    p = np.asarray(terms.params[c])
    if terms.kind == "piecewise_linear":
        k = p.size // 2
        xs, ys = p[:k], p[k:]
        mu, lo, hi = (lambda z: np.interp(z, xs, ys)), xs[0], xs[-1]
        w = min(max(w, ys.min()), ys.max())
    else:
        mu, lo, hi = (lambda z: 1.0 / (1.0 + np.exp(-p[1] * (z - p[0])))), -50.0, 50.0
        w = min(max(w, 1e-12), 1 - 1e-12)
    return scipy.optimize.brentq(lambda z: mu(z) - w, lo, hi, xtol=1e-13)


def test_tsukamoto_rejects_non_monotone_terms():
    with pytest.raises(ValueError, match="output_terms"):
        fz.tsukamoto(
            [("triangular", [[0.0, 1.0, 2.0]])],
            ("piecewise_linear", [[0.0, 1.0, 2.0, 0.0, 1.0, 0.0]]),
            fz.rule_base([[0]], [0]),
        )
    with pytest.raises(ValueError, match="output_terms"):
        fz.tsukamoto([("triangular", [[0.0, 1.0, 2.0]])], ("gaussian", [[0.0, 1.0]]), fz.rule_base([[0]], [0]))
