"""Study ``gnss_correction_prediction`` (seed 004 #30, part 3) through the CLI, tiny preset: the hold
and unconstrained predictors re-scored with NumPy, the tuned constrained predictor re-scored with
SciPy's SLSQP fits, the claims kept as computed."""

import jax
import numpy as np
import pytest

from experiments.gnss_correction_prediction import STUDY, corrections, windows
from tests.estimation.test_dc_prediction import slsqp_fit
from tests.experiments.study_cli import run_quick_study


@pytest.fixture(scope="module")
def study_output(tmp_path_factory):
    out = tmp_path_factory.mktemp("gnss")
    return out, run_quick_study("gnss_correction_prediction", out, preset="tiny")


@pytest.fixture(scope="module")
def test_windows():
    cfg = STUDY.resolve("tiny")[1]
    n = max(cfg.horizons)
    test = corrections(cfg, jax.random.fold_in(jax.random.PRNGKey(cfg.seed), 2))
    past, future = windows(cfg, test, n)
    return cfg, n, np.asarray(past), np.asarray(future)


def rows_by(res):
    return {(r["method"], r["horizon_s"]): r for r in res["tables"]["rms"]}


def test_files_and_claims(study_output):
    out, res = study_output
    for name in ("rms.csv", "tuning.csv", "rms_vs_horizon.png", "reproduction.csv"):
        assert (out / name).stat().st_size > 0, name
    verdicts = {r["metric"]: r["verdict"] for r in res["reproduction"]}
    m = res["metrics"]
    for metric in ("lpo_gain_over_kpo_test_long", "lpo_gain_over_fp_test_long"):
        assert (verdicts[metric] == "reproduced") == (0.10 <= m[metric] <= 0.15)


def test_hold_and_quadratic_rms_against_numpy(study_output, test_windows):
    _, res = study_output
    cfg, n, past, future = test_windows
    rows = rows_by(res)
    assert rows[("FP", n)]["rms_test_m"] == pytest.approx(np.sqrt(np.mean((past[:, -1] - future) ** 2)), rel=1e-10)
    s = np.arange(n) / (2 * n - 1)
    vander = np.stack([np.ones_like(s), s, s * s], axis=1)
    coef = np.linalg.lstsq(vander, past.T, rcond=None)[0]
    pred = coef.sum(axis=0)  # φ(1) = b0 + b1 + b2
    assert rows[("KP", n)]["rms_test_m"] == pytest.approx(np.sqrt(np.mean((pred - future) ** 2)), rel=1e-8)


def test_constrained_linear_rms_against_slsqp_fits(study_output, test_windows):
    _, res = study_output
    cfg, n, past, future = test_windows
    row = rows_by(res)[("LPO", n)]
    c, psi = row["c"], row["psi"]
    s0 = (n - 1) / (2 * n - 1)
    preds = []
    for d in past:
        b = slsqp_fit(d, n, c, psi)
        value = c * (b[0] + b[1] * s0 + b[2] * s0**2)
        preds.append(value + c * (b[1] + 2 * b[2] * s0) * (1 - s0))
    assert row["rms_test_m"] == pytest.approx(np.sqrt(np.mean((np.array(preds) - future) ** 2)), rel=1e-4)
