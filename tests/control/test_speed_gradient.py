"""Speed-gradient energy laws (jaxsim.control.speed_gradient): formulas against NumPy, the Lyapunov
identity dL/dt = −γ1 b Σ (V − V*)² q̇² by forward-mode JVP, and L non-increasing along a SciPy
(solve_ivp, tight tolerance) solution of the reduced model (1)–(2)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.integrate

from jaxsim.control import speed_gradient as sg

A0 = np.array([1.566, 1.0])
B = np.array([2.43, 0.363])
A1 = np.array([0.3, 0.5])
GAINS = sg.SpeedGradientGains(
    gamma1=jnp.array([20.0, 300.0]), gamma2=jnp.array([5.0, 50.0]), v_star=jnp.array([0.094, 0.015]), a0=A0
)


def test_energy_control_and_adaptation_match_numpy():
    rng = np.random.default_rng(0)
    q, qd, ah = rng.uniform(-1.2, 1.2, 2), rng.normal(size=2), rng.normal(size=2)
    v = 0.5 * qd**2 + A0 * (1 - np.cos(q))
    np.testing.assert_allclose(sg.energy(q, qd, A0), v, rtol=1e-14)
    err = v - np.asarray(GAINS.v_star)
    w = (ah * qd - np.asarray(GAINS.gamma1) * err * qd) / np.cos(q)
    np.testing.assert_allclose(sg.control(GAINS, q, qd, ah), w, rtol=1e-12)
    np.testing.assert_allclose(sg.adaptation(GAINS, q, qd), -np.asarray(GAINS.gamma2) * err * qd**2, rtol=1e-12)
    # amplitude inverts the rest energy; the cos floor bounds the division near ±90°
    amp = np.array([0.3, 0.7])
    np.testing.assert_allclose(sg.amplitude(A0 * (1 - np.cos(amp)), A0), amp, rtol=1e-10)
    near = jnp.array([np.pi / 2, -np.pi / 2])
    wn = np.asarray(sg.control(GAINS, near, jnp.ones(2), jnp.ones(2)))
    numer = np.abs(1.0 - np.asarray(GAINS.gamma1) * (np.asarray(sg.energy(near, 1.0, A0)) - np.asarray(GAINS.v_star)))
    assert np.all(np.isfinite(wn)) and np.all(np.abs(wn) <= numer / 0.1 * (1 + 1e-12))


def test_lyapunov_derivative_identity():
    rng = np.random.default_rng(1)
    for _ in range(5):
        x = jnp.asarray(np.concatenate([rng.uniform(-1.0, 1.0, 2), rng.normal(size=2), rng.normal(size=2)]))
        f = sg.reduced_dynamics(GAINS, A1, B, x)
        _, ldot = jax.jvp(lambda z: sg.lyapunov(GAINS, A1, B, z), (x,), (f,))
        err = sg.energy(x[:2], x[2:4], A0) - GAINS.v_star
        expected = -jnp.sum(GAINS.gamma1 * B * err**2 * x[2:4] ** 2)
        assert float(ldot) == pytest.approx(float(expected), rel=1e-10, abs=1e-14)
        assert float(ldot) <= 0.0


def test_lyapunov_non_increasing_along_scipy_solution():
    x0 = np.array([0.09, 0.05, 0.0, 0.0, 0.0, 0.0])
    f = jax.jit(lambda x: sg.reduced_dynamics(GAINS, A1, B, x))
    sol = scipy.integrate.solve_ivp(
        lambda t, x: np.asarray(f(jnp.asarray(x))),
        (0.0, 15.0),
        x0,
        method="DOP853",
        rtol=1e-11,
        atol=1e-13,
        t_eval=np.linspace(0, 15, 301),
    )
    lyap = np.asarray(sg.lyapunov(GAINS, A1, B, jnp.asarray(sol.y.T)))
    assert np.max(np.diff(lyap)) <= 1e-9 * lyap[0]
    assert lyap[-1] < 0.9 * lyap[0]  # it does decrease (energy pumped towards V*)


def test_bad_gains_raise():
    with pytest.raises(ValueError, match="gamma1"):
        sg.validate_gains(sg.SpeedGradientGains(gamma1=-1.0))
    with pytest.raises(ValueError, match="v_star"):
        sg.validate_gains(sg.SpeedGradientGains(v_star=-0.1))
