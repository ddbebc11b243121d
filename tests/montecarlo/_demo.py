"""A small per-run function exercising every kind of metric leaf, shared by the in-process tests and
the subprocess scripts (imported as ``tests.montecarlo._demo`` with the repository root on the path)."""

import jax
import jax.numpy as jnp

import jaxsim.montecarlo as mc

SPACE = {
    "a": mc.normal(1.0, 0.5),
    "b": mc.deviation(1.0, 0.2, relative=True),
    "c": mc.lognormal(0.0, 0.3),
    "d": mc.truncated_normal(0.0, 1.0, -1.0, 2.0),
    "e": mc.deviation(0.5, 0.25),
    "fixed": 3.0,
}


def demo_fn(key, p):
    """Scalars, a vector, an int, an event, non-finite values, tiny values and a small linear solve."""
    x = p["a"] + p["b"] * jax.random.normal(key)
    m = jnp.array([[p["c"], 1.0, 0.0], [0.0, p["fixed"], p["d"]], [p["e"], 0.0, 1.0]])
    y = jnp.linalg.solve(m @ m.T + jnp.eye(3), jnp.array([x, 1.0, -x]))
    return {
        "x": x,
        "vec": jnp.stack([x * x, jnp.sin(x), y[0], y[2]]),
        "count": jnp.floor(jnp.abs(x) * 3).astype(jnp.int32),
        "flag": x > 1.5,
        "bad": jnp.where(x > 2.2, jnp.nan, jnp.where(x < -0.3, jnp.inf, x)),
        "tiny": 1e-12 * x,
    }


def slow_progress(delay):
    """A progress bar that sleeps after every computed chunk (lets a test kill a sweep mid-way)."""
    import time

    class Bar:
        def __init__(self, **_):
            pass

        def update(self, _):
            time.sleep(delay)

        def close(self):
            pass

    return Bar
