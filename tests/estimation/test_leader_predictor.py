"""Leader predictor (seed 002, eqs. 7–16): LS window + multi-rate Kalman, exact on polynomials."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.estimation.leader_predictor import LeaderEstimate, leader_predictor
from jaxsim.plants.marine import rotation_z

H, EVERY = 1e-3, 100  # control tick, ticks per camera frame (0.1 s)


def _follower(t):
    """A follower moving and turning (the predictor must undo its motion exactly)."""
    x = jnp.zeros(12)
    return x.at[0].set(0.5 * t).at[1].set(-0.2 * t**2).at[2].set(1.0).at[5].set(0.3 * jnp.sin(t))


def _run(est, target, n_ticks):
    """Drive the estimator like the rollout does (update on frames, read, predict every tick)."""

    def measure(t, k):
        f = _follower(t)
        z_fr = rotation_z(f[5]).T @ (target(t)[0] - f[:3])
        return jnp.concatenate([f, z_fr, jnp.array([(k % EVERY == 0) * 1.0])])

    def tick(s, k):
        t = k * H
        s = est.update(est.params, s, measure(t, k))
        read = est.read(est.params, s)
        s = est.predict(est.params, s, jnp.zeros(6), H)
        return s, read

    s0 = est.init(est.params, measure(0.0, 0))
    _, reads = jax.lax.scan(tick, s0, jnp.arange(n_ticks))
    return reads


def _poly(coeffs):
    """Target position, velocity, acceleration for per-axis polynomial coefficients (low → high)."""
    c = jnp.asarray(coeffs)

    def f(t):
        pw = jnp.stack([t**i for i in range(c.shape[1])])
        d1 = jnp.stack([i * t ** max(i - 1, 0) for i in range(c.shape[1])])
        d2 = jnp.stack([i * (i - 1) * t ** max(i - 2, 0) for i in range(c.shape[1])])
        return jnp.stack([c @ pw, c @ d1, c @ d2])

    return f


def test_fit_exact_on_quartic_at_frames():
    """A degree-4 trajectory is fitted exactly (position, velocity, acceleration) once the window
    holds 51 frames, although the follower moves and turns."""
    target = _poly([[3.0, 1.2, 0.01, -2e-3, 4e-5], [0.0, 0.3, -0.05, 1e-3, -2e-5], [1.2, 0.0, 0.02, 0.0, 1e-5]])
    est = leader_predictor(51, 4, 0.1, mode="hold")
    n = 60 * EVERY
    reads = _run(est, target, n)
    ts = np.arange(n) * H
    got = np.asarray(reads.target)
    truth = np.asarray(jax.vmap(target)(jnp.asarray(ts)))
    frames = np.arange(5100, n, EVERY)  # window full from frame 50 (t = 5.0 s) on
    np.testing.assert_allclose(got[frames], truth[frames], atol=1e-7)
    # zero-filled start: wrong before the window fills (the paper's start-up transient)
    # (window initialised with the follower's own position): the velocity is metres per second off
    assert np.abs(got[2000, 1] - truth[2000, 1]).max() > 1.0


def test_read_is_a_named_leader_estimate():
    """The controller reads named fields: the follower's own (INS) state as measured this tick and
    the target point's position, velocity, acceleration, ``target`` stacking them row-wise."""
    target = _poly([[3.0, 1.2], [0.0, 0.3], [1.2, 0.0]])
    reads = _run(leader_predictor(51, 4, 0.1, mode="polynomial"), target, 250)
    assert isinstance(reads, LeaderEstimate)
    assert reads.follower.shape == (250, 12) and reads.position.shape == (250, 3)
    ts = jnp.arange(250) * H
    np.testing.assert_allclose(np.asarray(reads.follower), np.asarray(jax.vmap(_follower)(ts)), rtol=1e-14, atol=1e-15)
    np.testing.assert_array_equal(np.asarray(reads.target[:, 1]), np.asarray(reads.velocity))


def test_kalman_predicts_exactly_between_frames_on_constant_acceleration():
    """Quadratic trajectory: the filter's 1 ms prediction driven by the fitted acceleration is exact
    at every tick between frames (R ≈ 0 makes the correction adopt the exact fit)."""
    target = _poly([[3.0, 1.2, 0.04], [0.0, -0.3, 0.1], [1.2, 0.1, -0.02]])
    n = 60 * EVERY
    ts = jnp.arange(n) * H
    truth = np.asarray(jax.vmap(target)(ts))
    kal = np.asarray(_run(leader_predictor(51, 4, 0.1, meas_std=1e-7, mode="kalman"), target, n).target)
    hold = np.asarray(_run(leader_predictor(51, 4, 0.1, mode="hold"), target, n).position)
    after = slice(5100, n)
    np.testing.assert_allclose(kal[after, :2], truth[after, :2], atol=1e-6)
    # without prediction the held position lags by up to v·0.1 s
    assert np.abs(hold[after] - truth[after, 0]).max() > 0.1


def test_bad_input():
    with pytest.raises(ValueError, match="mode"):
        leader_predictor(mode="magic")
    with pytest.raises(ValueError, match="degree"):
        leader_predictor(degree=1)
    with pytest.raises(ValueError, match="meas_std"):
        leader_predictor(meas_std=0.0)
    with pytest.raises(ValueError, match="p0: expected shape"):
        leader_predictor(p0=(1.0, 1.0, 1.0))
    with pytest.raises(ValueError, match="camera_period"):
        leader_predictor(camera_period=0.0)
    with pytest.raises(ValueError, match="t_start"):
        leader_predictor(t_start=float("nan"))
