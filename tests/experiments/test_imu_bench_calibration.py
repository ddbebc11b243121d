"""Study ``imu_bench_calibration`` through the CLI (tiny preset): the rank table, the NEES interval
recomputed with SciPy's χ² quantiles, the optimised plan's trace no larger than the initial one."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.stats

from experiments.imu_bench_calibration import STUDY
from tests.experiments.study_cli import run_quick_study


@pytest.fixture(scope="module")
def study_output(tmp_path_factory):
    out = tmp_path_factory.mktemp("ibc")
    return out, run_quick_study("imu_bench_calibration", out, preset="tiny")


def test_files_ranks_and_claims(study_output):
    out, res = study_output
    for name in (
        "observability.csv",
        "consistency.csv",
        "optimised_plan.csv",
        "information_spectra.png",
        "reproduction.csv",
    ):
        assert (out / name).stat().st_size > 0, name
    m = res["metrics"]
    # structural ranks: 12, 20, 23 of 24 for one, two, three cycles; the Earth rate adds the azimuth
    assert (m["rank_1_cycle"], m["rank_2_cycles"], m["rank_3_cycles"]) == (12, 20, 23)
    assert m["rank_3_cycles_with_earth_rate"] == 24
    assert (m["skew_gain_one_rate"], m["skew_gain_two_rates"]) == (0, 1)
    assert (m["thermal_gain_constant"], m["thermal_gain_ramp"]) == (0, 3)
    rows = {r["plan"]: r for r in res["tables"]["observability"]}
    assert all(r["rank_structural"] <= r["rank_with_earth_rate"] <= r["states"] for r in rows.values())


def test_nees_interval_and_plan(study_output):
    _, res = study_output
    cfg = STUDY.resolve("tiny")[1]
    m = res["metrics"]
    k = 24 * cfg.mc_runs
    lo, hi = scipy.stats.chi2.ppf([0.025, 0.975], k) / cfg.mc_runs
    assert m["nees_lo"] == pytest.approx(lo) and m["nees_hi"] == pytest.approx(hi)
    assert lo <= m["nees_mean"] <= hi
    assert 0.0 <= m["trace_reduction"] < 1.0 and m["trace_optimised"] <= m["trace_initial"]
    rates = np.array([[r["rate1_deg_s"], r["rate2_deg_s"]] for r in res["tables"]["optimised_plan"]])
    assert np.all((rates >= cfg.rate_bounds_deg[0] - 1e-9) & (rates <= cfg.rate_bounds_deg[1] + 1e-9))
