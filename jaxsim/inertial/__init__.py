"""Inertial-sensor kernels (seed 004): gyro error models, Allan-variance model fits, heading by
gyro-carousel least squares, attitude update algorithms.

* :mod:`jaxsim.inertial.sensor_errors` — generators of the five IEEE-952 gyro error terms and of a
  discrete Wiener sequence;
* :mod:`jaxsim.inertial.allan_fit` — the five-term Allan-variance model and its fits (weighted least
  squares, gradient in log space with a Hessian covariance).

The Allan-variance estimator itself is :mod:`jaxsim.estimation.allan`.
"""

from jaxsim.inertial.allan_fit import AllanFit, avar_dof, avar_model, design_matrix, fit_gradient, fit_wls
from jaxsim.inertial.sensor_errors import GyroNoise, flicker_noise, gyro_noise, noise_terms, wiener_sequence

__all__ = [
    "AllanFit",
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
