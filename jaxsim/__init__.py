"""jaxsim: differentiable simulation, estimation and tuning for control engineering, in pure JAX.

Sub-packages:

* :mod:`jaxsim.core` — integrators, discretisation, the closed-loop rollout, signals, metrics,
  linearisation, transfer functions;
* :mod:`jaxsim.plants` — one module per plant family of the seed papers;
* :mod:`jaxsim.control` — controllers (PID, ...) and their design rules;
* :mod:`jaxsim.estimation` — Kalman filters and smoothers, banks, particle filters, observers,
  Allan variance;
* :mod:`jaxsim.inertial` — inertial-sensor error models, attitude updates, gyro heading and Allan fits;
* :mod:`jaxsim.montecarlo` — Monte Carlo and parameter sweeps: reproducible streaming statistics,
  sharded over devices and hosts, resumable;
* :mod:`jaxsim.problem` — a tuning or robustness question as one object (parameter space,
  closed-loop builder, running-cost objective, uncertainty), shared by tuners, Monte Carlo and envs.

Importing the package enables float64 (see :mod:`jaxsim.precision`) and lets XLA's CPU backend
compile a small time loop as one function (see :mod:`jaxsim.xla_flags`; import jaxsim before the
first JAX computation of a process).
"""

from jaxsim.xla_flags import compile_small_loops_whole as _compile_small_loops_whole

_compile_small_loops_whole()

from jaxsim.precision import enable_x64_from_env as _enable_x64_from_env  # noqa: E402

_enable_x64_from_env()

__version__ = "0.1.0"
