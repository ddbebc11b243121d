"""Piezo accelerometer (seed 004 #25/#26): resonator and bench against scipy.signal and solve_ivp."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.integrate
import scipy.optimize
import scipy.signal

from jaxsim.core.integrators import RK4, integrate
from jaxsim.plants import piezo_accelerometer as pa


def test_resonator_response_state_space_and_peak():
    p = pa.ResonatorParams(f_r=807.5, q=35.0, gain=2.0)
    a, b, c = (np.asarray(m) for m in pa.resonator_state_space(p))
    f = np.array([10.0, 700.0, 807.5, 900.0])
    h_ref = [(c @ np.linalg.solve(2j * np.pi * fk * np.eye(2) - a, b))[0, 0] for fk in f]  # C (sI − A)⁻¹ B
    np.testing.assert_allclose(np.asarray(pa.resonator_response(p, f)), h_ref, rtol=1e-10)
    x, u = jnp.array([0.1, -30.0]), jnp.array([0.5])
    np.testing.assert_allclose(np.asarray(pa.resonator_dynamics(p, x, u, 0.0)), a @ np.asarray(x) + b[:, 0] * 0.5)
    peak = scipy.optimize.minimize_scalar(
        lambda fr: -abs(complex(pa.resonator_response(p, fr))),
        bounds=(790, 820),
        method="bounded",
        options={"xatol": 1e-9},
    )
    assert peak.x == pytest.approx(807.5, abs=1e-5)


def test_bench_time_constant_and_response():
    p = pa.BenchParams()
    r = 1.0 / (1.0 / 5.5e6 + 1.0 / 6e11)
    assert float(pa.time_constant(p)) == pytest.approx(1.2e-9 * r, rel=1e-14)
    tau = 1.2e-9 * r
    f = np.array([1.0, 10.0, 24.1146, 1000.0])
    _, h_ref = scipy.signal.freqs([10e-3 * tau, 0.0], [tau, 1.0], worN=2 * np.pi * f)
    np.testing.assert_allclose(np.asarray(pa.bench_response(p, f)), h_ref, rtol=1e-12)
    assert float(pa.corner_frequency(p)) == pytest.approx(1 / (2 * np.pi * tau), rel=1e-14)


def test_bench_plant_against_solve_ivp():
    p = pa.BenchParams()
    plant = pa.bench_sensor(p)
    tau, kp, f, phi = float(pa.time_constant(p)), p.kp, 20.0, 1.2

    def rhs(t, x):
        return plant.f(x, pa.rotating_input(f, t, phi)[None], t)

    ts, xs = integrate(rhs, jnp.zeros(1), 0.0, 1e-4, 500, RK4)
    v = np.asarray(jax.vmap(lambda x, t: plant.h(x, pa.rotating_input(f, t, phi)[None])[0])(xs, ts))
    # the same circuit written as C_d·V̇ = d·ȧ − V/R with K_p = d/C_d: V̇ = K_p·ȧ − V/τ
    ref = scipy.integrate.solve_ivp(
        lambda t, vv: [kp * np.cos(phi) * 2 * np.pi * f * np.cos(2 * np.pi * f * t) - vv[0] / tau],
        (0.0, 0.05),
        [0.0],
        t_eval=np.asarray(ts),
        rtol=1e-11,
        atol=1e-14,
    )
    np.testing.assert_allclose(v, ref.y[0], atol=1e-9)


def test_bad_parameters_raise():
    with pytest.raises(ValueError, match="q"):
        pa.resonator(q=0.5)
    with pytest.raises(ValueError, match="c_d"):
        pa.bench_sensor(c_d=-1.0)
