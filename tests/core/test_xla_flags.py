"""jaxsim.core.xla_flags: flags are appended unless already set; the suite's compile flags change no result."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from jaxsim.core.xla_flags import LOW_OPT, add_xla_flags
from tests.conftest import child_env


def test_flags_are_appended_once_and_a_users_value_wins():
    env = {"XLA_FLAGS": "--xla_force_host_platform_device_count=2"}
    value = add_xla_flags(LOW_OPT, env)
    assert value.split() == ["--xla_force_host_platform_device_count=2", *LOW_OPT]
    assert add_xla_flags(LOW_OPT, env) == value  # idempotent
    mine = {"XLA_FLAGS": "--xla_backend_optimization_level=3"}
    assert add_xla_flags(LOW_OPT, mine) == "--xla_backend_optimization_level=3"  # the user's level stays


def test_a_malformed_flag_is_refused_by_name():
    with pytest.raises(ValueError, match="flags: each must read --name=value"):
        add_xla_flags(["xla_cpu_use_fusion_emitters=false"], {})


def test_the_suite_compiles_with_the_fast_flags_unless_told_otherwise():
    if os.environ.get("JAXSIM_TEST_DEFAULT_XLA", "") not in ("", "0"):
        pytest.skip("JAXSIM_TEST_DEFAULT_XLA set: the suite runs with XLA's defaults")
    named = {f.split("=", 1)[0] for f in os.environ["XLA_FLAGS"].split()}
    assert {f.split("=", 1)[0] for f in LOW_OPT} <= named
    assert child_env()["XLA_FLAGS"] == os.environ["XLA_FLAGS"]  # spawned interpreters get them too


_PROGRAM = """
import json, jax, jax.numpy as jnp
jax.config.update("jax_enable_x64", True)
from optim.problems import PIDTuning
from jaxsim.control.riccati import solve_continuous_are
theta = jnp.array([2.0, 1.0, 0.1])
loss, grad = jax.jit(jax.value_and_grad(PIDTuning().loss))(theta)
a = jnp.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [-1.0, -2.0, -0.5]])
x = jax.jit(solve_continuous_are)(a, jnp.eye(3)[:, 2:], jnp.diag(jnp.array([10.0, 1.0, 0.1])), jnp.eye(1))
print(json.dumps({"loss": float(loss), "grad": grad.tolist(), "care": x.tolist()}))
"""


def _run(default_xla: bool) -> dict:
    env = child_env(JAXSIM_TEST_DEFAULT_XLA="1" if default_xla else "0")
    if default_xla:
        env["XLA_FLAGS"] = ""
    proc = subprocess.run([sys.executable, "-c", _PROGRAM], capture_output=True, text=True, env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


def test_fast_compile_flags_give_the_default_builds_numbers():
    """A loss, its gradient through a 600-step rollout and a CARE solution, compiled with XLA's
    defaults and with the suite's flags: equal to 1e-12 relative (measured: ≤ 8e-16)."""
    default, fast = _run(default_xla=True), _run(default_xla=False)
    np.testing.assert_allclose(fast["loss"], default["loss"], rtol=1e-12)
    np.testing.assert_allclose(fast["grad"], default["grad"], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(fast["care"], default["care"], rtol=1e-12)
    assert np.isfinite(default["loss"]) and np.shape(default["care"]) == (3, 3)
