"""Study ``motorin_examples`` through the CLI (tiny preset): files and config, each claim's verdict
against its band, the Monte-Carlo intervals, and the random-walk steady state and the dead-reckoning
covariances recomputed by independent NumPy Riccati recursions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from experiments.motorin_examples import STUDY, dr_mask, dr_model
from tests.experiments.study_cli import recorded_config, run_quick_study


@pytest.fixture(scope="module")
def study_output(tmp_path_factory):
    out = tmp_path_factory.mktemp("motorin_examples")
    return out, run_quick_study("motorin_examples", out, preset="tiny")


def test_config_files_and_verdicts(study_output):
    out, res = study_output
    cfg = STUDY.resolve("tiny")[1]
    assert res["preset"] == "tiny" and res["config"] == recorded_config(cfg)
    for name in (
        "random_walk_identities.csv",
        "monte_carlo.csv",
        "ml_vs_bank.csv",
        "bank_posteriors.png",
        "robustness.png",
        "reproduction.csv",
    ):
        assert (out / name).stat().st_size > 0, name
    claims = {c.metric: c for c in STUDY.claims}
    rows = {r["metric"]: r for r in res["reproduction"]}
    assert set(rows) == set(claims)
    for name, c in claims.items():
        ours = res["metrics"][name]
        if c.band is not None:
            ok = c.band[0] <= ours <= c.band[1]
        else:
            ok = abs(ours - c.paper) <= (c.abs_tol or 0.0) + (c.rel_tol or 0.0) * abs(c.paper)
        assert rows[name]["verdict"] == ("reproduced" if ok else "differs"), name
    # the identities hold even at the tiny sizes
    for name in (
        "rw_dare_closed_form_max_rel_diff",
        "rw_filter_steady_max_rel_diff",
        "rw_prediction_equals_estimate_max_diff",
        "rw_blind_prediction_max_deviation",
        "dr_mismatch_identity_max_rel_diff",
        "dr_mismatch_excess_mse",
    ):
        assert rows[name]["verdict"] == "reproduced", name
    for r in res["tables"]["monte_carlo"]:
        assert r["runs"] == cfg.runs
        assert r["ci95_low"] <= r["mean"] <= r["ci95_high"], r["metric"]


def test_random_walk_steady_state_against_numpy_riccati(study_output):
    _, res = study_output
    cfg = STUDY.resolve("tiny")[1]
    q, r, p = cfg.sigma_w**2, cfg.sigma_v**2, cfg.sigma_0**2
    for _ in range(500):  # scalar Riccati iteration (update, then predict) to convergence
        p_post = p * r / (p + r)
        p = p_post + q
    rows = {row["quantity"]: row["value"] for row in res["tables"]["random_walk_identities"]}
    assert rows["P⁺ closed form (m²)"] == pytest.approx(p_post, rel=1e-12)
    assert res["metrics"]["rw_steady_gain"] == pytest.approx(p / (p + r), rel=1e-12)  # p: the prior P⁻
    assert res["metrics"]["rw_steady_sd_ratio"] == pytest.approx(math.sqrt(p_post / r), rel=1e-12)


def numpy_filter_pos_mse(model, mask: np.ndarray) -> np.ndarray:
    """Position trace of the filtered covariance of a time-varying Kalman filter (NumPy, Joseph form)."""
    F, H = np.asarray(model.F), np.asarray(model.H)
    Q, R, P = np.asarray(model.Q), np.asarray(model.R), np.asarray(model.P0)
    out = []
    for t in range(len(mask)):
        if mask[t]:
            k = P @ H[t].T @ np.linalg.inv(H[t] @ P @ H[t].T + R)
            ikh = np.eye(4) - k @ H[t]
            P = ikh @ P @ ikh.T + k @ R @ k.T
        out.append(np.trace(P[:2, :2]))
        P = F[t] @ P @ F[t].T + Q
    return np.array(out)


def test_dead_reckoning_covariances_against_numpy_filter(study_output):
    _, res = study_output
    cfg = STUDY.resolve("tiny")[1]
    mask = dr_mask(cfg)
    m = res["metrics"]
    optimal = numpy_filter_pos_mse(dr_model(cfg), mask).mean()
    claimed = numpy_filter_pos_mse(dr_model(cfg, cfg.tau_dk_assumed), mask).mean()
    assert m["dr_optimal_pos_mse_exact"] == pytest.approx(optimal, rel=1e-9)
    assert m["dr_stationary_pos_mse_claimed"] == pytest.approx(claimed, rel=1e-9)
    assert m["dr_stationary_pos_mse_exact"] >= m["dr_optimal_pos_mse_exact"]
