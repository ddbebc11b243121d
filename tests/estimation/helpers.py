"""Random models shared by the estimation tests (NumPy, seeded)."""

from __future__ import annotations

import numpy as np

from jaxsim.estimation.lgssm import LinearGaussianSSM, lgssm


def spd(rng: np.random.Generator, n: int, scale: float = 1.0, floor: float = 0.1) -> np.ndarray:
    a = rng.standard_normal((n, n))
    return scale * (a @ a.T / n + floor * np.eye(n))


def stable(rng: np.random.Generator, n: int, radius: float = 0.95) -> np.ndarray:
    f = rng.standard_normal((n, n))
    return radius * f / max(1.0, np.max(np.abs(np.linalg.eigvals(f))))


def random_model(rng: np.random.Generator, n: int = 4, p: int = 2, m: int = 0) -> LinearGaussianSSM:
    return lgssm(
        F=stable(rng, n),
        Q=spd(rng, n, 0.3),
        H=rng.standard_normal((p, n)),
        R=spd(rng, p, 0.5),
        m0=rng.standard_normal(n),
        P0=spd(rng, n),
        B=rng.standard_normal((n, m)) if m else None,
    )


def random_time_varying(rng: np.random.Generator, t: int, n: int = 3, p: int = 2, m: int = 1) -> LinearGaussianSSM:
    return lgssm(
        F=np.stack([stable(rng, n) for _ in range(t)]),
        Q=np.stack([spd(rng, n, 0.3) for _ in range(t)]),
        H=rng.standard_normal((t, p, n)),
        R=np.stack([spd(rng, p, 0.5) for _ in range(t)]),
        m0=rng.standard_normal(n),
        P0=spd(rng, n),
        B=rng.standard_normal((t, n, m)),
    )


def simulate_np(model: LinearGaussianSSM, rng: np.random.Generator, t: int, u=None):
    """Draw a trajectory with NumPy (independent of our JAX sampler)."""
    get = lambda a, k: np.asarray(a)[k] if np.ndim(a) == 3 else np.asarray(a)  # noqa: E731
    n, p = model.n_states, model.n_outputs
    x = rng.multivariate_normal(np.asarray(model.m0), np.asarray(model.P0))
    xs, ys = [], []
    for k in range(t):
        xs.append(x)
        ys.append(get(model.H, k) @ x + rng.multivariate_normal(np.zeros(p), get(model.R, k)))
        x = get(model.F, k) @ x + rng.multivariate_normal(np.zeros(n), get(model.Q, k))
        if u is not None:
            x = x + get(model.B, k) @ u[k]
    return np.array(xs), np.array(ys)


def filterpy_kalman(model: LinearGaussianSSM, y: np.ndarray, u=None, mask=None) -> dict[str, np.ndarray]:
    """FilterPy's ``KalmanFilter`` as an oracle, stepped in our order (update with ``y_t``, then predict
    with ``F_t, Q_t, B_t u_t``), with per-step matrices for time-varying fields.  The update uses only
    the available components of ``mask (T, p)`` and is skipped when none is.  Returns the per-step
    filtered and predicted moments and log-likelihoods (0 on fully masked steps)."""
    import filterpy.kalman

    get = lambda a, k: np.asarray(a, float)[k] if np.ndim(a) == 3 else np.asarray(a, float)  # noqa: E731
    t, p = np.shape(y)
    n = model.n_states
    mask = np.ones((t, p), bool) if mask is None else np.asarray(mask, bool)
    kf = filterpy.kalman.KalmanFilter(dim_x=n, dim_z=p)
    kf.x, kf.P = np.asarray(model.m0, float).reshape(n, 1).copy(), np.asarray(model.P0, float).copy()
    out: dict[str, list] = {k: [] for k in ("means", "covs", "predicted_means", "predicted_covs", "log_likelihoods")}
    for k in range(t):
        out["predicted_means"].append(kf.x.ravel().copy())
        out["predicted_covs"].append(kf.P.copy())
        idx = np.flatnonzero(mask[k])
        ll = 0.0
        if idx.size:
            H, R = get(model.H, k)[idx], get(model.R, k)[np.ix_(idx, idx)]
            kf.update(np.asarray(y[k], float)[idx].reshape(-1, 1), R=R, H=H)
            ll = kf.log_likelihood
        out["means"].append(kf.x.ravel().copy())
        out["covs"].append(kf.P.copy())
        out["log_likelihoods"].append(ll)
        if u is None:
            kf.predict(F=get(model.F, k), Q=get(model.Q, k))
        else:
            kf.predict(
                u=np.asarray(u[k], float).reshape(-1, 1), B=get(model.B, k), F=get(model.F, k), Q=get(model.Q, k)
            )
    return {k: np.array(v) for k, v in out.items()}
