"""Streaming statistics: Chan-merged moments vs NumPy, the quantile sketch's bound, Wilson vs SciPy."""

import math
from fractions import Fraction

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp
from scipy import stats

import jaxsim.montecarlo as mc
from jaxsim.montecarlo.engine import _PointAccumulator
from jaxsim.montecarlo.kernel import Leaf

PROPERTY = settings(max_examples=60, deadline=None, derandomize=True)  # reproducible in CI


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
    x = np.concatenate(
        [
            rng.lognormal(0.0, 2.0, 400_000),
            -rng.lognormal(1.0, 1.0, 300_000),
            rng.normal(0.0, 1e-10, 100_000),
            np.zeros(50_000),
            rng.uniform(-5, 5, 150_000),
        ]
    )
    counts = _sketch_counts(sketch, x)
    assert counts.sum() == x.size
    qs = np.array([0.0, 1e-4, 0.001, 0.01, 0.05, 0.25, 0.3, 0.5, 0.75, 0.95, 0.99, 0.999, 1.0])
    est = mc.sketch_quantile(sketch, counts, qs, x.min(), x.max())
    xs = np.sort(x)
    exact = xs[np.maximum(1, np.ceil(qs * x.size)).astype(int) - 1]
    np.testing.assert_array_equal(exact, np.quantile(x, qs, method="inverted_cdf"))
    bound = np.where(np.abs(exact) <= sketch.min_abs, sketch.min_abs, sketch.rel_accuracy * np.abs(exact) * (1 + 1e-12))
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


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"rel_accuracy": 0.0}, "rel_accuracy"),
        ({"min_abs": -1.0}, "min_abs"),
        ({"max_abs": 1e-12}, "max_abs"),
    ],
)
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


# --- properties on random data (hypothesis) ---------------------------------------------------------

BLOCK = 64  # every part is summarised as one padded, masked block of this length: one compilation
_block_moments = jax.jit(mc.block_moments)
EPS = np.finfo(float).eps


@st.composite
def _data_and_partition(draw):
    """Values (optionally on a large offset: cancellation-prone) and a partition into consecutive,
    possibly empty, parts of at most ``BLOCK`` values, grouped into consecutive chunks."""
    n = draw(st.integers(1, 4 * BLOCK))
    x = draw(hnp.arrays(np.float64, n, elements=st.floats(-1e3, 1e3, allow_subnormal=False)))
    x = x + draw(st.sampled_from([0.0, 1e6]))
    cuts = sorted(draw(st.lists(st.integers(0, n), max_size=10)) + list(range(BLOCK, n, BLOCK)))
    parts = [x[a:b] for a, b in zip([0] + cuts, cuts + [n])]
    chunk_cuts = sorted(set(draw(st.lists(st.integers(1, len(parts)), max_size=4))) | {len(parts)})
    chunks = [parts[a:b] for a, b in zip([0] + chunk_cuts, chunk_cuts) if b > a]
    return x, chunks


def _exact_moments(x: np.ndarray) -> tuple[float, float]:
    """Mean and ``Σ(x − mean)²`` in exact rational arithmetic."""
    fx = [Fraction(float(v)) for v in x]
    mean = sum(fx) / len(fx)
    return float(mean), float(sum((v - mean) ** 2 for v in fx))


def _summary(part: np.ndarray) -> mc.Moments:
    pad = np.zeros(BLOCK)
    pad[: len(part)] = part
    m = _block_moments(jnp.asarray(pad), jnp.arange(BLOCK) < len(part))
    return mc.Moments(*(np.asarray(a) for a in m))


@PROPERTY
@given(_data_and_partition())
def test_moments_merged_over_any_partition_equal_the_pooled_moments(case):
    """Per-part device summaries merged in order (the binary tree of ``PairwiseMerge`` and a plain
    left fold) give the moments of the whole data, to a rounding bound; the engine's accumulator
    merges chunk minima, maxima and sketch counts exactly."""
    x, chunks = case
    n = len(x)
    mean, m2 = _exact_moments(x)
    tol_mean = 64 * EPS * np.max(np.abs(x))
    spread = np.max(np.abs(x - mean))
    tol_m2 = 64 * EPS * n * np.max(np.abs(x)) * spread + n * tol_mean**2
    summaries = [_summary(p) for c in chunks for p in c]
    tree = mc.PairwiseMerge(mc.merge_moments)
    fold = summaries[0]
    for s in summaries:
        tree.push(s)
    for s in summaries[1:]:
        fold = mc.merge_moments(fold, s)
    for got in (tree.result(), fold):
        assert int(got.count) == n
        assert abs(float(got.mean) - mean) <= tol_mean
        assert abs(float(got.m2) - m2) <= tol_m2

    sketch = mc.QuantileSketch(1e-2, 1e-3, 1e7)
    acc = _PointAccumulator([Leaf("x", (), "numeric")], sketch)
    for c in chunks:
        values = np.concatenate(c)
        acc.add(
            {
                "runs": np.int64(len(values)),
                "count/x": np.array([len(p) for p in c]),
                "mean/x": np.array([_summary(p).mean for p in c]),
                "m2/x": np.array([_summary(p).m2 for p in c]),
                "nonfinite/x": np.int64(0),
                "min/x": np.min(values, initial=np.inf),
                "max/x": np.max(values, initial=-np.inf),
                "hist/x": np.bincount(np.asarray(_bucket(sketch, values)), minlength=sketch.n_bins),
            }
        )
    runs, out = acc.stats()
    st_x = out["x"]
    assert runs == n and int(st_x.count) == n
    assert float(st_x.minimum) == x.min() and float(st_x.maximum) == x.max()
    assert abs(float(st_x.moments.mean) - mean) <= tol_mean
    assert abs(float(st_x.moments.m2) - m2) <= tol_m2
    np.testing.assert_array_equal(
        st_x.bucket_counts, np.bincount(np.asarray(_bucket(sketch, x)), minlength=sketch.n_bins)
    )


def _bucket(sketch: mc.QuantileSketch, x: np.ndarray) -> np.ndarray:
    """Bucket indices through one compiled padded call per layout."""
    pad = np.zeros(4 * BLOCK)
    pad[: len(x)] = x
    return np.asarray(_jit_bucket(sketch)(jnp.asarray(pad)))[: len(x)]


_BUCKET_FNS: dict = {}


def _jit_bucket(sketch: mc.QuantileSketch):
    if sketch not in _BUCKET_FNS:
        _BUCKET_FNS[sketch] = jax.jit(sketch.bucket)
    return _BUCKET_FNS[sketch]


@st.composite
def _spread_values(draw):
    """Values over many decades, of both signs, with zeros and values beyond the sketch's range."""
    n = draw(st.integers(1, 4 * BLOCK))
    exponent = draw(hnp.arrays(np.float64, n, elements=st.floats(-9.0, 9.0)))
    sign = draw(hnp.arrays(np.float64, n, elements=st.sampled_from([-1.0, 0.0, 1.0])))
    return sign * 10.0**exponent


@PROPERTY
@given(
    _spread_values(),
    st.lists(st.floats(0.0, 1.0), min_size=1, max_size=5),
    st.sampled_from([mc.QuantileSketch(1e-3, 1e-6, 1e6), mc.QuantileSketch(5e-2, 1e-3, 1e3)]),
)
@example(np.arange(1.0, 11.0), [0.1, 0.3, 0.7, 0.9, 1.0], mc.QuantileSketch(5e-2, 1e-3, 1e3))
def test_sketch_quantile_meets_its_stated_bound_on_random_data(x, qs, sketch):
    """Module docstring of ``sketch``: for the order statistic ``x₍ᵣ₎``, ``r = max(1, ⌈qN⌉)`` (NumPy's
    ``inverted_cdf``), ``|q̂ − x₍ᵣ₎| ≤ α|x₍ᵣ₎|`` inside the range, ``≤ min_abs`` near zero, and
    beyond ``max_abs`` the estimate is the exact minimum or maximum.  The explicit example puts
    ``qN`` on integers in decimal (0.1·10 is 1 in floating point, just above 1 in binary)."""
    counts = np.bincount(_bucket(sketch, x), minlength=sketch.n_bins)
    est = mc.sketch_quantile(sketch, counts, np.array(qs), x.min(), x.max())
    alpha = sketch.rel_accuracy
    exact = np.quantile(x, qs, method="inverted_cdf")  # x₍ᵣ₎, the definition's order statistic
    for q, e, xr in zip(qs, est, exact):
        if abs(xr) <= sketch.min_abs:
            assert abs(e - xr) <= sketch.min_abs, (q, xr, e)
        elif abs(xr) <= sketch.max_abs:
            assert abs(e - xr) <= alpha * abs(xr) * (1 + 1e-12), (q, xr, e)
        else:
            assert e == (x.max() if xr > 0 else x.min()), (q, xr, e)
        assert abs(e - xr) <= mc.quantile_error_bound(sketch, e)
