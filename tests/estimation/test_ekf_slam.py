"""EKF-SLAM in static shapes (:mod:`jaxsim.estimation.ekf_slam`) against a textbook NumPy EKF-SLAM whose
state grows by concatenation in order of discovery, with hand-written Jacobians."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.estimation import ekf_slam as slam

DT = 0.25
Q_U = np.diag([0.05, np.radians(1.0)]) ** 2
R = np.diag([0.1, np.radians(1.0)]) ** 2
# index order differs from the order of discovery (45°, 135°, 225°; the one at 315° stays unseen)
LANDMARKS = np.array([[-9.9, 9.9], [9.9, -9.9], [9.9, 9.9], [-9.9, -9.9]])
MAX_RANGE = 7.0


def wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


def scenario(steps=170, seed=3):
    """Noisy odometry ``(T, 2)``, scans ``(T, 4, 2)`` and ``seen (T, 4)`` of a unicycle on a 10 m circle."""
    rng = np.random.default_rng(seed)
    pose = np.array([10 * np.cos(0.5), 10 * np.sin(0.5), 0.5 + np.pi / 2])
    odo, scans, seen = [], [], []
    for _ in range(steps):
        u = np.array([1.0, 0.1])
        pose = np.array(
            [pose[0] + u[0] * DT * np.cos(pose[2]), pose[1] + u[0] * DT * np.sin(pose[2]), pose[2] + u[1] * DT]
        )
        d = LANDMARKS - pose[:2]
        z = np.stack([np.hypot(d[:, 0], d[:, 1]), wrap(np.arctan2(d[:, 1], d[:, 0]) - pose[2])], 1)
        seen.append(z[:, 0] <= MAX_RANGE)
        scans.append(z + rng.normal(size=z.shape) * np.sqrt(np.diag(R)))
        odo.append(u + rng.normal(size=2) * np.sqrt(np.diag(Q_U)))
    return np.array(odo), np.array(scans), np.array(seen)


def numpy_slam(x0, p0, odo, scans, seen, dt=DT, q_u=Q_U, r_cov=R):
    """Growing-state EKF-SLAM; returns the final mean, covariance and the landmark order of discovery."""
    DT, Q_U, R = dt, q_u, r_cov  # noqa: N806  (the module's names, overridable)
    x, P, order = x0.copy(), p0.copy(), []
    for u, z, s in zip(odo, scans, seen):
        th = x[2]
        Fx = np.array([[1, 0, -u[0] * DT * np.sin(th)], [0, 1, u[0] * DT * np.cos(th)], [0, 0, 1]])
        Gu = np.array([[DT * np.cos(th), 0], [DT * np.sin(th), 0], [0, DT]])
        x[:3] = [x[0] + u[0] * DT * np.cos(th), x[1] + u[0] * DT * np.sin(th), wrap(th + u[1] * DT)]
        F = np.eye(len(x))
        F[:3, :3] = Fx
        G = np.zeros((len(x), 2))
        G[:3] = Gu
        P = F @ P @ F.T + G @ Q_U @ G.T
        for j in range(len(z)):
            if not s[j]:
                continue
            r, b = z[j]
            if j not in order:  # augment
                a = x[2] + b
                lm = x[:2] + r * np.array([np.cos(a), np.sin(a)])
                Gx = np.array([[1, 0, -r * np.sin(a)], [0, 1, r * np.cos(a)]])
                Gz = np.array([[np.cos(a), -r * np.sin(a)], [np.sin(a), r * np.cos(a)]])
                cross = Gx @ P[:3, :]
                Pll = Gx @ P[:3, :3] @ Gx.T + Gz @ R @ Gz.T
                P = np.block([[P, cross.T], [cross, Pll]])
                x = np.concatenate([x, lm])
                order.append(j)
                continue
            i = 3 + 2 * order.index(j)
            d = x[i : i + 2] - x[:2]
            q = d @ d
            zh = np.array([np.sqrt(q), wrap(np.arctan2(d[1], d[0]) - x[2])])
            H = np.zeros((2, len(x)))
            H[:, :3] = [[-d[0] / np.sqrt(q), -d[1] / np.sqrt(q), 0], [d[1] / q, -d[0] / q, -1]]
            H[:, i : i + 2] = [[d[0] / np.sqrt(q), d[1] / np.sqrt(q)], [-d[1] / q, d[0] / q]]
            nu = np.array([r - zh[0], wrap(b - zh[1])])
            S = H @ P @ H.T + R
            K = P @ H.T @ np.linalg.inv(S)
            x = x + K @ nu
            x[2] = wrap(x[2])
            ikh = np.eye(len(x)) - K @ H
            P = ikh @ P @ ikh.T + K @ R @ K.T
    return x, P, order


def jax_slam(x0, p0, odo, scans, seen):
    def step(st, inp):
        u, z, s = inp
        st = slam.slam_predict(st, lambda p, v: slam.unicycle(p, v, DT), u, jnp.asarray(Q_U))
        st, nis = slam.slam_observe(st, slam.RANGE_BEARING, z, s, jnp.asarray(R))
        return st, nis

    st0 = slam.slam_init(x0, p0, len(LANDMARKS))
    return jax.jit(lambda a, b, c: jax.lax.scan(step, st0, (a, b, c)))(odo, scans, seen)


def test_static_shape_slam_equals_growing_state_numpy_slam():
    odo, scans, seen = scenario()
    x0 = np.array([10 * np.cos(0.5), 10 * np.sin(0.5), 0.5 + np.pi / 2])
    p0 = np.diag([1e-4, 1e-4, 1e-6])
    xn, Pn, order = numpy_slam(x0, p0, odo, scans, seen)
    assert order == [2, 0, 3]
    st, nis = jax_slam(x0, p0, jnp.asarray(odo), jnp.asarray(scans), jnp.asarray(seen))
    # slot order of ours ← discovery order of NumPy's
    idx = [0, 1, 2] + [k for j in order for k in (3 + 2 * j, 4 + 2 * j)]
    np.testing.assert_allclose(np.asarray(st.mean)[idx], xn, rtol=1e-9, atol=1e-11)
    np.testing.assert_allclose(np.asarray(st.cov)[np.ix_(idx, idx)], Pn, rtol=1e-8, atol=1e-13)
    assert list(np.flatnonzero(np.asarray(st.active))) == sorted(order)
    # never-seen slots hold nothing
    unseen = [j for j in range(len(LANDMARKS)) if j not in order]
    for j in unseen:
        assert not np.any(np.asarray(st.cov)[3 + 2 * j : 5 + 2 * j])
    # updates happened and their NIS is finite exactly where a mapped landmark was re-observed
    assert np.isfinite(np.asarray(nis)).sum() > 10


def test_augmentation_covariance_and_masked_update():
    st = slam.slam_init(jnp.array([1.0, 2.0, 0.3]), jnp.diag(jnp.array([0.04, 0.09, 0.01])), 3)
    z = jnp.array([5.0, 0.2])
    r = jnp.diag(jnp.array([0.01, 1e-4]))
    aug = slam.slam_augment(st, slam.RANGE_BEARING, jnp.asarray(1), z, r)
    a = 0.5
    np.testing.assert_allclose(aug.mean[5:7], [1 + 5 * np.cos(a), 2 + 5 * np.sin(a)], rtol=1e-14)
    # the placed landmark's covariance: the pose and the measurement errors mapped through the inverse model
    samples = np.random.default_rng(0).multivariate_normal(
        np.r_[1.0, 2.0, 0.3, 5.0, 0.2], np.diag([0.04, 0.09, 0.01, 0.01, 1e-4]), 400000
    )
    ang = samples[:, 2] + samples[:, 4]
    lm = samples[:, :2] + samples[:, 3:4] * np.stack([np.cos(ang), np.sin(ang)], 1)
    np.testing.assert_allclose(aug.cov[5:7, 5:7], np.cov(lm.T), rtol=0.05)
    assert np.all(np.linalg.eigvalsh(np.asarray(aug.cov)) > -1e-12)
    assert list(np.asarray(aug.active)) == [False, True, False]
    same, _ = slam.slam_update(aug, slam.RANGE_BEARING, jnp.asarray(1), jnp.array([4.0, 0.1]), r, use=False)
    np.testing.assert_array_equal(same.mean, aug.mean)
    np.testing.assert_array_equal(same.cov, aug.cov)
    moved, innov = slam.slam_update(aug, slam.RANGE_BEARING, jnp.asarray(1), jnp.array([4.9, 0.21]), r)
    assert float(jnp.trace(moved.cov)) < float(jnp.trace(aug.cov)) and float(innov.nis) > 0


def test_bearing_residual_is_wrapped():
    res = slam.RANGE_BEARING.residual(jnp.array([1.0, np.pi - 0.01]), jnp.array([1.0, -np.pi + 0.01]))
    np.testing.assert_allclose(res, [0.0, -0.02], atol=1e-12)


@pytest.mark.parametrize(
    ("args", "match"),
    [((jnp.zeros(2), jnp.eye(3), 4), "pose_mean"), ((jnp.zeros(3), jnp.eye(3), 0), "n_landmarks")],
)
def test_bad_input_is_named(args, match):
    with pytest.raises(ValueError, match=match):
        slam.slam_init(*args)
