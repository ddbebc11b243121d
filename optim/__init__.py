"""Tuning layer: reparametrisations, gradient tuner (optax), particle swarm, searches, comparisons.

Every tuner takes a :class:`jaxsim.problem.Problem` (or, as before, a plain loss function) and
returns one result type, :class:`TuneResult`.  Importing ``optim`` imports ``jaxsim`` (float64 on).
CasADi/IPOPT helpers live in :mod:`optim.casadi_pid` (imported on demand).
"""

import jaxsim  # noqa: F401  (precision set up in one place)
from jaxsim.problem import Param, ParamSpace, Problem, Scenario, Sorted
from jaxsim.problem.reparam import (
    Identity,
    Interval,
    LogInterval,
    Positive,
    Reparam,
    Simplex,
    SortedBreakpoints,
    SPDMatrix,
    apply,
    check_domain,
    invert,
)
from optim.cmaes import cmaes
from optim.compare import (
    Comparison,
    Curve,
    best_within,
    compare,
    comparison_metrics,
    plot_comparison,
    standard_tuners,
)
from optim.hybrid import hybrid
from optim.lbfgs import lbfgs
from optim.least_squares import levenberg_marquardt
from optim.problems import PIDTuning, rastrigin, rosenbrock, sphere
from optim.pso import PSOConfig, SwarmState, pso, pso_init, pso_step
from optim.results import History, SearchHistory, SearchResult, TuneResult
from optim.robust import cvar, mean, robust_loss, worst_case
from optim.search import grid_search, random_search
from optim.tune import FORWARD_MODE_MAX_PARAMS, StepInfo, Tuner, TunerState, gradient_tuner, tune

__all__ = [
    "Param",
    "ParamSpace",
    "Problem",
    "Scenario",
    "Sorted",
    "Comparison",
    "Curve",
    "best_within",
    "compare",
    "comparison_metrics",
    "plot_comparison",
    "standard_tuners",
    "cmaes",
    "hybrid",
    "lbfgs",
    "levenberg_marquardt",
    "PIDTuning",
    "rastrigin",
    "rosenbrock",
    "sphere",
    "PSOConfig",
    "SwarmState",
    "pso",
    "pso_init",
    "pso_step",
    "Identity",
    "Interval",
    "LogInterval",
    "Positive",
    "Reparam",
    "Simplex",
    "SortedBreakpoints",
    "SPDMatrix",
    "apply",
    "check_domain",
    "invert",
    "History",
    "SearchHistory",
    "SearchResult",
    "TuneResult",
    "cvar",
    "mean",
    "robust_loss",
    "worst_case",
    "grid_search",
    "random_search",
    "FORWARD_MODE_MAX_PARAMS",
    "StepInfo",
    "Tuner",
    "TunerState",
    "gradient_tuner",
    "tune",
]
