"""Digital force-rebalance loop (seed 004 B6): quantisers, the smooth surrogate's limit and gradient,
the sampled loop vs its linear closed-loop model (a NumPy recursion), masking of the control period."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.control import force_rebalance as fr
from jaxsim.plants import quartz_accelerometer as qa

DT = 5e-5


def test_quantizers():
    x = jnp.array([-3.0, -0.26, 0.24, 0.26, 0.74, 3.0])
    np.testing.assert_allclose(fr.quantize(x, 0.5, 2.0), [-2.0, -0.5, 0.0, 0.5, 0.5, 2.0])
    xs = jnp.linspace(-1.9, 1.9, 101)
    soft = fr.soft_quantize(xs, 0.5, 2.0, 1e-3)
    hard = fr.quantize(xs, 0.5, 2.0)
    far = np.abs((np.asarray(xs) / 0.5) % 1 - 0.5) > 0.02
    np.testing.assert_allclose(np.asarray(soft)[far], np.asarray(hard)[far], atol=1e-9)
    f = lambda v: fr.soft_quantize(v, 0.5, 2.0, 0.3)  # noqa: E731
    v, eps = 0.37, 1e-6
    assert float(jax.grad(f)(v)) == pytest.approx((float(f(v + eps)) - float(f(v - eps))) / (2 * eps), rel=1e-5)
    conv = fr.Converters(adc_bits=12.0)
    assert float(conv.q_adc) == pytest.approx(5.0 / 4096)


def _linear(p, g, ts, accel, noise):
    A, B, C, D = fr.closed_loop_matrices(p, g, ts)
    z, out = np.zeros(4), []
    for a, n in zip(accel, noise):
        u = np.array([a, n, 0.0])
        out.append((C @ z + D @ u)[0])
        z = A @ z + B @ u
    return np.array(out)


@pytest.mark.parametrize("m", [1, 2])
def test_loop_matches_linear_model(m):
    p, g = qa.Params(), fr.Gains()
    conv = fr.Converters(adc_bits=40.0, dac_bits=40.0)  # quantisers negligible
    n = 120 * m
    accel = np.full(n, 0.5 * qa.G0)
    noise = 1e-3 * np.asarray(jax.random.normal(jax.random.PRNGKey(0), (n,)))
    tr = fr.simulate(p, g, conv, jnp.asarray(accel), jnp.asarray(noise), DT, m, substeps=4)
    ref = _linear(p, g, m * DT, accel[::m], noise[::m])
    got = np.asarray(tr.current)[::m]
    assert np.max(np.abs(got - ref)) < 1e-6 * np.max(np.abs(ref))
    held = np.asarray(tr.current).reshape(-1, m)
    assert np.all(held == held[:, :1])  # ZOH between control ticks


def test_null_and_scale_factor_at_steady_state():
    p, g = qa.Params(), fr.Gains()
    n = 2000  # 100 ms ≈ 20 integral time constants
    tr = fr.simulate(p, g, fr.Converters(), jnp.full(n, 2.0 * qa.G0), jnp.zeros(n), DT)
    assert float(tr.output_g[-1]) == pytest.approx(2.0, abs=2e-3)  # integral action: null restored
    open_loop = float(p.m_l * 2.0 * qa.G0 / p.k)  # deflection without rebalance (beyond the stops)
    assert abs(float(tr.theta[-1])) < 1e-4 * open_loop


def test_bad_shapes():
    with pytest.raises(ValueError, match="accel/noise"):
        fr.simulate(qa.Params(), fr.Gains(), fr.Converters(), jnp.zeros(5), jnp.zeros(4), DT)
