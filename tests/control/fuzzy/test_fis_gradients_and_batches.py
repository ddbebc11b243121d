"""Gradients of fuzzy systems w.r.t. every parameter equal central differences; vmap == loop;
rule bases and norms reject bad input."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.control import fuzzy as fz


def _mamdani(defuzzifier="centroid", implication="min", out_kind="triangular"):
    inputs = [
        ("gaussian", [[-1.0, 0.5], [0.0, 0.4], [1.0, 0.6]]),
        ("triangular", [[-2.0, -1.0, 0.2], [-0.9, 0.1, 1.1], [0.0, 1.0, 2.0]]),
    ]
    out = {
        "triangular": [[-2.0, -1.0, 0.1], [-1.1, 0.05, 1.0], [0.0, 1.0, 2.1]],
        "bell": [[0.6, 2.0, -1.0], [0.5, 1.5, 0.0], [0.7, 2.5, 1.0]],
    }[out_kind]
    rules = fz.grid_rule_base([[0, 0, 1], [0, 1, 2], [1, 2, 2]])
    return fz.mamdani(
        inputs,
        np.linspace(-2.5, 2.5, 51),
        (out_kind, out),
        rules,
        defuzzifier=defuzzifier,
        implication=implication,
        weights=np.full(9, 0.9),
    )


def _sugeno():
    inputs = [("bell", [[0.8, 2.0, -1.0], [0.8, 2.0, 1.0]]), ("sigmoid", [[0.0, 3.0], [0.5, -2.0]])]
    return fz.sugeno(
        inputs,
        [[0.1, 1.0, -0.5], [0.5, -0.3, 0.8], [-0.4, 0.2, 0.3]],
        fz.rule_base([[0, 0], [0, 1], [1, 0], [1, 1]], [0, 1, 2, 0]),
        and_norm="product",
    )


def _tsukamoto():
    inputs = [("trapezoidal", [[-2.0, -1.2, -0.4, 0.3], [-0.5, 0.2, 0.9, 2.0]])]
    out = ("piecewise_linear", [[-1.0, 1.0, 0.0, 1.0], [-1.2, 0.8, 1.0, 0.0]])
    return fz.tsukamoto(inputs, out, fz.rule_base([[0], [1]], [0, 1]))


CASES = {
    "mamdani_centroid": (_mamdani, [0.13, -0.37]),
    "mamdani_bell_bisector": (lambda: _mamdani("bisector", out_kind="bell"), [0.41, 0.22]),
    "larsen_centroid": (lambda: _mamdani(implication="product"), [-0.52, 0.64]),
    "sugeno_first_order": (_sugeno, [0.27, -0.18]),
    "tsukamoto": (_tsukamoto, [-0.11]),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_gradient_wrt_every_parameter_equals_central_differences(case):
    make, x = CASES[case]
    fis = make()
    x = jnp.asarray(x)
    leaves, treedef = jax.tree_util.tree_flatten(fis)
    # differentiate every leaf except the output grid (a discretisation, not a parameter)
    grid_id = id(fis.output.grid) if isinstance(fis.output, fz.MamdaniOutput) else None
    idx = [k for k, leaf in enumerate(leaves) if id(leaf) != grid_id]

    def f(params):
        full = list(leaves)
        for k, p in zip(idx, params):
            full[k] = p
        return fz.evaluate(jax.tree_util.tree_unflatten(treedef, full), x)

    params = [jnp.asarray(leaves[k], float) for k in idx]
    grads = jax.jit(jax.grad(f))(params)
    f_jit = jax.jit(f)
    h = 1e-6
    checked = 0
    for p_i, (p, g) in enumerate(zip(params, grads)):
        flat = np.asarray(p).ravel()
        for j in range(flat.size):

            def shifted(delta):
                q = list(params)
                q[p_i] = jnp.asarray(flat.copy()).at[j].add(delta).reshape(p.shape)
                return float(f_jit(q))

            up, mid, down = shifted(h), float(f_jit(params)), shifted(-h)
            fwd, bwd = (up - mid) / h, (mid - down) / h
            if abs(fwd - bwd) > 1e-4 * max(1.0, abs(fwd)):
                continue  # a kink of the piecewise-linear construction: no derivative to compare
            assert float(np.asarray(g).ravel()[j]) == pytest.approx((up - down) / (2 * h), rel=1e-5, abs=1e-7)
            checked += 1
    assert checked >= 10


def test_vmap_over_system_parameters_equals_a_loop():
    base = _mamdani()
    rng = np.random.default_rng(0)
    n = 5
    shift = rng.uniform(-0.2, 0.2, n)
    scale = rng.uniform(0.8, 1.2, n)
    batch = jax.tree_util.tree_map(lambda leaf: jnp.stack([leaf] * n), base)
    in0 = batch.inputs[0].params * scale[:, None, None]
    out = batch.output.terms.params + shift[:, None, None]
    batch = fz.FuzzySystem(
        (fz.Terms(in0, "gaussian"), batch.inputs[1]),
        fz.MamdaniOutput(batch.output.grid, fz.Terms(out, "triangular")),
        batch.weights,
        base.rules,
    )
    x = jnp.asarray([0.21, -0.43])
    batched = jax.jit(jax.vmap(fz.evaluate, in_axes=(0, None)))(batch, x)
    for k in range(n):
        one = jax.tree_util.tree_map(lambda leaf: leaf[k], batch)
        assert float(batched[k]) == pytest.approx(float(jax.jit(fz.evaluate)(one, x)), abs=1e-13)


def test_evaluate_batch_equals_vmap():
    fis = _mamdani()
    xs = jnp.asarray(np.random.default_rng(1).uniform(-1.5, 1.5, (37, 2)))
    chunked = jax.jit(lambda v: fz.evaluate_batch(fis, v, batch_size=8))(xs)
    whole = jax.jit(jax.vmap(lambda v: fz.evaluate(fis, v)))(xs)
    np.testing.assert_allclose(chunked, whole, rtol=0, atol=1e-14)


def test_rule_base_validation_names_the_argument():
    with pytest.raises(ValueError, match="antecedents: empty rule base"):
        fz.rule_base(np.zeros((0, 2), int), np.zeros(0, int))
    with pytest.raises(ValueError, match="table: empty rule base"):
        fz.grid_rule_base(np.zeros((0, 3), int))
    with pytest.raises(ValueError, match="consequents"):
        fz.rule_base([[0, 1]], [0, 1])
    with pytest.raises(ValueError, match="antecedents: term indices must be integers"):
        fz.rule_base([[0.5, 1]], [0])
    with pytest.raises(ValueError, match="connective"):
        fz.rule_base([[0, 1]], [0], connective="xor")
    inputs = [("triangular", [[-1, 0, 1], [0, 1, 2]])] * 2
    with pytest.raises(ValueError, match="antecedents: rule 1 uses term 2 of input 1"):
        fz.sugeno(inputs, [1.0, 2.0], fz.rule_base([[0, 1], [1, 2]], [0, 1]))
    with pytest.raises(ValueError, match="consequents: rule 0 fires output 3"):
        fz.sugeno(inputs, [1.0, 2.0], fz.rule_base([[0, 1]], [3]))
    with pytest.raises(ValueError, match="inputs: the rule base has 1 inputs"):
        fz.sugeno(inputs, [1.0], fz.rule_base([[0]], [0]))
    with pytest.raises(ValueError, match="weights"):
        fz.sugeno(inputs, [1.0], fz.rule_base([[0, 0]], [0]), weights=[1.5])
    with pytest.raises(ValueError, match="and_norm"):
        fz.sugeno(inputs, [1.0], fz.rule_base([[0, 0]], [0]), and_norm="max")
    with pytest.raises(ValueError, match="output_grid"):
        fz.mamdani(inputs, [0.0, 0.0, 1.0], ("triangular", [[0, 1, 2]]), fz.rule_base([[0, 0]], [0]))
    with pytest.raises(ValueError, match="defuzzifier"):
        fz.mamdani(inputs, [0.0, 1.0], ("triangular", [[0, 1, 2]]), fz.rule_base([[0, 0]], [0]), defuzzifier="median")


def test_norms_and_their_reductions():
    a = jnp.asarray([0.2, 0.7, 0.5])
    assert float(fz.tnorm_reduce("min", a)) == 0.2
    assert float(fz.tnorm_reduce("product", a)) == pytest.approx(0.07)
    assert float(fz.snorm_reduce("max", a)) == 0.7
    # probabilistic sum folds pairwise: S(S(a, b), c)
    assert float(fz.snorm_reduce("probor", a)) == pytest.approx(
        float(fz.snorm("probor", fz.snorm("probor", 0.2, 0.7), 0.5))
    )
    assert float(fz.tnorm_reduce("min", jnp.zeros((0,)))) == 1.0  # identities on empty axes
    assert float(fz.snorm_reduce("probor", jnp.zeros((0,)))) == 0.0
    with pytest.raises(ValueError, match="kind"):
        fz.tnorm("max", 0.1, 0.2)
