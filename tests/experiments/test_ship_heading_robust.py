"""Study ``ship_heading_robust`` (seed 004 #4) through the CLI, tiny preset: files and verdicts, the
designs' phase margins against python-control, their closed-loop roots (NumPy) and max|T| (SciPy)."""

import control
import numpy as np
import pytest
import scipy.signal

from experiments.ship_heading_robust import STUDY
from tests.experiments.study_cli import recorded_config, run_quick_study


@pytest.fixture(scope="module")
def study_output(tmp_path_factory):
    out = tmp_path_factory.mktemp("ship")
    return out, run_quick_study("ship_heading_robust", out, preset="tiny")


def test_config_files_and_verdicts(study_output):
    out, res = study_output
    tiny = STUDY.resolve("tiny")[1]
    cfg = recorded_config(tiny)
    assert res["config"] == cfg
    for name in ("designs.csv", "designs.png"):
        assert (out / name).stat().st_size > 0, name
    verdicts = {r["metric"]: r["verdict"] for r in res["reproduction"]}
    assert all(v == "reproduced" for v in verdicts.values()), verdicts


def test_designs_against_python_control_and_numpy(study_output):
    res = study_output[1]
    tiny = STUDY.resolve("tiny")[1]
    K, T, Tr = tiny.K, tiny.T, tiny.T_r
    den = np.polymul([T * Tr, T + Tr, 1.0], [1.0, 0.0, 0.0])
    for row in res["tables"]["designs"]:
        num = K * np.array([row["k_d"], row["k_p"], row["k_i"]])
        gm, pm, _, _ = control.margin(control.tf(num, den))
        assert row["pm_deg"] == pytest.approx(pm, abs=1e-6)
        assert res["metrics"][f"{row['design']}_gm_finite"] == 0.0 and not np.isfinite(gm)  # no phase crossover
        roots = np.roots(np.polyadd(den, num))
        assert row["slowest_re"] == pytest.approx(roots.real.max(), rel=1e-8)
        w = np.logspace(np.log10(tiny.w_lo), np.log10(tiny.w_hi), tiny.n_freq)
        _, lval = scipy.signal.freqs(num, den, worN=w)
        assert row["j1_max_T"] == pytest.approx(np.abs(lval / (1 + lval)).max(), rel=1e-9)
