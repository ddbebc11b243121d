"""Kernels of the MEMS AHRS (jaxsim.inertial.ahrs) against independent references: allantools for the
Gauss–Markov generator (closed-form Allan variance), SciPy rotations and finite differences for the
flight truth, jacfwd for the measurement Jacobian, χ² bounds for the MEKF's NEES."""

import math

import allantools
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from jaxsim.core.rotations import quat_mul, quat_rotation_vector, rotation_from_quat, rotation_zyx
from jaxsim.estimation.gating import chi2_bounds
from jaxsim.inertial import ahrs


def gm_avar_closed_form(T, sigma, tau):
    """Allan variance of a first-order Gauss–Markov rate (variance σ², correlation time τ)."""
    u = T / tau
    return sigma**2 / u**2 * (2 * u - 3 + 4 * np.exp(-u) - np.exp(-2 * u))


def test_gauss_markov_allan_variance_against_allantools():
    sigma, tau, dt, n = 0.05, 300.0, 1.0, 30000
    keys = jax.random.split(jax.random.PRNGKey(3), 48)
    x = np.asarray(jax.vmap(lambda k: ahrs.gauss_markov(k, sigma, tau, dt, n, dim=1)[:, 0])(keys))
    taus = np.array([10.0, 30.0, 100.0, 300.0, 1000.0])
    avars = []
    for seq in x:
        t2, ad, _, _ = allantools.oadev(seq, rate=1.0 / dt, data_type="freq", taus=taus)
        avars.append(ad**2)
    ours = np.mean(avars, axis=0)
    closed = gm_avar_closed_form(t2, sigma, tau)
    np.testing.assert_allclose(ours, closed, rtol=0.12)
    # stationary from the first sample: the variance of x_0 across many sequences is σ²
    x0 = np.asarray(
        jax.vmap(lambda k: ahrs.gauss_markov(k, sigma, tau, dt, 2, dim=1)[0, 0])(
            jax.random.split(jax.random.PRNGKey(4), 4000)
        )
    )
    assert np.var(x0) == pytest.approx(sigma**2, rel=0.1)


def test_gauss_markov_autocovariance_closed_form_and_validation():
    assert float(ahrs.gauss_markov_autocovariance(300.0, 2.0, 300.0)) == pytest.approx(4.0 / math.e, rel=1e-14)
    with pytest.raises(ValueError, match="tau"):
        ahrs.gauss_markov(jax.random.PRNGKey(0), 1.0, -1.0, 1.0, 10)
    with pytest.raises(ValueError, match="n"):
        ahrs.gauss_markov(jax.random.PRNGKey(0), 1.0, 1.0, 1.0, 0)


def test_quat_from_euler_matches_scipy():
    rng = np.random.default_rng(0)
    for _ in range(5):
        e = rng.uniform([-1.0, -1.2, -3.0], [1.0, 1.2, 3.0])
        ref = Rotation.from_euler("ZYX", e[::-1]).as_quat()  # [x, y, z, w]
        q = np.asarray(ahrs.quat_from_euler(jnp.asarray(e)))
        ref = np.concatenate([ref[3:], ref[:3]])
        assert min(np.max(np.abs(q - ref)), np.max(np.abs(q + ref))) < 1e-12
        np.testing.assert_allclose(np.asarray(ahrs.euler_from_quat(jnp.asarray(q))), e, atol=1e-12)


def test_flight_truth_against_finite_differences():
    fl = ahrs.Flight(duration=200.0, turn_angle=2.0, turn_duration=0.3)
    t = jnp.array([31.0, 50.0, 101.0, 120.0])
    tr = ahrs.flight_truth(fl, t)
    h = 1e-4
    for i, ti in enumerate(np.asarray(t)):
        ep, em = (np.asarray(ahrs.flight_truth(fl, jnp.array([ti + s]))["euler"][0]) for s in (h, -h))
        Rp, Rm = np.asarray(rotation_zyx(jnp.asarray(ep))), np.asarray(rotation_zyx(jnp.asarray(em)))
        R = np.asarray(rotation_zyx(tr["euler"][i]))
        W = R.T @ (Rp - Rm) / (2 * h)  # [ω×]
        np.testing.assert_allclose(np.asarray(tr["omega"][i]), [W[2, 1], W[0, 2], W[1, 0]], atol=1e-7)

        def vel(e):
            return fl.speed * np.array([np.cos(e[1]) * np.cos(e[2]), np.cos(e[1]) * np.sin(e[2]), -np.sin(e[1])])

        a_n = (vel(ep) - vel(em)) / (2 * h)
        np.testing.assert_allclose(np.asarray(tr["f"][i]), R.T @ (a_n - [0, 0, ahrs.GRAVITY]), atol=1e-6)
        # air-data identity: body acceleration = ω × [V, 0, 0] at constant airspeed
        np.testing.assert_allclose(
            np.asarray(tr["a_body"][i]), np.cross(np.asarray(tr["omega"][i]), [fl.speed, 0, 0]), atol=1e-9
        )
    # coordinated turn: no lateral specific force
    assert np.max(np.abs(np.asarray(tr["f"][:, 1]))) < 1e-9


def test_specific_force_jacobian_against_jacfwd():
    q = ahrs.quat_from_euler(jnp.array([0.3, -0.2, 1.0]))
    v = jnp.array([0.4, -1.0, 9.0])
    h = lambda d: rotation_from_quat(quat_mul(q, ahrs.quat_exp(d))).T @ v  # noqa: E731
    np.testing.assert_allclose(jax.jacfwd(h)(jnp.zeros(3)), ahrs.specific_force_jacobian(q, v), atol=1e-12)


def test_accel_tilt_and_mag_heading_are_exact_without_errors():
    e = jnp.array([0.2, -0.3, 2.0])
    R = rotation_zyx(e)
    f = R.T @ jnp.array([0.0, 0.0, -ahrs.GRAVITY])
    np.testing.assert_allclose(ahrs.accel_tilt(f), e[:2], atol=1e-12)
    m = R.T @ ahrs.earth_field()
    assert float(ahrs.mag_heading(m, e[0], e[1])) == pytest.approx(2.0, abs=1e-12)


def test_mekf_nees_within_chi2_bounds_static():
    """Static level vehicle, white sensor noise and a constant gyro bias drawn from the filter's prior:
    the run-averaged attitude NEES stays inside its χ² bounds most of the time."""
    dt, n, runs = 0.05, 600, 24
    tun = ahrs.MekfTuning(
        accel_bias=1e-6, mag_bias=1e-6, accel_scale=1e-6, mag_scale=1e-6, accel_sigma=0.02, mag_sigma=0.3, gm_sigma=1e-6
    )
    m_ned = ahrs.earth_field()
    e_true = jnp.array([0.05, -0.02, 0.7])
    q_true = ahrs.quat_from_euler(e_true)
    R = rotation_zyx(e_true)

    def one(key):
        kb, kg, ka, km, k0 = jax.random.split(key, 5)
        bias = tun.gyro_bias * jax.random.normal(kb, (3,))
        gyro = bias + tun.gyro_white * jax.random.normal(kg, (n, 3))
        accel = R.T @ jnp.array([0.0, 0.0, -ahrs.GRAVITY]) + tun.accel_sigma * jax.random.normal(ka, (n, 3))
        mag = R.T @ m_ned + tun.mag_sigma * jax.random.normal(km, (n, 3))
        q0 = quat_mul(q_true, ahrs.quat_exp(tun.attitude0 * jax.random.normal(k0, (3,))))
        res = ahrs.mekf_run(tun, q0, gyro, accel, mag, jnp.zeros(n), m_ned, dt)
        d = quat_rotation_vector(quat_mul(res.q * jnp.array([1.0, -1.0, -1.0, -1.0]), q_true))
        return jnp.einsum("ni,nij,nj->n", d, jnp.linalg.inv(res.P_att), d)

    nees = np.asarray(jax.jit(jax.vmap(one))(jax.random.split(jax.random.PRNGKey(0), runs)))
    lo, hi = chi2_bounds(3, runs, 0.95)
    avg = nees.mean(axis=0)[::10]
    assert np.mean((avg >= lo) & (avg <= hi)) > 0.85
    assert 2.0 < nees.mean() < 4.0


def test_mekf_rejects_bad_shapes():
    n = 10
    z = jnp.zeros((n, 3))
    with pytest.raises(ValueError, match="accel"):
        ahrs.mekf_run(
            ahrs.MekfTuning(), jnp.array([1.0, 0, 0, 0]), z, jnp.zeros((n, 2)), z, jnp.zeros(n), ahrs.earth_field(), 0.1
        )
    with pytest.raises(ValueError, match="update_every"):
        ahrs.mekf_run(
            ahrs.MekfTuning(), jnp.array([1.0, 0, 0, 0]), z, z, z, jnp.zeros(n), ahrs.earth_field(), 0.1, update_every=0
        )
    with pytest.raises(ValueError, match="q0"):
        ahrs.mekf_run(ahrs.MekfTuning(), jnp.zeros(3), z, z, z, jnp.zeros(n), ahrs.earth_field(), 0.1)


def test_complementary_filter_converges_and_estimates_the_gyro_bias():
    """Noise-free static case with a constant gyro bias: the attitude converges to the truth and the
    bias integral to the bias (the fixed point of the filter)."""
    e_true = jnp.array([0.1, -0.05, 0.7])
    R = rotation_zyx(e_true)
    n, dt = 6000, 0.05
    bias = jnp.array([0.003, -0.002, 0.001])
    gyro = jnp.tile(bias, (n, 1))
    accel = jnp.tile(R.T @ jnp.array([0.0, 0.0, -ahrs.GRAVITY]), (n, 1))
    mag = jnp.tile(R.T @ ahrs.earth_field(), (n, 1))
    q0 = quat_mul(ahrs.quat_from_euler(e_true), ahrs.quat_exp(jnp.array([0.05, -0.08, 0.1])))
    gains = ahrs.ComplementaryGains(tilt_crossover=0.1, heading_crossover=0.1, ki_ratio=0.25)
    res = ahrs.complementary_run(gains, q0, gyro, accel, mag, jnp.zeros(n), dt)
    err = np.asarray(ahrs.euler_error(ahrs.euler_from_quat(res.q[-1]), e_true))
    assert np.max(np.abs(err)) < 1e-4
    np.testing.assert_allclose(np.asarray(res.bias[-1]), np.asarray(bias), atol=1e-6)
