"""Association (Gaussian scores, greedy assignment), the CA motion model and the CLEAR MOT metrics,
against SciPy, a plain-Python greedy loop, Van Loan's discretisation and the ``motmetrics`` package."""

import jax
import jax.numpy as jnp
import motmetrics
import numpy as np
import pytest
import scipy.linalg
import scipy.stats

from jaxsim.estimation.association import gaussian_scores, greedy_assignment
from jaxsim.estimation.mot_metrics import clear_mot
from jaxsim.estimation.motion_models import ca_axis_process_noise, ca_axis_transition, ca_planar


def spd(rng, n, p):
    a = rng.normal(size=(n, p, p))
    return a @ a.transpose(0, 2, 1) + 0.1 * np.eye(p)


def test_gaussian_scores_against_scipy():
    rng = np.random.default_rng(0)
    zh, S, z, R = rng.normal(size=(4, 2)), spd(rng, 4, 2), rng.normal(size=(3, 2)), spd(rng, 3, 2)
    sc = gaussian_scores(jnp.asarray(zh), jnp.asarray(S), jnp.asarray(z), jnp.asarray(R))
    for i in range(4):
        for j in range(3):
            cov = S[i] + R[j]
            ref = scipy.stats.multivariate_normal(zh[i], cov).logpdf(z[j])
            assert float(sc.log_lik[i, j]) == pytest.approx(ref, rel=1e-12)
            d = z[j] - zh[i]
            assert float(sc.nis[i, j]) == pytest.approx(d @ np.linalg.solve(cov, d), rel=1e-12)
    with pytest.raises(ValueError, match="z, R"):
        gaussian_scores(jnp.asarray(zh), jnp.asarray(S), jnp.asarray(z[:, :1]), jnp.asarray(R))


def python_greedy(score, valid):
    score = np.where(valid, score, -np.inf)
    out = -np.ones(score.shape[0], int)
    while np.isfinite(score).any():
        i, j = np.unravel_index(np.argmax(score), score.shape)
        out[i] = j
        score[i, :] = -np.inf
        score[:, j] = -np.inf
    return out


@pytest.mark.parametrize("shape", [(10, 13), (6, 4)])
def test_greedy_assignment_equals_a_python_loop_and_vmaps(shape):
    rng = np.random.default_rng(1)
    scores = rng.normal(size=(5, *shape))
    valid = rng.random((5, *shape)) < 0.6
    ours = np.asarray(jax.vmap(greedy_assignment)(jnp.asarray(scores), jnp.asarray(valid)))
    for k in range(5):
        np.testing.assert_array_equal(ours[k], python_greedy(scores[k].copy(), valid[k]))
        taken = ours[k][ours[k] >= 0]
        assert len(set(taken)) == len(taken)  # one track per measurement
    with pytest.raises(ValueError, match="valid"):
        greedy_assignment(jnp.zeros(shape), jnp.ones((shape[0], shape[1] + 1), bool))


def test_ca_model_is_the_exact_discretisation_of_white_jerk():
    dt, q = 0.04, 2.5
    A = np.diag([1.0, 1.0], 1)  # d/dt (L, V, a) = (V, a, 0) + (0, 0, 1)·jerk
    B = np.array([[0.0], [0.0], [1.0]])
    van_loan = scipy.linalg.expm(np.block([[-A, q * B @ B.T], [np.zeros((3, 3)), A.T]]) * dt)
    F = van_loan[3:, 3:].T
    np.testing.assert_allclose(ca_axis_transition(dt), F, rtol=1e-13, atol=1e-16)
    np.testing.assert_allclose(ca_axis_process_noise(dt, q), F @ van_loan[:3, 3:], rtol=1e-10, atol=1e-20)
    F2, Q2, H2 = ca_planar(dt, q)
    np.testing.assert_array_equal(F2[3:, 3:], F2[:3, :3])
    assert not F2[:3, 3:].any() and not Q2[:3, 3:].any()
    np.testing.assert_array_equal(H2, [[1, 0, 0, 0, 0, 0], [0, 0, 0, 1, 0, 0]])


def random_frames(seed, n_frames=60):
    """Five objects; four tracker ids that miss, jitter, swap (frames 20–35) and a false hypothesis."""
    rng = np.random.default_rng(seed)
    t = np.arange(n_frames)[:, None]
    pos = np.stack([np.cos(0.05 * t + np.arange(5)), np.sin(0.07 * t + 2 * np.arange(5))], -1) * 3
    frames = []
    for k in range(n_frames):
        oid = np.array([i for i in range(5) if rng.random() > 0.05])
        hyp = {i + 10: pos[k, i] + rng.normal(scale=0.2, size=2) for i in range(4) if rng.random() > 0.1}
        if 20 <= k < 35 and 10 in hyp and 11 in hyp:
            hyp[10], hyp[11] = hyp[11], hyp[10]
        if rng.random() < 0.2:
            hyp[99] = rng.uniform(-3, 3, 2)
        hid = np.array(sorted(hyp))
        frames.append((oid, pos[k, oid], hid, np.array([hyp[h] for h in hid]).reshape(-1, 2)))
    return frames


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_clear_mot_equals_motmetrics(seed):
    frames = random_frames(seed)
    thr = 0.5
    acc = motmetrics.MOTAccumulator(auto_id=True)
    for oid, op, hid, hp in frames:
        acc.update(oid, hid, motmetrics.distances.norm2squared_matrix(op, hp, max_d2=thr**2))
    summary = motmetrics.metrics.create().compute(
        acc, metrics=["num_objects", "num_misses", "num_false_positives", "num_switches", "mota", "motp"]
    )
    ours = clear_mot(*zip(*frames), threshold=thr)
    ref = summary.iloc[0]
    assert ours.num_objects == ref["num_objects"]
    assert (ours.misses, ours.false_positives, ours.switches) == (
        ref["num_misses"],
        ref["num_false_positives"],
        ref["num_switches"],
    )
    assert ours.switches > 0 and ours.false_positives > 0 and ours.misses > 0  # the cases are exercised
    assert ours.mota == pytest.approx(ref["mota"], rel=1e-12)
    assert np.mean(ours.distances**2) == pytest.approx(ref["motp"], rel=1e-10)  # motp of squared distances


def test_clear_mot_rejects_bad_input():
    with pytest.raises(ValueError, match="threshold"):
        clear_mot([np.array([0])], [np.zeros((1, 2))], [np.array([0])], [np.zeros((1, 2))], threshold=0.0)
    with pytest.raises(ValueError, match="one entry per frame"):
        clear_mot([np.array([0])], [], [np.array([0])], [np.zeros((1, 2))], threshold=1.0)
