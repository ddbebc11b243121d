"""Streaming statistics: Chan-merged moments vs NumPy, the quantile sketch's bound, Wilson vs SciPy."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy import stats

import jaxsim.montecarlo as mc


def test_pairwise_sum_is_accurate_and_identical_under_vmap_and_jit():
    rng = np.random.default_rng(0)
    x = rng.normal(size=(7, 1000)) * 10.0 ** rng.integers(-8, 8, size=(7, 1000))
    single = np.array([float(mc.pairwise_sum(jnp.asarray(row))) for row in x])
    batched = np.asarray(jax.jit(jax.vmap(mc.pairwise_sum))(jnp.asarray(x)))
    assert np.array_equal(single, batched)
    exact = np.array([math.fsum(row) for row in x])
    scale = np.abs(x).sum(axis=1)
    assert np.all(np.abs(single - exact) <= 10 * 1.1e-16 * scale)  # log2(1024) levels


def test_pairwise_merge_tree_depends_only_on_the_count():
    merge = mc.PairwiseMerge(lambda a, b: f"({a}{b})")
    for i in range(5):
        merge.push(str(i))
    assert merge.result() == "(((01)(23))4)"
    merge = mc.PairwiseMerge(lambda a, b: f"({a}{b})")
    for i in range(7):
        merge.push(str(i))
    assert merge.result() == "(((01)(23))((45)6))"


def test_merged_moments_equal_numpy_on_a_million_samples():
    rng = np.random.default_rng(1)
    x = 1e3 + 0.01 * rng.standard_normal(1_000_000)  # large offset: cancellation-prone
    blocks = x.reshape(1000, 1000)
    per_block = jax.jit(jax.vmap(lambda b: mc.block_moments(b, jnp.ones(b.shape, bool))))(jnp.asarray(blocks))
    merge = mc.PairwiseMerge(mc.merge_moments)
    for j in range(1000):
        merge.push(mc.Moments(*(np.asarray(a[j]) for a in per_block)))
    m = merge.result()
    assert int(m.count) == x.size
    assert float(m.mean) == pytest.approx(np.mean(x), rel=1e-12)
    assert float(m.variance) == pytest.approx(np.var(x, ddof=1), rel=1e-12)
    # Chan's merge of uneven parts equals the pooled moments
    parts = np.split(x[:10_000], [1, 17, 5000, 9999])
    acc = mc.moments_of(parts[0])
    for p in parts[1:]:
        acc = mc.merge_moments(acc, mc.moments_of(p))
    assert float(acc.mean) == pytest.approx(np.mean(x[:10_000]), rel=1e-13)
    assert float(acc.variance) == pytest.approx(np.var(x[:10_000], ddof=1), rel=1e-10)


def test_block_moments_ignore_masked_values():
    x = jnp.array([1.0, 2.0, jnp.nan, 4.0, 100.0])
    mask = jnp.array([True, True, False, True, False])
    m = mc.block_moments(x, mask)
    assert int(m.count) == 3 and float(m.mean) == pytest.approx(7 / 3)
    assert float(m.m2) == pytest.approx(np.var([1.0, 2.0, 4.0]) * 3)
    empty = mc.block_moments(x, jnp.zeros(5, bool))
    merged = mc.merge_moments(empty, m)
    assert float(merged.mean) == float(m.mean) and float(merged.m2) == float(m.m2)


def _sketch_counts(sketch, x):
    idx = np.asarray(jax.jit(sketch.bucket)(jnp.asarray(x)))
    return np.bincount(idx, minlength=sketch.n_bins)


@pytest.mark.parametrize("sketch", [mc.QuantileSketch(), mc.QuantileSketch(1e-2, 1e-6, 1e6)])
def test_sketch_quantiles_respect_the_stated_bound(sketch):
    rng = np.random.default_rng(2)
    x = np.concatenate([
        rng.lognormal(0.0, 2.0, 400_000), -rng.lognormal(1.0, 1.0, 300_000),
        rng.normal(0.0, 1e-10, 100_000), np.zeros(50_000), rng.uniform(-5, 5, 150_000),
    ])
    counts = _sketch_counts(sketch, x)
    assert counts.sum() == x.size
    qs = np.array([0.0, 1e-4, 0.001, 0.01, 0.05, 0.25, 0.3, 0.5, 0.75, 0.95, 0.99, 0.999, 1.0])
    est = mc.sketch_quantile(sketch, counts, qs, x.min(), x.max())
    xs = np.sort(x)
    exact = xs[np.maximum(1, np.ceil(qs * x.size)).astype(int) - 1]
    np.testing.assert_array_equal(exact, np.quantile(x, qs, method="inverted_cdf"))
    bound = np.where(np.abs(exact) <= sketch.min_abs, sketch.min_abs,
                     sketch.rel_accuracy * np.abs(exact) * (1 + 1e-12))
    assert np.all(np.abs(est - exact) <= bound), np.abs(est - exact) / bound
    assert np.all(np.abs(est - exact) <= mc.quantile_error_bound(sketch, est))
    # the bound is tight-ish: the relative accuracy is actually used
    inside = np.abs(exact) > 1e-3
    assert np.max(np.abs(est - exact)[inside] / np.abs(exact[inside])) > 0.2 * sketch.rel_accuracy


def test_sketch_beyond_its_range_reports_the_exact_extremes():
    sketch = mc.QuantileSketch(1e-3, 1e-3, 1e3)
    x = np.array([-5e4, -1.0, 2.0, 7e5, 9e5])
    counts = _sketch_counts(sketch, x)
    assert counts[0] == 1 and counts[-1] == 2
    est = mc.sketch_quantile(sketch, counts, [0.0, 0.9, 1.0], x.min(), x.max())
    assert est[0] == -5e4 and est[1] == 9e5 and est[2] == 9e5
    assert np.isinf(mc.quantile_error_bound(sketch, est[2]))


@pytest.mark.parametrize("kwargs, match", [
    ({"rel_accuracy": 0.0}, "rel_accuracy"), ({"min_abs": -1.0}, "min_abs"), ({"max_abs": 1e-12}, "max_abs"),
])
def test_sketch_rejects_bad_layouts(kwargs, match):
    with pytest.raises(ValueError, match=match):
        mc.QuantileSketch(**kwargs)


@pytest.mark.parametrize("k, n", [(0, 10), (3, 10), (10, 10), (1, 1_000_000), (4999, 10_000), (0, 1)])
@pytest.mark.parametrize("confidence", [0.9, 0.95, 0.99])
def test_wilson_interval_matches_scipy(k, n, confidence):
    lo, hi = mc.wilson_interval(k, n, confidence)
    ref = stats.binomtest(k, n).proportion_ci(confidence_level=confidence, method="wilson")
    assert float(lo) == pytest.approx(ref.low, rel=1e-12, abs=1e-15)
    assert float(hi) == pytest.approx(ref.high, rel=1e-12, abs=1e-15)


def test_wilson_interval_rejects_bad_input():
    with pytest.raises(ValueError, match="k, n"):
        mc.wilson_interval(11, 10)
    with pytest.raises(ValueError, match="confidence"):
        mc.wilson_interval(1, 10, 1.0)
