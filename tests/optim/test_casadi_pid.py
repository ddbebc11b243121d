"""CasADi cross-check of the PID tuning problem: same loss, same gradient, same optimum as IPOPT."""

import jax
import jax.numpy as jnp
import numpy as np
import optax
import pytest

from optim.casadi_pid import casadi_value_and_grad, ipopt_tune
from optim.problems import PIDTuning
from optim.tune import tune

PROBLEM = PIDTuning()
POINTS = [np.array([3.0, 2.0, 0.2]), np.array([0.7, 5.0, 0.0]), np.array([12.0, 9.0, 1.1])]


@pytest.fixture(scope="module")
def jax_value_and_grad():
    return jax.jit(jax.value_and_grad(PROBLEM.loss))


@pytest.mark.parametrize("gains", POINTS, ids=["mid", "pi", "high"])
def test_losses_and_gradients_agree(gains, jax_value_and_grad):
    v_jax, g_jax = jax_value_and_grad(jnp.asarray(gains))
    v_ca, g_ca = casadi_value_and_grad(PROBLEM, gains)
    assert float(v_jax) == pytest.approx(v_ca, rel=1e-12)  # the same discrete computation
    np.testing.assert_allclose(np.asarray(g_jax), g_ca, rtol=1e-6, atol=1e-6 * np.max(np.abs(g_ca)))
    # both against central finite differences of the JAX loss
    loss = jax.jit(PROBLEM.loss)
    h = 1e-6
    fd = [(loss(jnp.asarray(gains + h * e)) - loss(jnp.asarray(gains - h * e))) / (2 * h) for e in np.eye(3)]
    np.testing.assert_allclose(g_ca, np.asarray(fd), rtol=1e-6, atol=1e-8)


def test_gradient_tuner_and_ipopt_reach_the_same_optimum():
    ip = ipopt_tune(PROBLEM, np.array([1.0, 1.0, 0.1]), tol=1e-12)
    assert "Solve_Succeeded" in ip.message
    ours = tune(
        PROBLEM.loss,
        jnp.array([1.0, 1.0, 0.1]),
        steps=100,
        gtol=1e-10,
        optimizer=optax.lbfgs(linesearch=optax.scale_by_backtracking_linesearch(20)),
    )
    assert ours.mode == "forward"
    np.testing.assert_allclose(np.asarray(ours.params), ip.x, rtol=1e-6)
    assert ours.loss == pytest.approx(ip.loss, rel=1e-12)
    # an interior optimum: inside the box, gradient zero by CasADi's own AD
    lo, hi = PROBLEM.box
    assert np.all(ip.x > lo) and np.all(ip.x < hi)
    _, g = casadi_value_and_grad(PROBLEM, ip.x)
    assert np.linalg.norm(g) < 1e-7
    assert ip.n_sims > 0 and ip.history.sims[-1] == ip.n_sims and np.all(np.diff(ip.history.best_loss) <= 0)


def test_bad_start_point():
    with pytest.raises(ValueError, match="x0"):
        ipopt_tune(PROBLEM, np.array([-1.0, 1.0, 0.1]))
    with pytest.raises(ValueError, match="lo/hi"):
        ipopt_tune(PROBLEM, np.array([1.0, 1.0, 0.1]), lo=[0, 0, 0], hi=[5, 5, 0])
