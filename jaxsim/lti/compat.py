"""python-control-style namespace: ``import jaxsim.lti.compat as ct``.

Everything of :mod:`jaxsim.lti` under python-control's names, plus what returns python-control's
plain values instead of the toolkit's richer ones:

* ``lqr``, ``dlqr`` → ``K, S, E``; ``lqe``, ``dlqe`` → ``L, P, E``; ``care``, ``dare`` → ``X, L, G``
  (:mod:`jaxsim.lti.design`; the toolkit's own API is :mod:`jaxsim.control.lqr` and
  :mod:`jaxsim.control.kalman_gain`);
* ``margin`` → exactly ``gm, pm, wcg, wcp`` (:func:`jaxsim.lti.margin` adds the delay margin);
* ``step_info`` → python-control's dictionary (``RiseTime``, ``SettlingTime``, …);
* aliases: ``poles``, ``zeros``, ``sample_system`` (= ``c2d``).
"""

from __future__ import annotations

from typing import Any

from jaxsim.lti import *  # noqa: F401,F403
from jaxsim.lti import __all__ as _lti_all
from jaxsim.lti import c2d, pole, zero
from jaxsim.lti import margin as _margin
from jaxsim.lti import step_info as _step_info
from jaxsim.lti.design import LQEResult, LQRResult, RiccatiResult, care, dare, dlqe, dlqr, lqe, lqr

poles = pole
zeros = zero
sample_system = c2d


def margin(sys: Any) -> tuple:
    """python-control's ``margin(sys)``: ``gm, pm, wcg, wcp`` (see :func:`jaxsim.lti.margin`)."""
    return tuple(_margin(sys)[:4])


def step_info(*args: Any, **kwargs: Any) -> dict:
    """python-control's ``step_info``: a dictionary with its keys (see :func:`jaxsim.lti.step_info`)."""
    return _step_info(*args, **kwargs).as_dict()


__all__ = [n for n in _lti_all if n not in ("margin", "step_info")] + [
    "margin",
    "step_info",
    "poles",
    "zeros",
    "sample_system",
    "lqr",
    "dlqr",
    "care",
    "dare",
    "lqe",
    "dlqe",
    "LQRResult",
    "LQEResult",
    "RiccatiResult",
]
