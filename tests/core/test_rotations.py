"""Quaternion kernels of :mod:`jaxsim.core.rotations` against SciPy's ``Rotation`` and finite differences."""

import jax
import jax.numpy as jnp
import numpy as np
from scipy.spatial.transform import Rotation

from jaxsim.core.rotations import quat_exp, quat_kinematics, quat_mul, rotation_from_quat, rotation_zyx


def scipy_quat(q):
    """[w, x, y, z] → SciPy's scalar-last order."""
    return np.roll(np.asarray(q), -1)


def test_rotation_from_quat_matches_scipy_and_ignores_scale():
    rng = np.random.default_rng(0)
    for q in rng.normal(size=(5, 4)):
        ref = Rotation.from_quat(scipy_quat(q)).as_matrix()
        np.testing.assert_allclose(rotation_from_quat(jnp.asarray(3.0 * q)), ref, atol=1e-14)


def test_quat_exp_and_product_compose_like_rotation_matrices():
    rng = np.random.default_rng(1)
    a, b = rng.normal(size=(2, 3))
    qa, qb = quat_exp(jnp.asarray(a)), quat_exp(jnp.asarray(b))
    np.testing.assert_allclose(rotation_from_quat(qa), Rotation.from_rotvec(a).as_matrix(), atol=1e-14)
    np.testing.assert_allclose(
        rotation_from_quat(quat_mul(qa, qb)), rotation_from_quat(qa) @ rotation_from_quat(qb), atol=1e-14
    )
    # zyx Euler angles: R_z(ψ) R_y(θ) R_x(φ) as three elementary quaternions
    euler = jnp.array([0.3, -0.2, 1.1])
    q = quat_mul(
        quat_mul(quat_exp(jnp.array([0, 0, 1.1])), quat_exp(jnp.array([0, -0.2, 0]))), quat_exp(jnp.array([0.3, 0, 0]))
    )
    np.testing.assert_allclose(rotation_from_quat(q), rotation_zyx(euler), atol=1e-14)


def test_quat_kinematics_is_the_derivative_of_a_body_rate_rotation():
    """For a constant body rate ω, q(t) = q0 ⊗ exp(ω t): q̇(0) by central differences."""
    q0 = quat_exp(jnp.array([0.4, -0.1, 0.7]))
    omega = jnp.array([0.5, -1.2, 0.3])
    h = 1e-6
    fd = (quat_mul(q0, quat_exp(omega * h)) - quat_mul(q0, quat_exp(-omega * h))) / (2 * h)
    np.testing.assert_allclose(quat_kinematics(q0, omega), fd, atol=1e-9)
    # the kinematics keeps |q| = 1: d|q|²/dt = 2 q·q̇ = 0
    assert abs(float(jnp.dot(q0, quat_kinematics(q0, omega)))) < 1e-15
    assert jax.jit(quat_kinematics)(q0, omega).shape == (4,)
