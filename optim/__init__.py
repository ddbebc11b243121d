"""Tuning layer: reparametrisations, gradient tuner (optax), particle swarm, searches, comparisons.

Importing ``optim`` imports ``jaxsim`` (float64 on).  CasADi/IPOPT helpers live in
:mod:`optim.casadi_pid` (imported on demand).
"""

import jaxsim  # noqa: F401  (precision set up in one place)
from optim.compare import Comparison, Curve, best_within, compare, comparison_metrics, plot_comparison
from optim.problems import PIDTuning, rastrigin, rosenbrock, sphere
from optim.pso import PSOConfig, SwarmState, pso, pso_init, pso_step
from optim.reparam import (
    Identity,
    Interval,
    Positive,
    Reparam,
    Simplex,
    SortedBreakpoints,
    SPDMatrix,
    apply,
    check_domain,
    invert,
)
from optim.results import SearchHistory, SearchResult
from optim.robust import cvar, mean, robust_loss, worst_case
from optim.search import grid_search, random_search
from optim.tune import FORWARD_MODE_MAX_PARAMS, History, TuneResult, tune

__all__ = [
    "Comparison", "Curve", "best_within", "compare", "comparison_metrics", "plot_comparison",
    "PIDTuning", "rastrigin", "rosenbrock", "sphere",
    "PSOConfig", "SwarmState", "pso", "pso_init", "pso_step",
    "Identity", "Interval", "Positive", "Reparam", "Simplex", "SortedBreakpoints", "SPDMatrix",
    "apply", "check_domain", "invert",
    "SearchHistory", "SearchResult", "cvar", "mean", "robust_loss", "worst_case",
    "grid_search", "random_search", "FORWARD_MODE_MAX_PARAMS", "History", "TuneResult", "tune",
]
