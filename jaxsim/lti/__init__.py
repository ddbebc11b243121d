"""LTI systems the python-control way — differentiable.

python-control's vocabulary over the toolkit's kernels; every function is pure ``jnp``, so it
composes with ``jit``, ``vmap`` and ``grad`` (a phase margin can be a tuning constraint):

* construction: :func:`ss`, :func:`tf`, :func:`zpk` → a :class:`~jaxsim.core.system.Plant` with exact
  ``D`` feedthrough (continuous time) or a :class:`StateSpace` (discrete time);
* interconnection: :func:`series`, :func:`parallel`, :func:`feedback`; :func:`c2d`;
* structure: :func:`ctrb`, :func:`obsv`, :func:`pole`, :func:`zero`, :func:`dcgain`;
* state feedback: :func:`place` (Kautsky–Nichols–Van Dooren), :func:`acker`;
* time responses: :func:`step_response`, :func:`impulse_response`, :func:`initial_response`,
  :func:`forced_response` (:func:`lsim`) → :class:`TimeResponse`; :func:`step_info`;
* frequency responses: :func:`evalfr`, :func:`frequency_response`, :func:`bode`;
  :func:`margin` (with the delay margin), :func:`stability_margins`.

``lqr``, ``dlqr``, ``care``, ``dare``, ``lqe``, ``dlqe`` with python-control's return values
(``K, S, E`` …) live in :mod:`jaxsim.lti.compat`, beside the toolkit's NamedTuple API
(:mod:`jaxsim.control.lqr`, :mod:`jaxsim.control.kalman_gain`); ``import jaxsim.lti.compat as ct``
gives the whole python-control-style namespace.
"""

from jaxsim.lti.discretize import c2d, hold_matrices
from jaxsim.lti.frequency import FrequencyResponse, bode, dcgain, evalfr, frequency_response
from jaxsim.lti.interconnect import feedback, parallel, series
from jaxsim.lti.margins import AllMargins, Margin, StabilityMargins, delay_margin, margin, stability_margins
from jaxsim.lti.placement import acker, place
from jaxsim.lti.poles_zeros import pole, zero
from jaxsim.lti.responses import (
    TimeResponse,
    forced_response,
    impulse_response,
    initial_response,
    lsim,
    step_response,
)
from jaxsim.lti.statespace import StateSpace, as_state_space, is_lti, lti_plant, ss
from jaxsim.lti.step_info import StepInfo, step_info
from jaxsim.lti.structure import ctrb, obsv
from jaxsim.lti.transfer import tf, zpk

__all__ = [
    "StateSpace",
    "ss",
    "tf",
    "zpk",
    "as_state_space",
    "is_lti",
    "lti_plant",
    "series",
    "parallel",
    "feedback",
    "c2d",
    "hold_matrices",
    "ctrb",
    "obsv",
    "pole",
    "zero",
    "dcgain",
    "place",
    "acker",
    "TimeResponse",
    "step_response",
    "impulse_response",
    "initial_response",
    "forced_response",
    "lsim",
    "StepInfo",
    "step_info",
    "FrequencyResponse",
    "evalfr",
    "frequency_response",
    "bode",
    "Margin",
    "StabilityMargins",
    "AllMargins",
    "margin",
    "stability_margins",
    "delay_margin",
]
