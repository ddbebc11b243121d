"""The map_aided_pf study through the CLI (tiny preset): files, claim verdicts against their bands, the
Table 2 RMS and ratio recomputed with NumPy from the per-run final errors, the map gradients recomputed
with NumPy, and the Table 1 counts (Gaussian draws, exponents, interpolations) from the jaxpr."""

import math

import numpy as np
import pytest
import scipy.stats

from experiments.map_aided_pf import STUDY, make_maps
from tests.experiments.study_cli import assert_verdicts_follow_the_tolerances, run_quick_study

pytestmark = pytest.mark.slow  # a short study run through the CLI: a few compilations


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    out = tmp_path_factory.mktemp("mapf")
    return out, run_quick_study("map_aided_pf", out, preset="tiny")


def test_files_and_verdicts(result):
    out, res = result
    _, tiny = STUDY.resolve("tiny")
    assert res["preset"] == "tiny" and res["config"]["n_particles"] == tiny.n_particles == 500
    for name in ("table2.csv", "table1_ops.csv", "final_errors.csv", "rms_vs_fix.png", "reproduction.csv"):
        assert (out / name).exists(), name
    assert_verdicts_follow_the_tolerances(res, STUDY.claims)
    rows = {r["metric"]: r for r in res["reproduction"]}
    for name in (
        "ops_sis_gaussian_per_particle",
        "ops_resampled_exp_per_particle",
        "ops_sis_interpolation_per_particle",
    ):
        assert rows[name]["verdict"] == "reproduced", name


def test_table2_recomputed_with_numpy(result):
    res = result[1]
    m, cfg = res["metrics"], res["config"]
    errs = res["tables"]["final_errors"]
    for k in (1, 2, 3):
        rms = {}
        for v in ("sis", "resampled"):
            e = np.array([[r["ex_km"], r["ey_km"]] for r in errs if r["map"] == k and r["variant"] == v])
            assert e.shape == (cfg["n_runs"], 2)
            rms[v] = 1e3 * np.sqrt(np.mean(e**2))
            assert m[f"rms_map{k}_{v}_m"] == pytest.approx(rms[v], rel=1e-12)
        assert m[f"ratio_map{k}"] == pytest.approx(rms["resampled"] / rms["sis"], rel=1e-12)
        assert m[f"ratio_map{k}_ci_low"] <= m[f"ratio_map{k}_ci_high"]
    lo = scipy.stats.chi2.ppf(0.025, 2 * cfg["n_runs"]) / cfg["n_runs"]
    assert m["nees_chi2_lo"] == pytest.approx(lo, rel=1e-12)


def test_map_gradients_recomputed_with_numpy(result):
    res = result[1]
    _, cfg = STUDY.resolve("tiny")
    maps = make_maps(cfg)
    for k, vals in enumerate(maps, 1):
        gy, gx = np.gradient(vals, cfg.map_spacing)
        assert res["metrics"][f"map{k}_mean_grad_x"] == pytest.approx(np.mean(np.abs(gx)), rel=1e-10)
        target = sum(cfg.maps[k - 1])
        assert np.mean(np.abs(gx)) + np.mean(np.abs(gy)) == pytest.approx(target, rel=1e-10)


def test_operation_counts(result):
    m = result[1]["metrics"]
    assert m["ops_sis_gaussian_slope"] == 4 and m["ops_resampled_gaussian_slope"] == 4
    assert m["ops_resampled_uniform_constant"] == 1 and m["ops_sis_uniform_constant"] == 0
    assert m["ops_sis_compare_slope"] == 0
    n = result[1]["config"]["n_particles"]
    assert m["ops_resampled_compare_per_particle"] >= math.ceil(math.log2(n))  # binary search
    assert m["ops_resampled_mul_per_particle"] > m["ops_sis_mul_per_particle"]
