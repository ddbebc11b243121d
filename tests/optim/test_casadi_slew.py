"""Station slew: CasADi/IPOPT multiple shooting against the JAX rollout and the JAX SQP shooting —
the same discrete problem written twice, so the nodes and the optimal fuel agree to rounding."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.control import station_slew as ss
from optim import casadi_slew as cs


def test_ipopt_and_jax_shooting_agree_on_the_optimal_fuel():
    prob = ss.SlewProblem(n_intervals=6, substeps=2)
    r = cs.solve(prob, np.random.default_rng(2).normal(0, 3, (6, 3)))
    assert r["status"] == "Solve_Succeeded"
    # CasADi's nodes are the JAX rollout of CasADi's torques
    xs = jax.jit(lambda u: ss.rollout(u, prob))(jnp.asarray(r["u"]))
    np.testing.assert_allclose(np.asarray(xs), r["x"], atol=1e-9)
    assert float(np.abs(ss.terminal_error(xs[-1], prob)).max()) < 1e-9
    # JAX SQP started off the IPOPT optimum returns to it
    s = jax.jit(lambda u: ss.shoot(u, prob, iters=60))(jnp.asarray(r["u"]) + 0.01)
    assert float(np.abs(s["error"]).max()) < 1e-9
    assert float(s["fuel"]) == pytest.approx(r["fuel"], rel=1e-8)
    np.testing.assert_allclose(np.asarray(s["u"]), r["u"], atol=1e-4)
    # IPOPT's optimum satisfies the JAX problem's first-order conditions; a perturbed point does not
    kkt = jax.jit(lambda u: ss.kkt_residuals(u, prob))
    at_opt, off_opt = kkt(jnp.asarray(r["u"])), kkt(jnp.asarray(r["u"]) + 0.01)
    assert float(at_opt["stationarity"]) < 1e-6 and float(at_opt["error"]) < 1e-9
    assert float(at_opt["fuel"]) == pytest.approx(r["fuel"], rel=1e-12)
    assert float(off_opt["stationarity"]) > 1e-4
    # IPOPT warm-started at its own solution (torques and node states) stays there
    (again,) = cs.solve_many(prob, [r["u"]], states=[r["x"]])
    assert again["status"] == "Solve_Succeeded" and again["iterations"] <= 5
    assert again["fuel"] == pytest.approx(r["fuel"], rel=1e-10)
    with pytest.raises(ValueError, match="states"):
        cs.solve_many(prob, [r["u"]], states=[r["x"][:-1]])
