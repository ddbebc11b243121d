"""Importing jaxsim lets XLA's CPU backend compile a small time loop as one function
(:mod:`jaxsim.xla_flags`): the flag string it writes, and its effect on a compiled rollout derivative."""

import os

import jax
import jax.numpy as jnp
import pytest

from jaxsim.xla_flags import SMALL_LOOP_OPTION, compile_small_loops_whole, with_small_loop_threshold


def test_the_threshold_is_added_merged_or_left_as_the_user_gave_it():
    assert with_small_loop_threshold("", 4096) == f"--xla_backend_extra_options={SMALL_LOOP_OPTION}=4096"
    flags = "--xla_force_host_platform_device_count=2 --xla_backend_extra_options=a=1,b=2"
    assert with_small_loop_threshold(flags, 8) == (
        f"--xla_force_host_platform_device_count=2 --xla_backend_extra_options=a=1,b=2,{SMALL_LOOP_OPTION}=8"
    )
    mine = f"--xla_backend_extra_options={SMALL_LOOP_OPTION}=1024"
    assert with_small_loop_threshold(mine, 65536) == mine


@pytest.mark.parametrize("n_bytes", [-1, 65536.0, "65536", True])
def test_a_threshold_that_is_not_a_non_negative_integer_is_refused(n_bytes):
    with pytest.raises(ValueError, match="n_bytes: must be a non-negative integer"):
        with_small_loop_threshold("", n_bytes)


def test_this_process_runs_with_the_threshold():
    assert SMALL_LOOP_OPTION in os.environ["XLA_FLAGS"]


def _rollout(gain):
    """16 damped oscillators under feedback, 300 semi-implicit Euler steps: the shape of a tuning loss."""

    def step(carry, _):
        x, v, cost = carry
        a = -gain[0] * x - gain[1] * v - gain[2] * jnp.sin(x)
        v = v + 0.01 * a
        x = x + 0.01 * v
        return (x, v, cost + 0.01 * jnp.sum(x * x + gain[3] * a * a)), None

    x0 = jnp.linspace(0.5, 1.5, 16)
    return jax.lax.scan(step, (x0, jnp.zeros(16), jnp.zeros(())), None, length=300)[0][2]


def test_a_forward_mode_derivative_of_a_rollout_compiles_as_one_loop_function():
    """The tangent loop's body is over XLA's default 1 kB threshold; with the import's setting the
    whole loop becomes one small call (not one dispatched kernel per fusion per step)."""
    compiled = jax.jit(jax.jacfwd(_rollout)).lower(jnp.array([4.0, 1.0, 0.5, 1e-3])).compile().as_text()
    assert 'xla_cpu_small_call="true"' in compiled


def test_a_late_import_warns_and_leaves_the_flags_alone(monkeypatch):
    jnp.ones(1).block_until_ready()  # the backend has started in this process
    monkeypatch.setenv("XLA_FLAGS", "--xla_cpu_enable_fast_math=false")
    with pytest.warns(UserWarning, match="before the first JAX computation"):
        assert compile_small_loops_whole() is False
    assert os.environ["XLA_FLAGS"] == "--xla_cpu_enable_fast_math=false"
