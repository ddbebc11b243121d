"""Simulation core: integrators, discretisation, closed-loop rollout, signals, metrics."""

from jaxsim.core.discretize import c2d_zoh, van_loan
from jaxsim.core.integrators import (
    EULER,
    HEUN,
    RK4,
    RK4_ROLLED,
    ExplicitRK,
    ExponentialEuler,
    RolledRK4,
    SemiImplicitEuler,
    integrate,
)
from jaxsim.core.linearize import Linearization, find_equilibrium, linearize
from jaxsim.core.pytree import pytree_dataclass, static_field
from jaxsim.core.rollout import ClosedLoop, Tick, Timing, Trajectory, fold, simulate, tick_times
from jaxsim.core.signals import Constant, FilteredStep, Piecewise, Ramp, Sine, Square, Step, Sum
from jaxsim.core.system import (
    Controller,
    Estimator,
    Plant,
    Sensor,
    add_input_disturbance,
    gaussian_sensor,
    subtract_input_disturbance,
)
from jaxsim.core.transfer_function import characteristic_polynomial, ss2tf, tf2ss

__all__ = [
    "EULER",
    "HEUN",
    "RK4",
    "RK4_ROLLED",
    "ExplicitRK",
    "ExponentialEuler",
    "RolledRK4",
    "SemiImplicitEuler",
    "integrate",
    "c2d_zoh",
    "van_loan",
    "Linearization",
    "find_equilibrium",
    "linearize",
    "pytree_dataclass",
    "static_field",
    "ClosedLoop",
    "Tick",
    "Timing",
    "Trajectory",
    "fold",
    "simulate",
    "tick_times",
    "Constant",
    "FilteredStep",
    "Piecewise",
    "Ramp",
    "Sine",
    "Square",
    "Step",
    "Sum",
    "Controller",
    "Estimator",
    "Plant",
    "Sensor",
    "add_input_disturbance",
    "gaussian_sensor",
    "subtract_input_disturbance",
    "characteristic_polynomial",
    "ss2tf",
    "tf2ss",
]
