"""The Mamdani centroid's gradient does not depend on how XLA rounds.

XLA recomputes an elementwise operand in every fusion that reads it; built with
``--xla_backend_optimization_level=0`` two copies of a clipped membership rounded differently, so no
entry equalled the max JAX's derivative of ``jnp.max`` divides by (0/0: the Fig. 2 Mamdani fit of
``fuzzy_pid_accuracy`` stopped with a non-finite gradient at ``e = 0.7``).  The defuzzifiers use
:func:`jaxsim.core.robust_extrema.max_along`; this runs the fit's gradient in a child interpreter
built that way and compares it with this process's (XLA's default flags plus the small-loop threshold
of :mod:`jaxsim.xla_flags`, which the child gets too)."""

import json
import subprocess
import sys

import jax.numpy as jnp
import numpy as np

from jaxsim.control import fuzzy as fz
from jaxsim.problem.fuzzy_accuracy import mamdani_fit_problem
from tests.conftest import child_env


def fit_gradient() -> dict:
    """Loss and gradient of the Fig. 2 Mamdani fit at its start (the paper's characteristic)."""
    problem, _ = mamdani_fit_problem(fz.three_section(0.75, 0.3, 1.2, 1.0), jnp.linspace(-2.0, 2.0, 201))
    value, grad = problem.jitted.value_and_grad(problem.space.init)
    return {"value": float(value), **{k: jnp.ravel(v).tolist() for k, v in grad.items()}}


SCRIPT = """
import json, jax
jax.config.update("jax_enable_x64", True)
from tests.control.fuzzy.test_gradient_under_other_rounding import fit_gradient
print(json.dumps(fit_gradient()))
"""


def test_fit_gradient_is_finite_and_equal_under_llvm_level_0():
    env = child_env(XLA_FLAGS="--xla_backend_optimization_level=0")
    proc = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    level0, default = json.loads(proc.stdout.strip().splitlines()[-1]), fit_gradient()
    assert np.isclose(level0["value"], default["value"], rtol=1e-12)
    for name in ("e_bp", "u_bp", "width"):
        assert np.all(np.isfinite(level0[name])), (name, level0[name])
        np.testing.assert_allclose(level0[name], default[name], rtol=1e-9, atol=1e-15, err_msg=name)
