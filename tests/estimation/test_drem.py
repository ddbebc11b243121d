"""DREM (:mod:`jaxsim.estimation.drem`), the PMSM flux regression (:mod:`jaxsim.estimation.pmsm_flux`)
and the PMSM plant (:mod:`jaxsim.plants.pmsm`): cofactors against NumPy, the regression identity, exact
element-wise monotone convergence on a synthetic regression, the plant's power balance."""

import itertools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.estimation import drem
from jaxsim.estimation import pmsm_flux as pf
from jaxsim.plants import pmsm


def numpy_adjugate(m):
    n = m.shape[0]
    adj = np.empty_like(m)
    for i, j in itertools.product(range(n), range(n)):
        minor = np.delete(np.delete(m, i, 0), j, 1)
        adj[j, i] = (-1) ** (i + j) * np.linalg.det(minor)
    return adj


@pytest.mark.parametrize("n", [1, 2, 5, 7])
def test_adjugate_against_numpy_cofactors_and_singular_matrices(n):
    rng = np.random.default_rng(n)
    m = rng.normal(size=(n, n))
    np.testing.assert_allclose(drem.adjugate(jnp.asarray(m)), numpy_adjugate(m) if n > 1 else [[1.0]], rtol=1e-10)
    np.testing.assert_allclose(drem.adjugate(jnp.asarray(m)) @ m, np.linalg.det(m) * np.eye(n), atol=1e-10)
    if n > 2:  # rank n − 1: det·M⁻¹ does not exist, the adjugate does (rank 1, M·adj M = 0)
        s = m.copy()
        s[-1] = s[0] + s[1]
        adj = np.asarray(drem.adjugate(jnp.asarray(s)))
        np.testing.assert_allclose(adj, numpy_adjugate(s), rtol=1e-8, atol=1e-12)
        np.testing.assert_allclose(s @ adj, 0.0, atol=1e-10)
    with pytest.raises(ValueError, match="square"):
        drem.adjugate(jnp.zeros((2, 3)))


def test_drem_converges_element_wise_monotonically_on_a_synthetic_regression():
    """z = φ(t)ᵀθ with φ = (sin t, cos 2t, 1): filtered copies, mixing, the implicit gradient step."""
    theta = jnp.array([1.5, -0.7, 0.3])
    dt, n = 1e-3, 20000
    a, b = drem.lowpass_bank(jnp.array([1.0, 3.0, 9.0]), dt)

    def tick(carry, t):
        filt, est = carry
        phi = jnp.stack([jnp.sin(t), jnp.cos(2 * t), jnp.ones(())])
        filt = a[:, None] * filt + b[:, None] * jnp.concatenate([(phi @ theta)[None], phi])[None, :]
        delta, y = drem.mix(filt[:, 1:], filt[:, 0])
        est = drem.estimator_step(est, delta, y, 1e6, dt)
        return (filt, est), est

    _, hist = jax.lax.scan(tick, (jnp.zeros((3, 4)), jnp.zeros(3)), jnp.arange(n) * dt)
    err = np.abs(np.asarray(hist) - np.asarray(theta))
    assert np.all(np.diff(err, axis=0) <= 1e-12)  # monotone, element by element
    np.testing.assert_allclose(hist[-1], theta, atol=1e-6)


def test_estimator_step_is_monotone_for_any_gain_and_step():
    rng = np.random.default_rng(0)
    for _ in range(50):
        theta, est = rng.normal(size=4), rng.normal(size=4)
        delta = rng.normal() * 10 ** rng.uniform(-20, 2)
        gamma, dt = 10 ** rng.uniform(-5, 40), 10 ** rng.uniform(-6, 0)
        new = np.asarray(drem.estimator_step(jnp.asarray(est), delta, delta * jnp.asarray(theta), gamma, dt))
        assert np.all(np.abs(new - theta) <= np.abs(est - theta) * (1 + 1e-12))


def test_pmsm_regression_identity():
    rng = np.random.default_rng(1)
    for _ in range(20):
        c, zeta, lam_m, t = rng.normal(size=2), rng.normal(size=2), rng.uniform(0.05, 0.5), rng.uniform(0, 3)
        ang = rng.uniform(0, 2 * np.pi)
        q = lam_m * np.array([np.cos(ang), np.sin(ang)]) - zeta * t - c
        y, phi = pf.regressor(jnp.asarray(q), jnp.asarray(t))
        theta = pf.true_parameters(jnp.asarray(c), jnp.asarray(zeta), lam_m)
        assert float(y) == pytest.approx(float(phi @ theta), abs=1e-12)
        np.testing.assert_allclose(pf.magnet_flux(jnp.asarray(q), t, theta), q + zeta * t + c, rtol=1e-14)


def test_pmsm_power_balance():
    """vᵀi = R|i|² + d/dt(L|i|²/2) + τ_e ω at any state and input (energy conservation of the model)."""
    p = pmsm.Params()
    rng = np.random.default_rng(2)
    for _ in range(10):
        x = jnp.asarray([*rng.normal(scale=0.2, size=2), rng.normal(scale=50), rng.uniform(0, 6)])
        u = jnp.asarray([*rng.normal(scale=20, size=2), 0.0])
        dx = pmsm.dynamics(p, x, u, 0.0)
        i = pmsm.current(p, x)
        di = jax.jvp(lambda s: pmsm.current(p, s), (x,), (dx,))[1]
        lhs = u[:2] @ i
        rhs = p.R * i @ i + p.L * i @ di + pmsm.torque(p, x) * x[2]
        assert float(lhs) == pytest.approx(float(rhs), rel=1e-10, abs=1e-9)
