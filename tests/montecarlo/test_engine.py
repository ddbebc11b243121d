"""The Monte-Carlo engine in one process: reproducibility, accuracy against NumPy, sweeps, bad input."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxsim.montecarlo as mc
from tests.montecarlo._demo import SPACE, demo_fn


def _assert_same(a: mc.MonteCarloResult, b: mc.MonteCarloResult) -> None:
    aa, bb = a.arrays(), b.arrays()
    assert aa.keys() == bb.keys()
    for k in aa:
        assert np.array_equal(aa[k], bb[k], equal_nan=True), k


def test_statistics_are_bitwise_identical_for_chunk_sizes_1k_10k_100k():
    n = 120_500  # a partial last block and a partial last chunk
    results = [mc.monte_carlo(demo_fn, SPACE, n, 7, chunk_size=c) for c in (1_000, 10_000, 100_000)]
    for r in results[1:]:
        _assert_same(results[0], r)
    assert results[0].runs == n and results[0].chunks_computed == 121


def _reference_values(n, key):
    """Every run's metrics by one plain vmap over the run indices (no blocks, no chunks)."""
    one = jax.jit(jax.vmap(lambda i: mc.run_one(demo_fn, SPACE, {}, mc.as_key(key), i)[1]))
    return {k: np.asarray(v) for k, v in one(jnp.arange(n)).items()}


def test_a_million_runs_match_numpy_on_the_same_values():
    n, key = 1_000_000, 11
    res = mc.monte_carlo(demo_fn, SPACE, n, key, keep_runs=5)
    ref = _reference_values(n, key)
    x = ref["x"]
    s = res["x"]
    assert int(s.count) == n and int(s.nonfinite) == 0
    assert float(s.mean) == pytest.approx(np.mean(x), rel=1e-12)
    assert float(s.variance) == pytest.approx(np.var(x, ddof=1), rel=1e-12)
    assert float(s.minimum) == x.min() and float(s.maximum) == x.max()
    vec = res["vec"]
    np.testing.assert_allclose(vec.mean, ref["vec"].mean(axis=0), rtol=1e-12)
    np.testing.assert_allclose(vec.variance, ref["vec"].var(axis=0, ddof=1), rtol=1e-12)
    assert float(res["count"].mean) == pytest.approx(ref["count"].mean(), rel=1e-12)
    assert int(res["flag"].count) == int(ref["flag"].sum()) and res["flag"].runs == n
    bad = ref["bad"]
    finite = bad[np.isfinite(bad)]
    assert int(res["bad"].nonfinite) == int((~np.isfinite(bad)).sum()) > 0
    assert float(res["bad"].mean) == pytest.approx(finite.mean(), rel=1e-12)
    assert float(res["tiny"].variance) == pytest.approx(np.var(ref["tiny"], ddof=1), rel=1e-12)
    qs = np.array([0.001, 0.05, 0.5, 0.95, 0.999])
    for name, values in (("x", x), ("bad", finite), ("tiny", ref["tiny"])):
        exact = np.quantile(values, qs, method="inverted_cdf")
        est = res[name].quantile(qs)
        assert np.all(np.abs(est - exact) <= res[name].quantile_bound(qs)), name
    np.testing.assert_allclose(res.raw.metrics["x"], x[:5], rtol=1e-15)
    assert res.raw.params["fixed"].tolist() == [3.0] * 5


def test_sweep_points_equal_monte_carlo_with_the_value_fixed():
    space = {**SPACE}
    design = mc.grid({"fixed": (1.0, 2.0, 2)})
    swept = mc.sweep(demo_fn, space, design, 3000, 5)
    for p, value in enumerate((1.0, 2.0)):
        single = mc.monte_carlo(demo_fn, {**space, "fixed": value}, 3000, 5)
        _assert_same(swept.points[p], single)
    assert swept.points[0].point == {"fixed": 1.0}
    rows = swept.table()
    assert [r["fixed"] for r in rows] == [1.0, 2.0]
    assert rows[1]["x:mean"] == float(swept.points[1]["x"].mean)
    assert "vec[3]:p95" in rows[0] and "flag:wilson_high" in rows[0]


def test_designs():
    g = mc.grid({"a": (0.0, 1.0, 3), "b": (5.0, 5.0, 1), "c": (-1.0, 1.0, 2)})
    assert g.names == ("a", "b", "c") and g.values.shape == (6, 3)
    assert g.values[:, 0].tolist() == [0.0, 0.0, 0.5, 0.5, 1.0, 1.0]
    lhs = mc.latin_hypercube({"a": (0.0, 10.0), "b": (-1.0, 1.0)}, 16, seed=3)
    for j, (lo, hi) in enumerate([(0.0, 10.0), (-1.0, 1.0)]):  # one point in each of the 16 strata
        strata = np.floor((lhs.values[:, j] - lo) / (hi - lo) * 16).astype(int)
        assert sorted(strata.tolist()) == list(range(16))
    sob = mc.sobol({"a": (0.0, 1.0), "b": (2.0, 4.0)}, 32, seed=1)
    assert sob.values.shape == (32, 2) and np.all((sob.values[:, 1] >= 2) & (sob.values[:, 1] <= 4))
    for j in range(2):  # base-2 balance of a Sobol' net: 16 points in each half of each axis
        lo, hi = (0.0, 1.0) if j == 0 else (2.0, 4.0)
        assert np.sum(sob.values[:, j] < (lo + hi) / 2) == 16
    assert mc.parse_range("kp=0.5:2:4") == ("kp", 0.5, 2.0, 4)
    assert mc.parse_range("x=-1:1") == ("x", -1.0, 1.0, None)


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda: mc.grid({"kp": (2.0, 1.0, 3)}), "kp: range has lo=2.0 > hi=1.0"),
        (lambda: mc.latin_hypercube({"kp": (2.0, 1.0)}, 4), "kp: range"),
        (lambda: mc.sobol({"kp": (0.0, 1.0)}, 0), "n: number of points"),
        (lambda: mc.grid({"kp": (0.0, 1.0, 0)}), "kp: number of points"),
        (lambda: mc.parse_range("kp=3:1:2"), "kp: range has lo"),
        (lambda: mc.parse_range("kp=a:1"), "kp: lo and hi"),
        (lambda: mc.parse_range("kp"), "expected name=lo:hi"),
    ],
)
def test_bad_designs_raise(make, match):
    with pytest.raises(ValueError, match=match):
        make()


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"n": 0}, "n: must be in"),
        ({"n": -3}, "n: must be in"),
        ({"n": 2.5}, "n: must be an integer"),
        ({"chunk_size": 1500}, "chunk_size: must be a multiple of block_size=1000"),
        ({"keep_runs": 20}, "keep_runs"),
        ({"key": "seed"}, "key:"),
        ({"devices": 99}, "devices"),
        ({"design": mc.grid({"a": (0.0, 1.0, 2)})}, "a: is drawn from a distribution"),
    ],
)
def test_bad_arguments_raise_before_running(kwargs, match):
    args = {"n": 10, "key": 0, "design": mc.single_point(), **kwargs}
    with pytest.raises(ValueError, match=match):
        mc.sweep(demo_fn, SPACE, args.pop("design"), args.pop("n"), args.pop("key"), **args)


def test_non_numeric_metrics_are_refused():
    with pytest.raises(ValueError, match="fn: metric 'z'"):
        mc.monte_carlo(lambda k, p: {"z": jnp.complex64(1j) * p["a"]}, {"a": mc.normal()}, 10, 0)


def test_layout_probe_traces_the_design_point_so_value_checks_in_fn_pass():
    from jaxsim.core.validation import check_positive

    def fn(key, p):  # a metric that validates its parameters, like a study's per-run function
        check_positive("gate", p["gate"])
        return {"x": p["gate"] * 1.0}

    res = mc.sweep(fn, {"gate": 1.0}, mc.points(["gate"], [[2.0], [3.0]]), 4, 0, block_size=4)
    np.testing.assert_allclose([r["x"].mean for r in res.points], [2.0, 3.0])
