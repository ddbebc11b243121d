"""The filter_bank_wald study through the CLI (tiny preset): thresholds, N(r) against an independent
NumPy/SciPy computation of the drift, Monte-Carlo SPRT against Wald, the T tuning and consistency."""

import math

import numpy as np
import pytest
import scipy.linalg

from experiments.filter_bank_wald import STUDY
from tests.experiments.study_cli import run_quick_study

pytestmark = pytest.mark.slow  # a short study run through the CLI: a few compilations


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    out = tmp_path_factory.mktemp("fbw")
    return out, run_quick_study("filter_bank_wald", out, preset="tiny")


def _mu1_numpy(r: float, dt: float, q: float, rm: float, speed: float) -> float:
    """E₁[ℓ₁ − ℓ₀] by SciPy's DARE and a brute-force moment recursion (no jaxsim code)."""
    H = np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0]])
    Q, R = q * np.eye(2), rm * np.eye(2)

    def model(w):
        a = np.zeros((4, 4))
        a[0, 1] = a[2, 3] = 1.0
        a[1, 3], a[3, 1] = -w, w
        G = np.array([[dt**2 / 2, 0], [dt, 0], [0, dt**2 / 2], [0, dt]])
        return scipy.linalg.expm(a * dt), G

    def filt(w):
        F, G = model(w)
        P = scipy.linalg.solve_discrete_are(F.T, H.T, G @ Q @ G.T, R)
        S = H @ P @ H.T + R
        return F, G, P @ H.T @ np.linalg.inv(S), S

    w = speed / r
    F1, G, K1, S1 = filt(-w)  # H1 = right turn: the truth, matched filter 1
    F0, _, K0, S0 = filt(w)  # filter 0 mismatched
    A = F0 @ (np.eye(4) - K0 @ H)
    x, e, P = np.array([0, speed, 0, 0.0]), np.zeros(4), np.zeros((4, 4))
    for _ in range(800):
        e = (F1 - F0) @ x + A @ e
        P = A @ P @ A.T + F0 @ K0 @ R @ K0.T @ F0.T + G @ Q @ G.T
        x = F1 @ x
    gamma0 = H @ P @ H.T + R + np.outer(H @ e, H @ e)
    ll0 = -0.5 * np.log(np.linalg.det(2 * np.pi * S0)) - 0.5 * np.trace(np.linalg.solve(S0, gamma0))
    ll1 = -0.5 * np.log(np.linalg.det(2 * np.pi * S1)) - 1.0
    return ll1 - ll0


def test_config_files_and_thresholds(result):
    out, res = result
    _, tiny = STUDY.resolve("tiny")
    assert res["preset"] == "tiny" and res["config"]["mc_runs"] == tiny.mc_runs == 64
    files = ("bank_size_vs_radius.csv", "monte_carlo_sprt.csv", "bank_rule.csv", "bank_size.png", "reproduction.csv")
    for name in files:
        assert (out / name).exists(), name
    m = res["metrics"]
    assert m["threshold_A"] == pytest.approx(math.log(0.999 / 0.001), rel=1e-14)
    assert m["threshold_B"] == pytest.approx(-m["threshold_A"], rel=1e-14)
    rows = {r["metric"]: r for r in res["reproduction"]}
    assert rows["threshold_A"]["verdict"] == "reproduced" and rows["threshold_A"]["paper"] == 6.9068
    assert rows["radius_of_min_N"]["verdict"] == "differs"  # stated: tight circles bound the bias


def test_bank_size_against_an_independent_drift_computation(result):
    res = result[1]
    cfg = res["config"]
    speed = math.hypot(cfg["x_start"][1], cfg["x_start"][3])
    row = next(r for r in res["tables"]["bank_size_vs_radius"] if r["radius"] == 20.0 and r["dt_s"] == 1.0)
    mu1 = _mu1_numpy(20.0, 1.0, cfg["q"], cfg["r_meas"], speed)
    assert row["mu1"] == pytest.approx(mu1, rel=1e-7)
    a = math.log(0.999 / 0.001)
    assert row["N_A"] == pytest.approx(2 * a / mu1, rel=1e-7)
    ns = [r["N"] for r in res["tables"]["bank_size_vs_radius"] if r["dt_s"] == 1.0]
    assert ns[-1] > ns[-2] > ns[1]  # grows with r beyond the tight-circle minimum


def test_monte_carlo_sprt_against_wald(result):
    res = result[1]
    m = res["metrics"]
    conv = [r for r in res["tables"]["monte_carlo_sprt"] if r["start"] == "converged"]
    assert {r["runs"] for r in conv} == {64} and all(r["undecided"] == 0 for r in conv)
    for r in conv:  # Wald neglects the overshoot: the MC ASN lies above it, by about a sample
        assert r["asn_wald"] < r["asn_ci_high"] and r["asn_mc"] < 1.6 * r["asn_wald"]
        assert 0.85 < r["mu_wald_identity"] / r["mu_closed_form"] < 1.2
    cold = [r for r in res["tables"]["monte_carlo_sprt"] if r["start"] == "cold"]
    assert all(c["asn_mc"] > w["asn_mc"] for c, w in zip(cold, conv))  # the transient delays a new filter
    assert m["mc_error_rate_ci_high"] < 0.1


def test_bank_rule_tuning_and_consistency(result):
    m = result[1]["metrics"]
    assert m["bank_filters"] % 2 == 1 and 0.9 < m["bank_neighbour_N_max_over_budget"] < 1.4
    assert m["tuned_cost"] < m["initial_cost"]
    assert 3.0 < m["nees_mean"] < 5.0 and 1.5 < m["nis_mean"] < 2.5
