"""Redundant strapdown IMU (6 gyros + 6 accelerometers on the normals of a dodecahedron's faces):
least-squares vector reconstruction, analytic (gyrocompass) alignment, sensor-error influence, and
failure detection and isolation in the parity space (seed 004 part 2, #19, spec §2.3).

Frames: the navigation frame is ENU (East, North, Up); the instrument frame coincides with it unless a
body-to-navigation matrix ``C_bn`` is given (the paper's Fig. 1 with the true orientation is lost).
Sensor ``i`` measures ``m_i = h_iᵀ v_b`` (``v_b`` the angular rate in rad/s or the specific force in m/s²
in the instrument frame).  The axes :func:`dodecahedron_axes` are ``(0, ±1, φ), (±1, φ, 0), (φ, 0, ±1)``
over ``√(1 + φ²)`` (``φ`` the golden ratio), so ``HᵀH = 2I`` and the reconstruction is ``½ Hᵀ m``.

Alignment (:func:`analytic_alignment`, TRIAD): Up along the reconstructed specific force, East along
``ω × f``, North completing the frame.  :func:`attitude_errors` returns the small rotation
``(φ_E, φ_N, ψ)`` (rad) of the estimated frame relative to the true one; ``ψ`` (about Up) is the azimuth
error.  A gyro bias ``δω`` on sensor ``i`` gives ``|ψ| = |e_E·h_i| δω / (2 U cos φ_lat)`` at the equator.

Parity space (:func:`parity_matrix`): ``V (3, 6)`` with orthonormal rows and ``V H = 0``; ``p = V m`` is free
of the true vector.  :func:`loo_residuals` are the paper's "differences between each sensor's reading and
the projection of the vector reconstructed from the other five", ``r_i = v_iᵀ p / ‖v_i‖²`` (``v_i`` the
i-th column of ``V``); under a bias ``b`` on sensor ``i`` alone, ``r_i = b + noise``.  :func:`fdi` detects
by the χ²(3) test on ``‖p‖²/σ²``, isolates the largest normalised residual ``|r_i| ‖v_i‖ / σ`` and
corrects that sensor by ``r_i``.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.inertial.carousel import EARTH_RATE

GOLDEN = (1.0 + math.sqrt(5.0)) / 2.0
GRAVITY_EQUATOR = 9.78  # m/s², spec §2.3 (0.0015/9.78 rad = 0.53′)
ARCMIN = math.pi / (180.0 * 60.0)  # rad per arc-minute
DEG_PER_HOUR = math.pi / 180.0 / 3600.0  # rad/s per °/h


def dodecahedron_axes() -> jax.Array:
    """``H (6, 3)``: unit sensitive axes DUS1…DUS6 normal to the faces of a dodecahedron (one per pair
    of opposite faces).  Order (assumed; the paper's Fig. 1 is lost): DUS1/DUS6 ``(0, ±1, φ)``, DUS2/DUS5
    ``(φ, 0, ±1)``, DUS3/DUS4 ``(±1, φ, 0)`` — the symmetric pairs of the paper's table, placed so that the
    East projections ``0, 0.8507, 0.5257`` give its bias column (≈ 0, 4.86′, 3.00′)."""
    g = GOLDEN
    h = np.array([[0, 1, g], [g, 0, 1], [1, g, 0], [-1, g, 0], [g, 0, -1], [0, -1, g]], dtype=float)
    return jnp.asarray(h / math.sqrt(1 + g * g))


def _check_axes(H: Any) -> jax.Array:
    H = jnp.asarray(H)
    if H.ndim != 2 or H.shape[1] != 3 or H.shape[0] < 4:
        raise ValueError(f"H: expected shape (n ≥ 4, 3), got {tuple(H.shape)}")
    return H


def reconstruct(H: Any, m: Any) -> jax.Array:
    """Least-squares vector ``(HᵀH)⁻¹ Hᵀ m`` (``m (…, n)`` → ``(…, 3)``)."""
    H = _check_axes(H)
    return jnp.asarray(m) @ H @ jnp.linalg.inv(H.T @ H)  # HᵀH is symmetric


def navigation_vectors(latitude: Any, gravity: float = GRAVITY_EQUATOR) -> tuple[jax.Array, jax.Array]:
    """``(f_n, ω_n)`` in ENU at rest: specific force ``(0, 0, g)`` (m/s²) and Earth rate
    ``(0, U cos φ, U sin φ)`` (rad/s); ``latitude`` in rad."""
    lat = jnp.asarray(latitude, float)
    f = jnp.stack([0.0 * lat, 0.0 * lat, gravity + 0.0 * lat])
    w = EARTH_RATE * jnp.stack([0.0 * lat, jnp.cos(lat), jnp.sin(lat)])
    return f, w


def analytic_alignment(f_b: Any, w_b: Any) -> jax.Array:
    """Body-to-ENU matrix ``C_bn`` from the specific force ``f_b (3,)`` and the Earth rate ``w_b (3,)``
    measured in the instrument frame (TRIAD: Up ∥ f, East ∥ ω × f)."""
    up = f_b / jnp.linalg.norm(f_b)
    east = jnp.cross(w_b, up)
    east = east / jnp.linalg.norm(east)
    north = jnp.cross(up, east)
    return jnp.stack([east, north, up])  # rows: navigation axes in the body frame, i.e. C_bn


def attitude_errors(C_est: Any, C_true: Any) -> jax.Array:
    """Small rotation ``(φ_E, φ_N, ψ)`` (rad) with ``C_est ≈ (I − [φ×]) C_true``: tilts about East and
    North and the azimuth error ``ψ`` about Up."""
    E = C_est @ C_true.T
    A = 0.5 * (E.T - E)  # = [φ×] to first order
    return jnp.stack([A[2, 1], A[0, 2], A[1, 0]])


def measure(
    H: Any,
    v_n: Any,
    C_bn: Any = None,
    bias: Any = 0.0,
    scale: Any = 0.0,
    axis_tilt: Any = None,
) -> jax.Array:
    """Readings ``m_i = (1 + s_i)(h_i + δh_i)ᵀ C_bnᵀ v_n + b_i`` of the ``n`` sensors: ``bias``, ``scale``
    scalars or ``(n,)``; ``axis_tilt (n, 3)`` the misalignment of each true axis (``δh_i ⊥ h_i``, small)."""
    H = _check_axes(H)
    C_bn = jnp.eye(3) if C_bn is None else jnp.asarray(C_bn)
    v_b = C_bn.T @ jnp.asarray(v_n)
    axes = H if axis_tilt is None else H + jnp.asarray(axis_tilt)
    return (1.0 + jnp.asarray(scale)) * (axes @ v_b) + jnp.asarray(bias)


def align_from_readings(H: Any, m_accel: Any, m_gyro: Any) -> jax.Array:
    """``C_bn`` by analytic alignment of the reconstructed specific force and rate."""
    return analytic_alignment(reconstruct(H, m_accel), reconstruct(H, m_gyro))


def worst_tilt_direction(h: Any, w_b: Any) -> jax.Array:
    """Unit direction ``d ⊥ h`` maximising ``dᵀ w_b`` — the misalignment that most changes the reading."""
    d = w_b - (h @ w_b) * h
    return d / jnp.linalg.norm(d)


def parity_matrix(H: Any) -> jax.Array:
    """``V (n − 3, n)`` with orthonormal rows spanning the left null space of ``H`` (``V H = 0``)."""
    H = _check_axes(H)
    u, _, _ = jnp.linalg.svd(H, full_matrices=True)
    return u[:, 3:].T


def loo_residuals(V: Any, m: Any) -> jax.Array:
    """Leave-one-out residuals ``r_i = m_i − h_iᵀ x̂₍₋ᵢ₎ = v_iᵀ p / ‖v_i‖²`` (``m (…, n)``)."""
    V = jnp.asarray(V)
    p = jnp.asarray(m) @ V.T
    return (p @ V) / jnp.sum(V * V, axis=0)


class FDIResult(NamedTuple):
    """``statistic`` ``‖p‖²/σ²``; ``detected`` (statistic > threshold); ``isolated`` the index of the
    largest normalised residual; ``max_normalised`` that residual ``|r_i|‖v_i‖/σ``; ``bias_estimate``
    ``r_isolated``; ``corrected`` readings (the isolated sensor corrected by its residual when detected)."""

    statistic: jax.Array
    detected: jax.Array
    isolated: jax.Array
    max_normalised: jax.Array
    bias_estimate: jax.Array
    corrected: jax.Array


def fdi(V: Any, m: Any, sigma: Any, threshold: Any) -> FDIResult:
    """Parity-space failure detection, isolation and correction of one reading vector ``m (n,)`` with
    independent noise ``σ`` per reading; ``threshold`` on ``‖p‖²/σ²`` (χ²(n − 3) under no failure)."""
    V, m = jnp.asarray(V), jnp.asarray(m)
    p = V @ m
    stat = jnp.sum(p * p) / sigma**2
    r = loo_residuals(V, m)
    z = jnp.abs(r) * jnp.linalg.norm(V, axis=0) / sigma
    i = jnp.argmax(z)
    detected = stat > threshold
    corrected = m - jnp.where(detected, r[i], 0.0) * jax.nn.one_hot(i, m.shape[0], dtype=m.dtype)
    return FDIResult(stat, detected, i, z[i], r[i], corrected)
