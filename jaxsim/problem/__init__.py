"""The Problem layer: parameter spaces, reparametrisations and :class:`Problem` (a tuning or robustness
question as one object).  Imports only :mod:`jaxsim.core`, plants/control/estimation (through the
builders users pass) and :mod:`jaxsim.montecarlo.distributions`; ``optim``, ``jaxsim.montecarlo`` and
``jaxsim.envs`` accept a :class:`Problem`.  :mod:`~.trms` holds the TRMS tracking problem (the study and
the ``jaxsim_trms`` env share it).
"""

from jaxsim.core.costs import Breakdown, Objective, RunningCost, combine
from jaxsim.problem.problem import Jitted, Problem, Scenario, penalised
from jaxsim.problem.reducers import cvar, mean, worst_case
from jaxsim.problem.space import Param, ParamSpace, Sorted

__all__ = [
    "Breakdown",
    "Jitted",
    "Objective",
    "Param",
    "ParamSpace",
    "Problem",
    "RunningCost",
    "Scenario",
    "Sorted",
    "combine",
    "cvar",
    "mean",
    "penalised",
    "worst_case",
]
