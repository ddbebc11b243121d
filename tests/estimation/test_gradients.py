"""Gradients of the log-likelihood with respect to ``F``, ``Q`` and ``R`` through the Kalman filter
(serial and parallel), the EKF, the UKF and the IMM, against central finite differences.

Every entry of ``F`` and every symmetric pair of ``Q`` and ``R`` is a direction; the derivative
along it from ``jax.grad`` must equal the central difference with a step ``1e-6`` relative to the
matrix (float64).  Each loss is jitted once as ``value_and_grad`` and reused for the differences.
"""

from __future__ import annotations

from collections.abc import Callable

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.estimation.ekf import extended_kalman_filter
from jaxsim.estimation.imm import imm, imm_filter, imm_init, linear_member
from jaxsim.estimation.lgssm import LinearGaussianSSM, kalman_filter
from jaxsim.estimation.nonlinear import NonlinearSSM
from jaxsim.estimation.parallel import parallel_kalman_filter
from jaxsim.estimation.ukf import unscented_kalman_filter
from tests.estimation.helpers import random_model, simulate_np

T = 15
REL_STEP = 1e-6


def _directions(shape: tuple[int, int], symmetric: bool) -> list[np.ndarray]:
    """Unit directions: every entry, or every symmetric pair ``E_ij + E_ji`` (``E_ii`` on the diagonal)."""
    out = []
    for i in range(shape[0]):
        for j in range(shape[1]):
            if symmetric and j < i:
                continue
            d = np.zeros(shape)
            d[i, j] = 1.0
            if symmetric:
                d[j, i] = 1.0
            out.append(d)
    return out


def _check_against_finite_differences(loss: Callable[[dict], jax.Array], theta: dict[str, np.ndarray]) -> dict:
    """Directional derivatives from ``jax.grad`` vs central differences along every direction of
    every field of ``theta`` (``F`` element-wise, ``Q`` and ``R`` symmetric); returns the gradient."""
    vg = jax.jit(jax.value_and_grad(loss))
    _, grad = vg(theta)
    for name, value in theta.items():
        h = REL_STEP * float(np.max(np.abs(value)))
        ad, fd = [], []
        for d in _directions(value.shape, symmetric=name != "F"):
            plus = vg({**theta, name: value + h * d})[0]
            minus = vg({**theta, name: value - h * d})[0]
            fd.append(float(plus - minus) / (2 * h))
            ad.append(float(np.sum(np.asarray(grad[name]) * d)))
        fd, ad = np.array(fd), np.array(ad)
        assert np.max(np.abs(fd)) > 1e-3, f"{name}: the loss hardly depends on it, the check is vacuous"
        np.testing.assert_allclose(ad, fd, rtol=1e-6, atol=1e-6 * np.max(np.abs(fd)), err_msg=name)
    return grad


def _linear_problem(seed: int = 30):
    rng = np.random.default_rng(seed)
    model = random_model(rng, n=2, p=2)
    _, y = simulate_np(model, rng, T, None)
    mask = rng.random((T, 2)) > 0.25
    mask[5] = False
    theta = {k: np.asarray(getattr(model, k), float) for k in ("F", "Q", "R")}
    return model, np.where(mask, y, np.nan), theta


def _linear_loss(model: LinearGaussianSSM, y: np.ndarray, run: Callable) -> Callable[[dict], jax.Array]:
    def loss(th):
        m = LinearGaussianSSM(th["F"], th["Q"], model.H, th["R"], model.m0, model.P0)
        return run(m, y, missing="nan").log_likelihood

    return loss


def test_kalman_log_likelihood_gradient_matches_finite_differences():
    model, y, theta = _linear_problem()
    _check_against_finite_differences(_linear_loss(model, y, kalman_filter), theta)


@pytest.mark.slow  # the associative scan's gradient compiles slowly on a CPU (~30 s on a loaded 2-core machine)
def test_parallel_gradient_matches_finite_differences_and_the_serial_gradient():
    """Also the full matrices: a non-symmetric gradient in ``Q`` (what the parallel filter gave
    before ``Q`` was symmetrised in its elements) differs from the serial filter's."""
    model, y, theta = _linear_problem(seed=31)
    g_par = _check_against_finite_differences(_linear_loss(model, y, parallel_kalman_filter), theta)
    g_ser = jax.jit(jax.grad(_linear_loss(model, y, kalman_filter)))(theta)
    for k in theta:
        np.testing.assert_allclose(g_par[k], g_ser[k], rtol=1e-9, atol=1e-9 * np.max(np.abs(g_ser[k])), err_msg=k)


def _nl_f(params, x, u):
    return params["F"] @ x + 0.3 * jnp.sin(x)


def _nl_h(params, x):
    return jnp.stack([x[0] + 0.2 * x[1] ** 2])


def _nonlinear_problem():
    rng = np.random.default_rng(32)
    theta = {
        "F": np.array([[0.9, 0.2], [-0.1, 0.7]]),
        "Q": np.array([[0.05, 0.01], [0.01, 0.08]]),
        "R": np.array([[0.1]]),
    }
    x, ys = np.array([0.5, -0.3]), []
    for _ in range(T):
        ys.append(np.asarray(_nl_h(None, x)) + rng.normal(0, np.sqrt(0.1), 1))
        x = np.asarray(_nl_f(theta, x, None)) + rng.multivariate_normal(np.zeros(2), theta["Q"])
    m0, p0 = np.array([0.3, 0.0]), np.diag([0.2, 0.3])

    def model(th):
        return NonlinearSSM({"F": th["F"]}, th["Q"], th["R"], m0, p0, _nl_f, _nl_h)

    return model, np.array(ys), theta


@pytest.mark.parametrize("which", ["ekf", "ukf"])
def test_nonlinear_filter_log_likelihood_gradient_matches_finite_differences(which):
    model, y, theta = _nonlinear_problem()
    run = {
        "ekf": lambda m: extended_kalman_filter(m, y),
        "ukf": lambda m: unscented_kalman_filter(m, y, alpha=0.8, beta=2.0, kappa=1.0),
    }[which]
    _check_against_finite_differences(lambda th: run(model(th)).log_likelihood, theta)


def test_imm_log_likelihood_gradient_matches_finite_differences():
    """Two linear members; ``F``, ``Q``, ``R`` of the first member are differentiated."""
    model, y, theta = _linear_problem(seed=33)
    pi = np.array([[0.9, 0.1], [0.2, 0.8]])
    other = linear_member(0.8 * np.asarray(model.F), 4.0 * np.asarray(model.Q), model.H, model.R)
    init = imm_init(np.stack([model.m0] * 2), np.stack([model.P0] * 2), np.array([0.5, 0.5]))

    def loss(th):
        bank = imm((linear_member(th["F"], th["Q"], model.H, th["R"]), other), pi)
        return imm_filter(bank, init, y, missing="nan").log_likelihood

    _check_against_finite_differences(loss, theta)
