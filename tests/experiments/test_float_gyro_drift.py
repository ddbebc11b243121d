"""Study ``float_gyro_drift`` through the CLI (tiny preset): files and config, the Monte-Carlo table's
intervals, and the bank's posterior mean of the first draw recomputed by an independent NumPy Kalman filter."""

from __future__ import annotations

import jax
import numpy as np
import pytest

from experiments.float_gyro_drift import STUDY
from jaxsim.estimation.lgssm import sample
from jaxsim.inertial import float_gyro as fg
from tests.experiments.study_cli import run_quick_study


@pytest.fixture(scope="module")
def study_output(tmp_path_factory):
    out = tmp_path_factory.mktemp("float_gyro")
    return out, run_quick_study("float_gyro_drift", out, preset="tiny")


def numpy_loglik(y: np.ndarray, u: np.ndarray, alpha: float, beta: float, cfg) -> float:
    """Scalar-measurement Kalman filter of ``[ε₀, ε̃]`` in NumPy (update, then predict)."""
    phi = np.exp(-alpha * cfg.dt)
    b, q = beta * (1 - phi) / alpha, cfg.sigma**2 * (1 - phi**2)
    m, P = np.zeros(2), np.diag([cfg.sigma0**2, cfg.sigma**2])
    F, Hr, ll = np.diag([1.0, phi]), np.ones(2), 0.0
    for k in range(len(y)):
        s = Hr @ P @ Hr + cfg.r**2
        e = y[k] - Hr @ m
        ll -= 0.5 * (np.log(2 * np.pi * s) + e * e / s)
        K = P @ Hr / s
        m, P = m + K * e, P - np.outer(K, Hr @ P)
        m, P = F @ m + np.array([0.0, b * u[k]]), F @ P @ F.T + np.diag([0.0, q])
    return ll


def test_config_files_and_tables(study_output):
    out, res = study_output
    cfg = STUDY.resolve("tiny")[1]
    assert res["preset"] == "tiny" and res["config"]["n_steps"] == cfg.n_steps and res["config"]["runs"] == cfg.runs
    for name in ("one_run.csv", "monte_carlo.csv", "estimates_vs_time.png", "alpha_errors.png", "reproduction.csv"):
        assert (out / name).stat().st_size > 0, name
    rows = {r["method"]: r for r in res["tables"]["monte_carlo"]}
    assert set(rows) == {"bank", "ekf", "ml"}
    for r in rows.values():
        assert r["runs"] == cfg.runs
        assert r["alpha_err_ci95_low"] <= r["alpha_mean_abs_rel_err"] <= r["alpha_err_ci95_high"]
    m = res["metrics"]
    assert m["ml_max_grad_norm"] < 1e-6  # every ML run ends at a stationary point of the likelihood
    assert 0.0 <= m["kf_nees_fraction_within_bounds"] <= 1.0
    claimed = {r["metric"] for r in res["reproduction"]}
    assert claimed >= {"bank_alpha_mean_rel_err", "alpha_error_reduction_bank_vs_ekf"}


def test_bank_estimate_against_numpy_filter(study_output):
    _, res = study_output
    cfg = STUDY.resolve("tiny")[1]
    u = np.asarray(fg.warmup_temperature(np.arange(cfg.n_steps) * cfg.dt, cfg.delta_temp, cfg.tau_temp))
    true = fg.drift_model(cfg.alpha, cfg.beta, cfg.dt, cfg.sigma, cfg.sigma0, cfg.r)
    key = jax.random.split(jax.random.PRNGKey(cfg.seed), cfg.runs)[0]  # the study's first draw
    _, y = jax.jit(sample, static_argnums=2)(true, key, cfg.n_steps, u[:, None])
    y = np.asarray(y)[:, 0]
    a, b = np.meshgrid(np.linspace(*cfg.alpha_grid), np.linspace(*cfg.beta_grid), indexing="ij")
    ll = np.array([numpy_loglik(y, u, ai, bi, cfg) for ai, bi in zip(a.ravel(), b.ravel())])
    w = np.exp(ll - ll.max())
    w /= w.sum()
    row = next(r for r in res["tables"]["one_run"] if r["method"] == "bank")
    assert row["alpha_est"] == pytest.approx(w @ a.ravel(), rel=1e-8)
    assert row["beta_est"] == pytest.approx(w @ b.ravel(), rel=1e-8)
    assert row["alpha_err_pct"] == pytest.approx(100 * abs(row["alpha_est"] / cfg.alpha - 1), rel=1e-12)
