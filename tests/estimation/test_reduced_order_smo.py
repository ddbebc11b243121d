"""Reduced-order sliding-mode observer: closed forms, exact switching, stiffness, existence, gradients."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg

from jaxsim.core.integrators import RK4
from jaxsim.estimation import reduced_order_smo as smo


def _no_terms(params, t, y, u, z2):
    return jnp.zeros(()), jnp.zeros(1)


def _first_output(params, y):
    return y[0]


def double_integrator(Q=-1.0):
    """ẋ1 = x2, ẋ2 = d, y = x1; canonical z = (x1, x2 + Q x1) (F1 = −Q, F2 = 1, F3 = −Q², F4 = Q)."""
    Q = float(Q)
    return smo.ReducedModel(
        F1=jnp.asarray(-Q),
        F2=jnp.ones(1),
        F3=jnp.array([-Q * Q]),
        F4=jnp.array([[Q]]),
        D1=jnp.asarray(0.0),
        D2=jnp.ones(1),
        params=None,
        known=_no_terms,
        reduced_output=_first_output,
    )


def samples(dt, T=5.0, omega=2.0):
    """Exact double-integrator samples for d = sin(ωt), x(0) = (0, −1/ω)."""
    t = jnp.arange(0.0, T + dt / 2, dt)
    x1 = -jnp.sin(omega * t) / omega**2
    return t, x1[:, None], jnp.zeros((t.shape[0], 1)), jnp.sin(omega * t)


def ideal_sliding_estimate(t, rho, omega=2.0):
    """d̂ = ρ e2 with ė2 = −(1 + ρ) e2 + sin ωt, steady state (closed form)."""
    a = 1.0 + rho
    return rho * (a * np.sin(omega * t) - omega * np.cos(omega * t)) / (a**2 + omega**2)


GAINS = smo.SMOGains(k1=1e3, k2=1.0, k3=1e2)  # ρ = k1/k3 = 10


def test_lyapunov_matrix_matches_scipy():
    rng = np.random.default_rng(0)
    F4 = rng.normal(size=(3, 3)) - 4 * np.eye(3)
    W = np.diag([1.0, 2.0, 3.0])
    P = smo.lyapunov_P(jnp.asarray(F4), jnp.asarray(W))
    np.testing.assert_allclose(P, scipy.linalg.solve_continuous_lyapunov(F4.T, -W), rtol=1e-10, atol=1e-12)
    assert float(smo.lyapunov_P(jnp.array([[-1.0]]), jnp.array([[2.0]]))[0, 0]) == pytest.approx(
        1.0
    )  # paper: P = 1, W = 2


@pytest.mark.parametrize("scheme", ["implicit_sign", "smooth"])
def test_estimate_converges_to_ideal_sliding_closed_form(scheme):
    errs = []
    for dt in (1e-3, 5e-4):
        t, ys, us, d = samples(dt)
        par = smo.reduced_order_smo(double_integrator(), GAINS, scheme=scheme, width=1e-4)
        run = jax.jit(smo.smo_filter)(par, t, ys, us)
        late = np.asarray(t) > 1.0
        errs.append(np.max(np.abs(np.asarray(run.d_hat)[late] - ideal_sliding_estimate(np.asarray(t)[late], 10.0))))
    assert errs[1] < 2.5e-3  # of an amplitude ≈ 0.9
    assert 1.6 < errs[0] / errs[1] < 2.4  # first order in dt


def test_exact_switching_holds_the_surface_exactly():
    t, ys, us, _ = samples(1e-3)
    run = smo.smo_filter(smo.reduced_order_smo(double_integrator(), GAINS), t, ys, us)
    sliding = np.abs(np.asarray(run.v)) < 1.0
    assert sliding[100:].all()
    assert np.max(np.abs(np.asarray(run.e1)[100:])) < 1e-14  # e1 = 0 exactly on the surface


def test_stiff_gains_explicit_rk4_fails_semi_implicit_stays_accurate():
    gains = smo.SMOGains(k1=1e7, k2=1.0, k3=1e4)  # the paper's gains: k3/width = 1e7 s⁻¹
    t, ys, us, _ = samples(1e-4, T=1.0)
    rk4 = smo.reduced_order_smo(double_integrator(), gains, scheme="smooth", solver=RK4)
    bad = np.asarray(smo.smo_filter(rk4, t, ys, us).d_hat)  # |v| ≤ 1 keeps it bounded, but it chatters at ±k1
    assert np.nanmax(np.abs(bad[2000:])) > 1e6 or not np.all(np.isfinite(bad))
    semi = smo.reduced_order_smo(double_integrator(), gains, scheme="smooth")
    exact = smo.reduced_order_smo(double_integrator(), gains)
    a = np.asarray(smo.smo_filter(semi, t, ys, us).d_hat)[2000:]
    b = np.asarray(smo.smo_filter(exact, t, ys, us).d_hat)[2000:]
    ideal = ideal_sliding_estimate(np.asarray(t)[2000:], 1e3)
    assert np.max(np.abs(b - ideal)) < 1.5 * 1e-4 * 2.0  # one-step (dt) lag of a first-order scheme
    assert np.max(np.abs(a - ideal)) < 1.5 * 1e-4 * 2.0 and np.max(np.abs(a - b)) < 1.5e-4


def test_existence_condition_rejects_unreachable_gains_and_predicts_behaviour():
    bounds = smo.SlidingBounds(beta=1.0)  # |d| ≤ 1
    margins = smo.sliding_existence(double_integrator(), GAINS, jnp.eye(1), 2 * jnp.eye(1), bounds)
    assert margins.delta == pytest.approx(2 * 1.0 / (2 + 2 * 10), rel=1e-12)  # β‖PD2‖·2/λ
    weak = smo.SMOGains(k1=0.05, k2=1.0, k3=0.05)
    with pytest.raises(ValueError, match="k3"):
        smo.reduced_order_smo(double_integrator(), weak, bounds=bounds)
    # the condition is not vacuous: these gains indeed lose the sliding mode (|v| pinned at 1)
    t, ys, us, _ = samples(1e-3)
    run = smo.smo_filter(smo.reduced_order_smo(double_integrator(), weak), t, ys, us)
    assert np.mean(np.abs(np.asarray(run.v)) == 1.0) > 0.3
    with pytest.raises(ValueError, match="F4"):
        smo.reduced_order_smo(double_integrator(Q=0.5), GAINS)


def test_bad_inputs():
    with pytest.raises(ValueError, match="k1"):
        smo.reduced_order_smo(double_integrator(), smo.SMOGains(k1=-1.0))
    with pytest.raises(ValueError, match="scheme"):
        smo.reduced_order_smo(double_integrator(), GAINS, scheme="euler")
    with pytest.raises(ValueError, match="switch"):
        smo.reduced_order_smo(double_integrator(), GAINS, switch="cubic")
    t, ys, us, _ = samples(1e-2, T=0.1)
    with pytest.raises(ValueError, match="ys, us"):
        smo.smo_filter(smo.reduced_order_smo(double_integrator(), GAINS), t, ys[:-1], us)


def test_vmap_over_gains_equals_loop_and_grad_matches_finite_differences():
    t, ys, us, d = samples(2e-3, T=2.0)
    model = double_integrator()

    def loss(log_k1):
        par = smo.SMOParams(
            model=model,
            gains=smo.SMOGains(k1=jnp.exp(log_k1), k2=1.0, k3=100.0),
            P=jnp.eye(1),
            width=jnp.asarray(1e-3),
            filter_tau=jnp.asarray(0.0),
            scheme="smooth",
        )
        run = smo.smo_filter(par, t, ys, us)
        return jnp.mean((run.d_hat[200:] - d[200:]) ** 2)

    xs = jnp.log(jnp.array([300.0, 1000.0, 3000.0]))
    batched = jax.jit(jax.vmap(loss))(xs)
    np.testing.assert_allclose(batched, [float(loss(x)) for x in xs], rtol=1e-12)
    g = float(jax.jacfwd(loss)(xs[1]))
    h = 1e-5
    fd = (float(loss(xs[1] + h)) - float(loss(xs[1] - h))) / (2 * h)
    assert g == pytest.approx(fd, rel=1e-4) and g < 0  # larger k1/k3 → smaller bias
