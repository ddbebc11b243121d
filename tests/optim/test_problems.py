"""Reference problems: the PID loss is the sampled-data loop (independent NumPy stepping agrees)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from experiments.benchmarks.pso_vs_pyswarms import numpy_swarm_loss, python_particle_loss
from optim.problems import PIDTuning


def test_pid_loss_matches_independent_numpy_and_python_stepping():
    problem = PIDTuning(t_final=1.0)
    gains = np.random.default_rng(3).uniform(problem.box[0], problem.box[1], (5, 3))
    ours = np.asarray(jax.jit(jax.vmap(problem.loss))(jnp.asarray(gains)))
    np.testing.assert_allclose(numpy_swarm_loss(problem, gains), ours, rtol=1e-12)
    assert python_particle_loss(problem, gains[0]) == pytest.approx(ours[0], rel=1e-12)


def test_pid_loss_of_zero_gains_is_the_open_loop_integral():
    """kp = ki = kd = 0: u = 0, y = 0, e = 1 at every tick → J = t_final exactly."""
    problem = PIDTuning(t_final=1.0)
    assert float(problem.loss(jnp.zeros(3))) == pytest.approx(1.0, rel=1e-14)
