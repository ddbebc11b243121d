"""Inertial-sensor kernels (seed 004): gyro error models, Allan-variance model fits, heading by
gyro-carousel least squares, attitude update algorithms.

* :mod:`jaxsim.inertial.sensor_errors` — generators of the five IEEE-952 gyro error terms and of a
  discrete Wiener sequence;
* :mod:`jaxsim.inertial.allan_fit` — the five-term Allan-variance model and its fits (weighted least
  squares, gradient in log space with a Hessian covariance);
* :mod:`jaxsim.inertial.carousel` — heading from a continuously rotated gyro by batch least squares,
  and its differentiable error budget (white noise, bias random walk, turntable-rate error);
* :mod:`jaxsim.inertial.attitude` — quaternion attitude updates from gyro increments (first order,
  two- and three-sample coning corrections), classical coning motion and its closed-form drift;
* :mod:`jaxsim.inertial.bench_calibration` — the 24-state IMU bench-calibration model on a single-axis
  table (seed 004 B3): rotation plans, information-matrix observability ranks, covariance runs
  (imported by full path);
* :mod:`jaxsim.inertial.ahrs` — a MEMS AHRS (seed 004 §2.5, Luchkina): the Table 1 sensor-error
  generator (bias, scale, temperature, white and first-order Gauss–Markov noise), a prescribed
  manoeuvre flight, raw accelerometer/magnetometer attitude, a 22-state MEKF and a complementary
  filter (imported by full path).

The Allan-variance estimator itself is :mod:`jaxsim.estimation.allan`.
"""

from jaxsim.inertial.allan_fit import AllanFit, avar_dof, avar_model, design_matrix, fit_gradient, fit_wls
from jaxsim.inertial.attitude import (
    ALGORITHMS,
    coning_attitude,
    coning_drift_rate,
    coning_increments,
    coning_rate,
    drift_rate,
    propagate,
    quat_exp,
    quat_mul,
    quat_rotation_vector,
    rotation_vectors,
)
from jaxsim.inertial.carousel import (
    EARTH_RATE,
    HeadingBudget,
    HeadingEstimate,
    carousel_rate,
    closed_form_heading_std,
    heading_error_budget,
    heading_ls,
    whole_turn_budget,
)
from jaxsim.inertial.sensor_errors import GyroNoise, flicker_noise, gyro_noise, noise_terms, wiener_sequence

__all__ = [
    "ALGORITHMS",
    "EARTH_RATE",
    "coning_attitude",
    "coning_drift_rate",
    "coning_increments",
    "coning_rate",
    "drift_rate",
    "propagate",
    "quat_exp",
    "quat_mul",
    "quat_rotation_vector",
    "rotation_vectors",
    "AllanFit",
    "HeadingBudget",
    "HeadingEstimate",
    "carousel_rate",
    "closed_form_heading_std",
    "heading_error_budget",
    "heading_ls",
    "whole_turn_budget",
    "GyroNoise",
    "avar_dof",
    "avar_model",
    "design_matrix",
    "fit_gradient",
    "fit_wls",
    "flicker_noise",
    "gyro_noise",
    "noise_terms",
    "wiener_sequence",
]
