"""The hash of a traced computation (the part of a sweep's fingerprint that catches edited code):
sensitive to operations and to every constant's value, blind to names of files and lines, and the
same in every process."""

import os
import subprocess
import sys

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.montecarlo.jaxpr_hash import jaxpr_hash
from jaxsim.montecarlo.kernel import trace_run
from tests.conftest import ROOT
from tests.montecarlo._demo import SPACE, demo_fn


def _hash(fn, *args):
    return jaxpr_hash(jax.make_jaxpr(fn)(*args))


def _from_source(source, filename="metrics.py"):
    namespace = {"jax": jax, "jnp": jnp}
    exec(compile(source, filename, "exec"), namespace)
    return namespace["f"]


X = np.float64(0.3)


def test_an_edited_operation_changes_the_hash_and_an_identical_body_does_not():
    same_a = _from_source("def f(x):\n    return jnp.sin(x) * 2.0 + x\n")
    same_b = _from_source(
        "\n\n# moved down, another file\ndef f(x):\n    return jnp.sin(x) * 2.0 + x\n", filename="/elsewhere/other.py"
    )
    edited = _from_source("def f(x):\n    return jnp.cos(x) * 2.0 + x\n")
    assert _hash(same_a, X) == _hash(same_b, X)  # no file names, lines or object ids in the hash
    assert _hash(same_a, X) != _hash(edited, X)
    assert _hash(same_a, X) != _hash(same_a, np.float32(0.3))  # traced on other dtypes


def test_every_value_of_a_closed_over_array_is_covered():
    table = np.linspace(0.0, 1.0, 5000)  # printed jaxprs elide arrays this large
    nudged = table.copy()
    nudged[2500] = np.nextafter(nudged[2500], 2.0)  # one element in the middle, by one ulp

    def closing_over(arr):
        return lambda x: jnp.sum(arr * x)

    assert _hash(closing_over(table), X) == _hash(closing_over(table.copy()), X)
    assert _hash(closing_over(table), X) != _hash(closing_over(nudged), X)
    assert _hash(closing_over(jnp.asarray(table)), X) != _hash(closing_over(jnp.asarray(nudged)), X)


@pytest.mark.parametrize("a, b", [(0.1, np.nextafter(0.1, 1.0)), (2, 3)])
def test_a_closed_over_config_scalar_is_covered_to_the_last_bit(a, b):
    def scaled(k):
        return lambda x: x * k + 1.0

    assert _hash(scaled(a), X) == _hash(scaled(a), X)
    assert _hash(scaled(a), X) != _hash(scaled(b), X)


def test_sub_jaxprs_of_jit_scan_and_cond_are_covered():
    def loop(c):
        @jax.jit
        def inner(x):
            def body(carry, _):
                return jax.lax.cond(carry > 0, lambda v: v * c, lambda v: v - 1.0, carry), None

            return jax.lax.scan(body, x, None, length=3)[0]

        return inner

    assert _hash(loop(0.5), X) == _hash(loop(0.5), X)
    assert _hash(loop(0.5), X) != _hash(loop(0.25), X)


_SCRIPT = """
import jax, numpy as np
import jaxsim  # float64
import jaxsim.montecarlo as mc
from jaxsim.montecarlo.jaxpr_hash import jaxpr_hash
from jaxsim.montecarlo.kernel import trace_run
from tests.montecarlo._demo import SPACE, demo_fn
space = jax.tree_util.tree_map(np.asarray, SPACE)
print(jaxpr_hash(trace_run(demo_fn, space, {"fixed": np.float64(0.0)}, jax.random.key(3))[0]))
print(mc.sweep(demo_fn, SPACE, mc.grid({"fixed": (1.0, 2.0, 2)}), 20, 3, block_size=10).fingerprint)
"""


def test_the_hash_and_the_sweep_fingerprint_are_the_same_in_separate_processes():
    outputs = []
    for seed in ("1", "2"):  # different str hashing (PYTHONHASHSEED), different object addresses
        env = {**os.environ, "PYTHONHASHSEED": seed, "PYTHONPATH": str(ROOT)}
        proc = subprocess.run(
            [sys.executable, "-c", _SCRIPT], capture_output=True, text=True, cwd=ROOT, env=env, timeout=300
        )
        assert proc.returncode == 0, proc.stderr[-3000:]
        outputs.append(proc.stdout.split())
    assert outputs[0] == outputs[1] and len(outputs[0]) == 2
    space = jax.tree_util.tree_map(np.asarray, SPACE)
    here = jaxpr_hash(trace_run(demo_fn, space, {"fixed": np.float64(0.0)}, jax.random.key(3))[0])
    assert outputs[0][0] == here


def test_a_non_jaxpr_is_refused():
    with pytest.raises(ValueError, match="closed: expected a ClosedJaxpr"):
        jaxpr_hash(lambda x: x)
