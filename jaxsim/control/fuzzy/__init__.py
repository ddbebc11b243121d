"""Differentiable fuzzy inference and fuzzy PID control in pure JAX.

* :mod:`.membership` — triangular, trapezoidal, Gaussian, generalised bell, sigmoid and
  piecewise-linear membership functions; :class:`Terms` of a linguistic variable;
* :mod:`.norms` — t-norms (min, product) and s-norms (max, probabilistic sum);
* :mod:`.rules` — rule bases as integer arrays (:func:`rule_base`, :func:`grid_rule_base`);
* :mod:`.inference` — Mamdani, Larsen, Sugeno (zero/first order) and Tsukamoto systems,
  :func:`evaluate`;
* :mod:`.defuzzify` — centroid, bisector, mean/smallest/largest of maximum on a grid;
* :mod:`.characteristic` — the fuzzy-PID paper's three-section static characteristic (exact and
  smooth forms) and the linear characteristic;
* :mod:`.static_characteristic` — ``u(e)`` of a single-input system and the least-squares
  three-section fit;
* :mod:`.controller` — fuzzy P/PI/PD/PID as a :class:`~jaxsim.core.system.Controller`;
* :mod:`.templates` — odd-symmetric single-input Sugeno and Mamdani P controllers built from
  breakpoints (tunable by gradient).

Everything is a pytree: ``jax.grad`` reaches every membership-function parameter, and
``jax.vmap`` runs batches of systems or controllers of one structure.
"""

from jaxsim.control.fuzzy.characteristic import Linear, ThreeSection, from_gains, linear, three_section
from jaxsim.control.fuzzy.controller import FuzzyPIDParams, FuzzyPIDState, fuzzy_pid
from jaxsim.control.fuzzy.defuzzify import (
    bisector,
    centroid,
    largest_of_maximum,
    mean_of_maximum,
    smallest_of_maximum,
)
from jaxsim.control.fuzzy.inference import (
    FuzzySystem,
    MamdaniOutput,
    SugenoOutput,
    TsukamotoOutput,
    evaluate,
    evaluate_batch,
    firing_strengths,
    larsen,
    mamdani,
    output_set,
    sugeno,
    term_activations,
    tsukamoto,
)
from jaxsim.control.fuzzy.membership import (
    Terms,
    bell,
    gaussian,
    piecewise_linear,
    sigmoid,
    terms,
    trapezoidal,
    triangular,
)
from jaxsim.control.fuzzy.norms import snorm, snorm_reduce, tnorm, tnorm_reduce
from jaxsim.control.fuzzy.rules import RuleBase, grid_rule_base, rule_base
from jaxsim.control.fuzzy.static_characteristic import ThreeSectionFit, fit_three_section, static_characteristic
from jaxsim.control.fuzzy.templates import odd_input_terms, odd_mamdani, odd_sugeno

__all__ = [
    "Linear",
    "ThreeSection",
    "from_gains",
    "linear",
    "three_section",
    "FuzzyPIDParams",
    "FuzzyPIDState",
    "fuzzy_pid",
    "bisector",
    "centroid",
    "largest_of_maximum",
    "mean_of_maximum",
    "smallest_of_maximum",
    "FuzzySystem",
    "MamdaniOutput",
    "SugenoOutput",
    "TsukamotoOutput",
    "evaluate",
    "evaluate_batch",
    "firing_strengths",
    "larsen",
    "mamdani",
    "output_set",
    "sugeno",
    "term_activations",
    "tsukamoto",
    "Terms",
    "bell",
    "gaussian",
    "piecewise_linear",
    "sigmoid",
    "terms",
    "trapezoidal",
    "triangular",
    "snorm",
    "snorm_reduce",
    "tnorm",
    "tnorm_reduce",
    "RuleBase",
    "grid_rule_base",
    "rule_base",
    "ThreeSectionFit",
    "fit_three_section",
    "static_characteristic",
    "odd_input_terms",
    "odd_mamdani",
    "odd_sugeno",
]
