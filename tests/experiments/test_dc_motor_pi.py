"""The README's worked example, ``dc_motor_pi``, through the CLI (quick preset + --set), against
independent computations: the loss by an exact-ZOH NumPy simulation of the same sampled-data loop,
the tuned optimum by SciPy's Nelder–Mead on the same loss."""

import dataclasses

import jax.numpy as jnp
import numpy as np
import pytest
import scipy.optimize
import scipy.signal

from experiments.dc_motor_pi import STUDY, Config, problem_of
from tests.experiments.study_cli import run_quick_study


def oracle_loss(cfg: Config, kp: float, ki: float) -> float:
    """``ITAE + ρ·energy`` of the PI loop on the exact ZOH discretisation of ``K/(s(Ts+1))`` with the
    prefiltered unit step ``1 − exp(−t/τ)`` as reference, the controller written out (``u = kp·e + z``, ``z +=
    ts·ki·e``), each period split in 20 exact
    sub-steps so the load jump at ``t_load`` enters where it happens."""
    a = np.array([[0.0, 1.0], [0.0, -1.0 / cfg.T]])
    b = np.array([[0.0], [cfg.K / cfg.T]])
    n_sub = 20
    h = cfg.ts / n_sub
    ad, bd, *_ = scipy.signal.cont2discrete((a, b, np.eye(2), np.zeros((2, 1))), h, method="zoh")
    x, z, itae, energy = np.zeros(2), 0.0, 0.0, 0.0
    for k in range(int(round(cfg.t_final / cfg.ts))):
        t = k * cfg.ts
        e = 1.0 - np.exp(-t / cfg.prefilter) - x[0]
        u = kp * e + z
        itae += t * abs(e) * cfg.ts
        energy += u * u * cfg.ts
        z += cfg.ts * ki * e
        for i in range(n_sub):
            d = cfg.load if t + i * h >= cfg.t_load - 1e-12 else 0.0
            x = ad @ x + bd[:, 0] * (u - d)
    return itae + cfg.rho * energy


@pytest.fixture(scope="module")
def study_output(tmp_path_factory):
    out = tmp_path_factory.mktemp("dc")
    return out, run_quick_study("dc_motor_pi", out, "--set", "mc_runs=300")


def test_config_is_the_preset_plus_the_override_and_was_used(study_output):
    out, res = study_output
    quick = STUDY.resolve("quick", ["mc_runs=300"])[1]
    assert res["preset"] == "quick" and res["config"] == dataclasses.asdict(quick)
    assert res["config"]["budget"] == 256 and res["config"]["mc_runs"] == 300
    assert [r["runs"] for r in res["tables"]["robustness"]] == [300, 300]
    m = res["metrics"]
    assert m["sims_gradient"] == m["sims_pso"] == 256
    for name in ("loss_vs_budget.png", "step_responses.png", "mc_bands.png", "reproduction.csv", "robustness.csv"):
        assert (out / name).stat().st_size > 0, name
    (row,) = res["reproduction"]
    assert row["metric"] == "loss_ratio_gradient_to_pso" and row["verdict"] == "reproduced"


def test_tuned_loss_against_an_exact_zoh_simulation_and_nelder_mead(study_output):
    _, res = study_output
    cfg = STUDY.resolve("quick", ["mc_runs=300"])[1]
    grad = next(r for r in res["tables"]["comparison"] if r["tuner"] == "gradient")
    # the loss itself: the RK4 rollout vs exact ZOH; the load jump at a tick boundary costs O(dt)
    # in the one RK4 step that ends there (without the load the two agree to 1e-6)
    assert grad["best_loss"] == pytest.approx(oracle_loss(cfg, grad["kp"], grad["ki"]), rel=2e-3)
    no_load = dataclasses.replace(cfg, load=0.0)
    ours = float(problem_of(no_load).jitted.loss({"kp": jnp.asarray(grad["kp"]), "ki": jnp.asarray(grad["ki"])}))
    assert ours == pytest.approx(oracle_loss(no_load, grad["kp"], grad["ki"]), rel=5e-6)
    # the optimum: Nelder-Mead on the same loss (log gains), from the same start
    problem = problem_of(cfg)
    loss = problem.jitted.loss

    def f(z):
        return float(loss({"kp": jnp.exp(z[0]), "ki": jnp.exp(z[1])}))

    nm = scipy.optimize.minimize(
        f, np.log([1.0, 0.5]), method="Nelder-Mead", options=dict(xatol=1e-8, fatol=1e-12, maxiter=2000)
    )
    assert nm.success
    assert grad["best_loss"] == pytest.approx(nm.fun, rel=1e-2)
    assert res["metrics"]["loss_pso"] == pytest.approx(nm.fun, rel=1e-2)
    # the same basin: the loss is flat along ki near the optimum (a 5 % change in ki moves J by < 0.1 %)
    kp_nm, ki_nm = np.exp(nm.x)
    assert grad["kp"] == pytest.approx(kp_nm, rel=0.02) and grad["ki"] == pytest.approx(ki_nm, rel=0.1)
