"""Constrained prediction of GNSS differential corrections: the log-barrier QP against SciPy's SLSQP,
its gradient in (c, ψ) against central differences, the predictors against closed forms."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.optimize

from jaxsim.estimation import dc_prediction as dp

M, N = 59, 60


def series(seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(M + 1)
    return 2.0 * np.sin(2 * np.pi * t / 300 + 1.0) + np.cumsum(rng.normal(0, 0.05, M + 1)) + rng.normal(0, 0.3, M + 1)


def constraint_rows(psi, grid=dp.GRID):
    """``G b ≤ h`` of ``|φ| ≤ 1``, ``|dφ/ds| ≤ ψ`` on ``grid`` points of ``s ∈ [0, 1]``, in NumPy."""
    s = np.linspace(0, 1, grid)
    basis = np.stack([np.ones_like(s), s, s * s], axis=1)
    slope = np.stack([np.zeros_like(s), np.ones_like(s), 2 * s], axis=1)
    return np.vstack([basis, -basis, slope, -slope]), np.r_[np.ones(2 * grid), psi * np.ones(2 * grid)]


def slsqp_fit(d, n, c, psi):
    """The constrained least squares of :func:`dp.constrained_fit` by SciPy's SLSQP (``b (3,)``)."""
    s = np.arange(len(d)) / (len(d) - 1 + n)
    a = c * np.stack([np.ones_like(s), s, s * s], axis=1)
    g, h = constraint_rows(psi)
    return scipy.optimize.minimize(
        lambda x: np.mean((d - a @ x) ** 2),
        np.zeros(3),
        method="SLSQP",
        constraints=[{"type": "ineq", "fun": lambda x: h - g @ x}],
        options={"ftol": 1e-15, "maxiter": 500},
    ).x


@pytest.mark.parametrize("c, psi", [(3.0, 0.5), (2.5, 0.2), (5.0, 2.0)])
def test_constrained_fit_matches_slsqp(c, psi):
    d = series()
    b = np.asarray(jax.jit(lambda d: dp.constrained_fit(d, N, c, psi))(jnp.asarray(d)))
    np.testing.assert_allclose(b, slsqp_fit(d, N, c, psi), atol=1e-6)
    g, h = constraint_rows(psi)
    assert np.max(g @ b - h) < 0  # strictly feasible


def test_predictors_against_closed_forms():
    """An exact parabola is predicted exactly by the unconstrained quadratic; the linear predictor
    extrapolates the fitted tangent at the latest sample; hold returns the last correction."""
    s = np.asarray(dp.sample_times(M, N))
    d = jnp.asarray(0.3 + 1.2 * s - 0.8 * s**2)
    assert float(dp.predict(d, N, 1.0, 1.0, "quadratic")) == pytest.approx(0.3 + 1.2 - 0.8, abs=1e-10)
    s0 = M / (M + N)
    tangent = 0.3 + 1.2 * s0 - 0.8 * s0**2 + (1.2 - 1.6 * s0) * (1 - s0)
    assert float(dp.predict(d, N, 1.0, 1.0, "linear")) == pytest.approx(tangent, abs=1e-10)
    assert float(dp.predict(d, N, 1.0, 1.0, "hold")) == float(d[-1])
    # loose constraints (|φ| ≤ 1 with c = 10, slope ≤ 10): the constrained fit is the unconstrained one
    loose = float(dp.predict(d, N, 10.0, 10.0, "quadratic_constrained"))
    assert loose == pytest.approx(0.3 + 1.2 - 0.8, abs=1e-5)
    with pytest.raises(ValueError, match="method"):
        dp.predict(d, N, 1.0, 1.0, "cubic")


def test_gradient_in_c_and_psi_equals_central_differences():
    d = jnp.asarray(series(1))

    def pred(z):
        return dp.predict(d, N, jnp.exp(z[0]), jnp.exp(z[1]), "linear_constrained")

    z = jnp.array([np.log(2.2), np.log(0.3)])
    g = np.asarray(jax.jit(jax.grad(pred))(z))
    f = jax.jit(pred)
    h = 1e-5
    fd = [(float(f(z + h * e)) - float(f(z - h * e))) / (2 * h) for e in np.eye(2)]
    np.testing.assert_allclose(g, fd, rtol=1e-4, atol=1e-7)
    assert np.all(np.abs(g) > 1e-6)  # both constraints bind at this point
