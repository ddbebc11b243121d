"""A vmapped batch of 10,000 Riccati solves finishes (no hang) under a timeout.

Run in a subprocess so that a hang (the failure mode of jax 0.10.1/0.10.2 on 2-core CPUs, see
tests/test_jax_deadlock_regression.py) fails the test instead of blocking the suite.
"""

import subprocess
import sys
import textwrap

SCRIPT = textwrap.dedent(
    """
    import time
    import jax, numpy as np, scipy.linalg as sl
    import jaxsim
    from jaxsim.control.riccati import solve_continuous_are, solve_discrete_are

    rng = np.random.default_rng(0)
    count, n, m = 10_000, 4, 2
    a = rng.normal(size=(count, n, n))
    b = rng.normal(size=(count, n, m))
    q = np.broadcast_to(np.eye(n), (count, n, n))
    r = np.broadcast_to(np.eye(m), (count, m, m))
    worst = 0.0
    for solve, ref, scale in ((solve_continuous_are, sl.solve_continuous_are, 1.0),
                              (solve_discrete_are, sl.solve_discrete_are, 0.4)):
        start = time.perf_counter()
        x = np.asarray(jax.jit(jax.vmap(solve))(a * scale, b, q, r))
        elapsed = time.perf_counter() - start
        assert np.all(np.isfinite(x)), "some solves failed"
        for i in rng.choice(count, 20, replace=False):
            x_ref = ref(a[i] * scale, b[i], q[i], r[i])
            worst = max(worst, np.linalg.norm(x[i] - x_ref) / np.linalg.norm(x_ref))
        print(solve.__name__, x.shape, f"{elapsed:.2f}s")
    print("worst", worst)
    """
)


def test_vmapped_batch_of_10000_riccati_solves_finishes():
    proc = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, timeout=400)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "(10000, 4, 4)" in proc.stdout
    assert float(proc.stdout.split()[-1]) < 1e-9, proc.stdout
