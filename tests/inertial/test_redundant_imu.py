"""Redundant-IMU kernels against independent references: NumPy least squares (reconstruction and the
leave-one-out residuals), the exact TRIAD azimuth of a biased East component, SciPy rotations for the
attitude errors, and the parity-space FDI on noise-free faults (vmap == loop)."""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from jaxsim.inertial import redundant_imu as ri

H = ri.dodecahedron_axes()
HN = np.asarray(H)


def test_axes_geometry_and_reconstruction():
    np.testing.assert_allclose(HN.T @ HN, 2 * np.eye(3), atol=1e-14)
    np.testing.assert_allclose(np.linalg.norm(HN, axis=1), 1.0, rtol=1e-14)
    np.testing.assert_allclose(HN[0] * [1, -1, 1], HN[5], atol=1e-15)  # DUS1/DUS6 mirror pair
    m = np.random.default_rng(0).normal(size=6)
    np.testing.assert_allclose(ri.reconstruct(H, m), np.linalg.lstsq(HN, m, rcond=None)[0], rtol=1e-12)
    np.testing.assert_allclose(ri.reconstruct(H, m), 0.5 * HN.T @ m, rtol=1e-12)


@pytest.mark.parametrize("lat_deg", [0.0, 30.0])
def test_bias_azimuth_against_the_exact_triad_angle(lat_deg):
    lat = math.radians(lat_deg)
    f, w = ri.navigation_vectors(lat)
    b = 0.05 * ri.DEG_PER_HOUR
    for i in range(6):
        m_w = ri.measure(H, w, bias=jnp.zeros(6).at[i].set(b))
        psi = float(ri.attitude_errors(ri.align_from_readings(H, ri.measure(H, f), m_w), jnp.eye(3))[2])
        d = 0.5 * HN[i] * b  # reconstructed-rate error; East ∥ ω × Up: angle atan(δ_E / (U cos φ + δ_N))
        ref = -math.atan2(d[0], ri.EARTH_RATE * math.cos(lat) + d[1])
        assert psi == pytest.approx(ref, rel=1e-6, abs=1e-15)
        first_order = abs(HN[i, 0]) * b / (2 * ri.EARTH_RATE * math.cos(lat))
        assert abs(psi) == pytest.approx(first_order, rel=2e-3, abs=1e-15)


def test_attitude_errors_against_scipy_rotation():
    phi = np.array([2e-5, -3e-5, 4e-5])
    C_true = Rotation.from_euler("zyx", [0.3, -0.1, 0.2]).as_matrix()
    C_est = Rotation.from_rotvec(-phi).as_matrix() @ C_true  # C_est = (I − [φ×]) C_true to first order
    np.testing.assert_allclose(ri.attitude_errors(jnp.asarray(C_est), jnp.asarray(C_true)), phi, rtol=1e-6)


def test_parity_and_leave_one_out_against_numpy():
    V = np.asarray(ri.parity_matrix(H))
    np.testing.assert_allclose(V @ HN, 0.0, atol=1e-14)
    np.testing.assert_allclose(V @ V.T, np.eye(3), atol=1e-14)
    m = np.random.default_rng(1).normal(size=6)
    ref = []
    for i in range(6):
        keep = np.arange(6) != i
        x = np.linalg.lstsq(HN[keep], m[keep], rcond=None)[0]
        ref.append(m[i] - HN[i] @ x)
    np.testing.assert_allclose(ri.loo_residuals(V, m), ref, rtol=1e-10)


def test_fdi_isolates_and_corrects_noise_free_faults_vmap_equals_loop():
    V = ri.parity_matrix(H)
    _, w = ri.navigation_vectors(0.0)
    clean = ri.measure(H, w)
    sigma = 1e-8
    faults = clean[None] + 1e-6 * jnp.eye(6)  # one faulty gyro per row, 100 σ
    batch = jax.vmap(lambda m: ri.fdi(V, m, sigma, 16.27))(faults)
    for i in range(6):
        one = ri.fdi(V, faults[i], sigma, 16.27)
        assert bool(one.detected) and int(one.isolated) == i
        assert float(one.bias_estimate) == pytest.approx(1e-6, rel=1e-8)
        np.testing.assert_allclose(one.corrected, clean, atol=1e-14)
        assert float(one.statistic) == pytest.approx(float(jnp.sum((V @ faults[i]) ** 2)) / sigma**2, rel=1e-12)
        np.testing.assert_allclose(batch.corrected[i], one.corrected, rtol=1e-12, atol=1e-18)
    ok = ri.fdi(V, clean, sigma, 16.27)
    assert not bool(ok.detected)
    np.testing.assert_allclose(ok.corrected, clean, rtol=0)


def test_bad_axes_name_the_argument():
    with pytest.raises(ValueError, match="H"):
        ri.reconstruct(jnp.ones((3, 3)), jnp.ones(3))
