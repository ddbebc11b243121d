"""Regression guard for the jax 0.10.1/0.10.2 deadlock (DESIGN.md, Dependencies).

Those releases hang on 2-core CPUs in vmapped ``lax.scan`` loops of linear solves with batch ≥ 5000
in float64.  The pin in pyproject.toml keeps jax below 0.10; this test runs exactly that workload
in a subprocess under a timeout, so lifting the pin later fails loudly instead of hanging CI.
"""

import subprocess
import sys
import textwrap

SCRIPT = textwrap.dedent(
    """
    import jax, jax.numpy as jnp, numpy as np
    jax.config.update("jax_enable_x64", True)

    def run(a, b):
        def body(x, _):
            x = jnp.linalg.solve(a, x + b)
            return x, x[0]
        return jax.lax.scan(body, jnp.zeros(4), None, length=100)[1]

    rng = np.random.default_rng(0)
    a = rng.normal(size=(5000, 4, 4)) + 4.0 * np.eye(4)
    b = rng.normal(size=(5000, 4))
    out = np.asarray(jax.jit(jax.vmap(run))(a, b))
    x = np.zeros(4)
    for _ in range(100):
        x = np.linalg.solve(a[17], x + b[17])
    print(jax.__version__, out.shape, abs(out[17, -1] - x[0]))
    """
)


def test_vmapped_linear_solve_scan_finishes_under_a_timeout():
    proc = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    err = float(proc.stdout.split()[-1])
    assert err < 1e-10, proc.stdout  # the batched result equals a NumPy loop
