"""Map-aided Rao–Blackwellised particle filter (seed 004 part 4 §B4): against a 7-state Kalman filter
on a planar map (the model is then linear-Gaussian) as L grows, vmap over runs equals a loop, the
jaxpr operation counter against hand counts, anisotropic synthetic maps, input checks."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.core.op_count import count_operations
from jaxsim.estimation import map_aided_pf as mp
from jaxsim.plants import geophysical_map as gm

SLOPE = np.array([0.8, -0.5])  # mGal/km, planar map


def planar_model(sigma_v=1.0):
    n, sp = 121, 1.0
    origin = np.array([-60.0, -60.0])
    xs = origin[0] + sp * np.arange(n)
    vals = 10.0 + SLOPE[0] * xs[None, :] + SLOPE[1] * xs[:, None]
    return mp.make_model(
        vals, origin, sp, h=1 / 1200, sigma_x=0.6, dt=300.0, sigma_bar=0.8, sigma_c=2.0, sigma_v=sigma_v
    )


def kalman_oracle(model, z, x_ns):
    """NumPy KF on s = (Δ̄x, Δ̄y, δx, δy, δVx, δVy, c): z − 10 − a·X^NS = −a·(Δ̄ + δx) + c + v."""
    phi, lq, lp0 = (np.asarray(a) for a in (model.phi, model.chol_q, model.chol_p0))
    F, Q, P = np.eye(7), np.zeros((7, 7)), np.zeros((7, 7))
    P[:2, :2] = float(model.sigma_bar) ** 2 * np.eye(2)
    P[6, 6] = float(model.sigma_c) ** 2
    for ax in range(2):
        idx = [2 + ax, 4 + ax]
        F[np.ix_(idx, idx)] = phi
        Q[np.ix_(idx, idx)] = lq @ lq.T
        P[np.ix_(idx, idx)] = lp0 @ lp0.T
    H = np.array([-SLOPE[0], -SLOPE[1], -SLOPE[0], -SLOPE[1], 0, 0, 1.0])
    s, means, sds = np.zeros(7), [], []
    for zi, xi in zip(np.asarray(z), np.asarray(x_ns)):
        y = zi - 10.0 - SLOPE @ xi
        S = H @ P @ H + float(model.sigma_v) ** 2
        K = P @ H / S
        s = s + K * (y - H @ s)
        P = (np.eye(7) - np.outer(K, H)) @ P
        M = np.zeros((2, 7))
        M[:, :2], M[:, 2:4] = np.eye(2), np.eye(2)
        means.append(M @ s)
        sds.append(np.sqrt(np.diag(M @ P @ M.T)))
        s, P = F @ s, F @ P @ F.T + Q
    return np.array(means), np.array(sds)


@pytest.mark.parametrize("resampling", [False, True])
def test_matches_kalman_filter_on_planar_map_as_L_grows(resampling):
    model = planar_model()
    track = jnp.stack([jnp.linspace(-20, 20, 20), jnp.zeros(20)], 1)
    x_ns, z, _ = mp.simulate_run(model, jax.random.PRNGKey(7), track)
    kf_mean, kf_sd = kalman_oracle(model, z, x_ns)
    run = jax.jit(mp.run_filter, static_argnums=(4, 5))
    errs = {}
    for n in (200, 20_000):
        est = run(model, jax.random.PRNGKey(3), z, x_ns, n, resampling)
        errs[n] = np.max(np.abs(np.asarray(est.mean) - kf_mean) / kf_sd)
        if n == 20_000:
            sd = np.sqrt(np.diagonal(np.asarray(est.cov), axis1=1, axis2=2))
            np.testing.assert_allclose(sd, kf_sd, rtol=0.15)
    assert errs[20_000] < 0.1  # PF mean within 0.1 KF σ at every fix
    assert errs[20_000] < errs[200]


def test_vmap_over_runs_equals_loop():
    model = planar_model()
    track = jnp.stack([jnp.linspace(-5, 5, 6), jnp.zeros(6)], 1)
    err, est = jax.jit(mp.monte_carlo, static_argnums=(3, 4, 5))(model, jax.random.PRNGKey(1), track, 3, 50, True)
    sim, filt = jax.jit(mp.simulate_run), jax.jit(mp.run_filter, static_argnums=(4, 5))
    for r, k in enumerate(jax.random.split(jax.random.PRNGKey(1), 3)):
        ks, kf = jax.random.split(k)
        x_ns, z, e = sim(model, ks, track)
        one = filt(model, kf, z, x_ns, 50, True)
        np.testing.assert_allclose(err[r], e, rtol=1e-12, atol=1e-14)
        np.testing.assert_allclose(est.mean[r], one.mean, rtol=1e-10, atol=1e-12)


def test_markov2_discretisation_is_stationary():
    phi, lq, lp0 = mp.markov2_discrete(1 / 1200, 0.6, 300.0)
    p = lp0 @ lp0.T
    np.testing.assert_allclose(phi @ p @ phi.T + lq @ lq.T, p, rtol=1e-9, atol=1e-12)
    import scipy.linalg

    a = np.array([[0.0, 1.0], [-((1 / 1200) ** 2), -2 / 1200]])
    np.testing.assert_allclose(phi, scipy.linalg.expm(a * 300.0), rtol=1e-9)


def test_operation_counter_against_hand_counts():
    x, y, m = jnp.ones(7), jnp.ones(7), jnp.ones((3, 4))
    c = count_operations(lambda a, b: a * b + a / b - jnp.exp(a), x, y)
    assert c == {"mul": 14, "add": 14, "exp": 7}
    c = count_operations(lambda a, v: a @ v, m, jnp.ones(4))  # 3 outputs, 4 products, 3 sums each
    assert c == {"mul": 12, "add": 9}
    c = count_operations(
        lambda k: jax.random.normal(k, (5, 2)) + jnp.sort(jax.random.uniform(k, (3,))).sum(), jax.random.PRNGKey(0)
    )
    assert c["gaussian"] == 10 and c["uniform"] == 3 and c["sort"] == 1 and c["sort_elements"] == 3
    c = count_operations(lambda a: jax.lax.scan(lambda s, _: (s * a, None), a, None, length=5)[0], x)
    assert c == {"mul": 35}


def test_step_tally_is_linear_in_particles_without_resampling():
    model = planar_model()
    t = {}
    for n in (100, 200, 400):
        st = mp.pf_init(model, jax.random.PRNGKey(0), n)
        fn = lambda s, z, x: mp.pf_step(model, jax.random.PRNGKey(1), s, z, x, False)  # noqa: E731
        t[n] = count_operations(fn, st, 0.0, jnp.zeros(2), opaque={"map_lookup": "interpolation"})
    for k in ("mul", "add", "exp", "gaussian", "interpolation"):
        assert t[400][k] - t[200][k] == 2 * (t[200][k] - t[100][k]), k
    assert (t[200]["gaussian"], t[200]["exp"], t[200]["interpolation"]) == (800, 200, 200)


def test_anisotropic_field_mean_gradients():
    f = gm.anisotropic_random_field(jax.random.PRNGKey(2), (160, 160), 0.5, 3.0, (3.3, 3.1))
    gx, gy = (float(g) for g in gm.mean_axis_gradients(f, 0.5))
    gy_np, gx_np = np.gradient(np.asarray(f), 0.5)
    assert gx + gy == pytest.approx(6.4, rel=1e-12)
    assert gx == pytest.approx(np.mean(np.abs(gx_np)), rel=1e-12)
    assert gx == pytest.approx(3.3, rel=0.15) and gy == pytest.approx(3.1, rel=0.15)
    f = gm.anisotropic_random_field(jax.random.PRNGKey(2), (160, 160), 0.5, 3.0, (0.6, 0.2))
    gx, gy = (float(g) for g in gm.mean_axis_gradients(f, 0.5))
    assert 2.0 < gx / gy < 4.5


def test_bad_inputs():
    with pytest.raises(ValueError, match="mean_gradients"):
        gm.anisotropic_random_field(jax.random.PRNGKey(0), (8, 8), 1.0, 2.0, (1.0, 2.0, 3.0))
    with pytest.raises(ValueError, match="values"):
        mp.make_model(np.ones(5), np.zeros(2), 1.0, h=1e-3, sigma_x=1, dt=1, sigma_bar=1, sigma_c=1, sigma_v=1)
    with pytest.raises(ValueError, match="sigma_v"):
        mp.make_model(np.ones((5, 5)), np.zeros(2), 1.0, h=1e-3, sigma_x=1, dt=1, sigma_bar=1, sigma_c=1, sigma_v=0)
    with pytest.raises(ValueError, match="n_particles"):
        mp.pf_init(planar_model(), jax.random.PRNGKey(0), 0)
    with pytest.raises(ValueError, match="track"):
        mp.monte_carlo(planar_model(), jax.random.PRNGKey(0), np.zeros((4, 3)), 2, 10, False)
