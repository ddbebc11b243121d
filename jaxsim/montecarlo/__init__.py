"""Monte Carlo and parameter sweeps: reproducible streaming statistics, sharded, resumable.

* runs: :func:`monte_carlo` / :func:`sweep` evaluate ``fn(key, params) -> metrics`` under
  ``jit(vmap)`` in blocks, sharded over ``jax.devices()`` (host devices, GPUs, several processes
  after ``jax.distributed.initialize``); the result depends only on the key and ``n``;
* parameters: :func:`normal`, :func:`uniform`, :func:`lognormal`, :func:`truncated_normal`,
  :func:`deviation` ("nominal ± Δ") in a parameter *space* (a dict of distributions and values);
* statistics: :class:`Moments` (Chan's mergeable mean/variance), :class:`QuantileSketch`
  (quantiles with a stated relative error bound), :func:`wilson_interval` for event probabilities;
* designs: :func:`grid`, :func:`latin_hypercube`, :func:`sobol`, :func:`points`;
* checkpoints: ``out=DIR, resume=True`` (atomic chunk files with checksums, a sweep fingerprint that
  includes a hash of the per-run computation's jaxpr, so chunks of edited code are never merged).
"""

from jaxsim.montecarlo.designs import Design, grid, latin_hypercube, parse_range, points, single_point, sobol
from jaxsim.montecarlo.distributions import (
    Deviation,
    Distribution,
    LogNormal,
    Normal,
    TruncatedNormal,
    Uniform,
    deviation,
    draw,
    lognormal,
    normal,
    truncated_normal,
    uniform,
)
from jaxsim.montecarlo.engine import SweepResult, as_key, monte_carlo, resolve_devices, sweep
from jaxsim.montecarlo.events import wilson_interval
from jaxsim.montecarlo.kernel import run_one
from jaxsim.montecarlo.moments import Moments, PairwiseMerge, block_moments, merge_moments, moments_of, pairwise_sum
from jaxsim.montecarlo.plots import plot_distribution, plot_sweep
from jaxsim.montecarlo.result import EventStats, MetricStats, MonteCarloResult, RawRuns
from jaxsim.montecarlo.sketch import QuantileSketch, quantile_error_bound, sketch_quantile

__all__ = [
    "Design",
    "grid",
    "latin_hypercube",
    "parse_range",
    "points",
    "single_point",
    "sobol",
    "Deviation",
    "Distribution",
    "LogNormal",
    "Normal",
    "TruncatedNormal",
    "Uniform",
    "deviation",
    "draw",
    "lognormal",
    "normal",
    "truncated_normal",
    "uniform",
    "SweepResult",
    "as_key",
    "monte_carlo",
    "resolve_devices",
    "sweep",
    "wilson_interval",
    "run_one",
    "Moments",
    "PairwiseMerge",
    "block_moments",
    "merge_moments",
    "moments_of",
    "pairwise_sum",
    "EventStats",
    "MetricStats",
    "MonteCarloResult",
    "RawRuns",
    "QuantileSketch",
    "quantile_error_bound",
    "sketch_quantile",
    "plot_distribution",
    "plot_sweep",
]
