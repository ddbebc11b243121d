"""Study ``mems_accelerometer`` (seed 004 #35) through the CLI, tiny preset: files and verdicts, the
pull-in table against the closed-form static condition (SciPy brentq), the multiple-scales numbers
recomputed from their formulas, the design against the constraint vertex."""

import numpy as np
import pytest
import scipy.optimize

from experiments.mems_accelerometer import STUDY
from tests.experiments.study_cli import recorded_config, run_quick_study


@pytest.fixture(scope="module")
def study_output(tmp_path_factory):
    out = tmp_path_factory.mktemp("mems")
    return out, run_quick_study("mems_accelerometer", out, preset="tiny")


def test_config_files_and_verdicts(study_output):
    out, res = study_output
    tiny = STUDY.resolve("tiny")[1]
    assert res["preset"] == "tiny"
    assert res["config"] == recorded_config(tiny)
    for name in ("primary_peaks.csv", "sweeps.csv", "pull_in.csv", "frequency_response.png"):
        assert (out / name).stat().st_size > 0, name
    assert len(res["tables"]["sweeps"]) == tiny.n_omega * (2 * len(tiny.forces) + 2)
    verdicts = {r["metric"]: r["verdict"] for r in res["reproduction"]}
    assert all(v == "reproduced" for v in verdicts.values()), verdicts


def test_pull_in_against_closed_form(study_output):
    res = study_output[1]
    tiny = STUDY.resolve("tiny")[1]
    ek = tiny.eps * tiny.kappa
    for row in res["tables"]["pull_in"]:
        b = row["beta"]
        xs = scipy.optimize.brentq(
            lambda x: 1 + 3 * ek * x**2 - 2 * b * (1 / (1 - x) ** 3 + 1 / (1 + x) ** 3), 0, 0.999, xtol=1e-14
        )
        a = xs + ek * xs**3 - b * (1 / (1 - xs) ** 2 - 1 / (1 + xs) ** 2)
        assert row["a_pull_in_static"] == pytest.approx(a, rel=1e-9)
        assert row["a_pull_in_ramp"] == pytest.approx(a, rel=0.02)  # simulated collapse


def test_multiple_scales_and_design(study_output):
    m = study_output[1]["metrics"]
    tiny = STUDY.resolve("tiny")[1]
    w0 = np.sqrt(1 - 4 * tiny.beta)
    c = 2 * tiny.eps * tiny.mu
    assert m["omega0_linear"] == pytest.approx(w0, rel=1e-12)
    row = study_output[1]["tables"]["primary_peaks"][-1]
    assert row["ms_peak_amplitude"] == pytest.approx(tiny.forces[-1] / (c * w0), rel=1e-12)
    assert m["hysteresis_width"] > 0  # softening: the up sweep jumps above the down sweep
    assert m["softening_shift"] < 0
    b_min = (1 - 1 / tiny.s_min) / 4
    assert m["vertex_kappa"] == pytest.approx((8 * b_min + tiny.gamma) / tiny.eps, rel=1e-12)
    assert m["design_sensitivity"] >= tiny.s_min - 1e-12
    assert abs(m["design_flatness"]) <= tiny.gamma + 1e-12
    assert m["design_pull_in_a"] > m["design_start_pull_in_a"]
