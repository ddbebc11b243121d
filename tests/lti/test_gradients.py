"""``jit``/``vmap``/``grad`` through :mod:`jaxsim.lti`: gradients against central finite differences
(and closed forms), batched and jitted values against the plain calls."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxsim.lti as lt
from experiments.benchmarks.python_control_agreement import fd_gradient, random_ss

RTOL = 1e-6  # central differences with a relative step 1e-6: truncation and rounding near 1e-8
PLANT_DEN = jnp.array([0.5, 2.0, 2.5, 1.0])  # 1/((0.5 s + 1)(s² + 1.5 s + 1)), stable, third order
T = jnp.linspace(0.0, 10.0, 201)
W = jnp.logspace(-1, 1, 9)


def _pi_loop(theta):
    """``L = (kp s + ki)/s · 1/den``, ``θ = (kp, ki)``."""
    return lt.series(lt.tf(jnp.stack([theta[0], theta[1]]), jnp.array([1.0, 0.0])), lt.tf(jnp.array([1.0]), PLANT_DEN))


@jax.jit
def _margins(theta):
    m = lt.margin(_pi_loop(theta))
    return jnp.stack([m.gm, m.pm, m.wcg, m.wcp, m.dm])


_margins_jacobian = jax.jit(jax.jacrev(_margins))


def test_margin_gradients_against_finite_differences_and_the_scaling_law():
    """Gradients of the gain, phase and delay margins and of both crossover frequencies against
    central differences; and, exactly, the scaling law: ``L(c·θ) = c·L(θ)``, so ``GM(cθ) = GM(θ)/c``
    with the crossovers unchanged: ``∇GM·θ = −GM``, ``∇ω_pc·θ = 0``."""
    theta = jnp.array([0.8, 0.3])
    values = np.asarray(_margins(theta))
    assert np.all(np.isfinite(values)), values  # every margin exists for this loop
    jac = np.asarray(_margins_jacobian(theta))
    for i, name in enumerate(("gm", "pm", "wcg", "wcp", "dm")):
        fd = fd_gradient(lambda th, i=i: _margins(th)[i], theta)
        np.testing.assert_allclose(jac[i], fd, rtol=RTOL, atol=1e-9 * np.max(np.abs(fd)), err_msg=name)
    np.testing.assert_allclose(jac[0] @ np.asarray(theta), -values[0], rtol=1e-10)
    assert abs(jac[2] @ np.asarray(theta)) < 1e-10 * values[2]


@pytest.mark.slow
def test_margins_batch_with_vmap():
    """A margin as a tuning constraint over a batch of gains: ``vmap`` equals one call per gain."""
    thetas = jnp.array([[0.5, 0.3], [0.8, 0.3], [1.2, 0.2]])
    batched = jax.vmap(_margins)(thetas)
    one_by_one = jnp.stack([_margins(th) for th in thetas])
    np.testing.assert_allclose(np.asarray(batched), np.asarray(one_by_one), rtol=1e-13)
    jacs = jax.vmap(_margins_jacobian)(thetas)
    np.testing.assert_allclose(np.asarray(jacs), np.stack([_margins_jacobian(th) for th in thetas]), rtol=1e-12)


def test_dcgain_gradient_against_finite_differences():
    sys = random_ss(np.random.default_rng(0), 3, 2, 2)
    b, c, d = (jnp.asarray(x) for x in (sys.B, sys.C, sys.D))
    f = jax.jit(lambda a: jnp.sum(lt.dcgain(lt.ss(a, b, c, d)) ** 2))
    a0 = jnp.asarray(sys.A)
    np.testing.assert_allclose(np.asarray(jax.grad(f)(a0)), fd_gradient(f, a0), rtol=RTOL, atol=1e-10)


@jax.jit
def _itae(theta):
    """ITAE of the unit-step response of the PI loop closed with unity feedback."""
    y = lt.step_response(lt.feedback(_pi_loop(theta)), T).outputs
    return jnp.sum(T * jnp.abs(1.0 - y)) * (T[1] - T[0])


def test_step_response_itae_gradient_against_finite_differences():
    theta = jnp.array([0.8, 0.3])
    np.testing.assert_allclose(np.asarray(jax.grad(_itae)(theta)), fd_gradient(_itae, theta), rtol=RTOL)


C2D_METHODS = ("zoh", "foh", "tustin", "matched")


@jax.jit
def _sampled_gains(theta):
    """``Σ|G_d(e^{jωTs})|²`` of ``(s + θ₀)/(s² + θ₁ s + 2)`` sampled by each method of :data:`C2D_METHODS`."""
    g = lt.tf(jnp.array([1.0, theta[0]]), jnp.stack([1.0, theta[1], 2.0]))
    z = jnp.exp(1j * W * 0.2)
    return jnp.stack([jnp.sum(jnp.abs(lt.evalfr(lt.c2d(g, 0.2, m), z)) ** 2) for m in C2D_METHODS])


@pytest.mark.slow
def test_c2d_gradients_against_finite_differences():
    theta = jnp.array([0.7, 1.1])
    jac = np.asarray(jax.jit(jax.jacrev(_sampled_gains))(theta))
    for i, method in enumerate(C2D_METHODS):
        fd = fd_gradient(lambda th, i=i: _sampled_gains(th)[i], theta)
        np.testing.assert_allclose(jac[i], fd, rtol=RTOL, err_msg=method)


def test_frequency_and_time_responses_jit_and_vmap():
    sys = random_ss(np.random.default_rng(1), 3, 1, 1)
    a, b, c, d = (jnp.asarray(x) for x in (sys.A, sys.B, sys.C, sys.D))

    def responses(scale):
        g = lt.ss(scale * a, b, c, d)
        return lt.step_response(g, T[:51]).outputs, lt.bode(g, W).magnitude

    scales = jnp.array([0.9, 1.0, 1.1])
    step_b, mag_b = jax.vmap(jax.jit(responses))(scales)
    for i, s in enumerate(scales):
        step, mag = responses(s)
        np.testing.assert_allclose(np.asarray(step_b[i]), np.asarray(step), rtol=1e-12, atol=1e-14)
        np.testing.assert_allclose(np.asarray(mag_b[i]), np.asarray(mag), rtol=1e-12)


def test_design_gradients_against_finite_differences():
    """``lqr`` (through the toolkit's implicit Riccati derivative) and ``place`` (single input)."""
    import jaxsim.lti.compat as jc

    a0 = jnp.array([[0.0, 1.0], [-2.0, -0.5]])
    b = jnp.array([[0.0], [1.0]])

    def f(a):
        k_lqr = jc.lqr(a, b, jnp.eye(2), jnp.eye(1)).K
        k_place = lt.place(a, b, jnp.array([-1.0 + 1.0j, -1.0 - 1.0j]))
        return jnp.sum(k_lqr**2) + jnp.sum(k_place**2)

    fj = jax.jit(f)
    np.testing.assert_allclose(np.asarray(jax.grad(fj)(a0)), fd_gradient(fj, a0), rtol=RTOL, atol=1e-9)
