"""Benchmark: the map-aided Rao–Blackwellised particle filter (seed 004 part 4 §B4) in JAX against a
NumPy implementation of the same step, in particles × steps per second.

Both run the ``map_aided_pf`` study's default model on its map 3 (3.3, 3.1 mGal/km): L = 10⁴ particles,
30 fixes, ``--runs`` Monte-Carlo runs (truth simulated once with JAX and shared).  Rows: NumPy (a loop
over runs and fixes, each step vectorised over the particles, bilinear look-up by hand, systematic
resampling by ``np.searchsorted``), JAX one run at a time (``jit(run_filter)``), and JAX vmapped over
the runs (``jit(vmap(run_filter))``); each without and with resampling.  Timings: median of
``--repeats`` after a compiling/warm-up call.  Also prints the final per-axis RMS of every row (the
implementations use different random numbers, so these agree only within Monte-Carlo scatter).

Usage: ``python -m experiments.benchmarks.map_aided_pf_numpy [--runs 8] [--particles 10000] [--repeats 3]``.
Not asserted in tests (timings on a shared machine move with the load).
"""

from __future__ import annotations

import argparse

import jax
import jax.numpy as jnp
import numpy as np

import jaxsim  # noqa: F401  (float64)
from experiments.benchmarks.timing import median_time, write_json
from experiments.map_aided_pf import Config, error_model, make_maps, track
from jaxsim.estimation import map_aided_pf as mp


def np_bilinear(values: np.ndarray, origin: np.ndarray, spacing: float, pts: np.ndarray) -> np.ndarray:
    ny, nx = values.shape
    u = (pts - origin) / spacing
    i = np.clip(np.floor(u[:, 0]).astype(int), 0, nx - 2)
    j = np.clip(np.floor(u[:, 1]).astype(int), 0, ny - 2)
    fx, fy = u[:, 0] - i, u[:, 1] - j
    v00, v01 = values[j, i], values[j, i + 1]
    v10, v11 = values[j + 1, i], values[j + 1, i + 1]
    return (1 - fy) * ((1 - fx) * v00 + fx * v01) + fy * ((1 - fx) * v10 + fx * v11)


def np_filter(p: dict, rng: np.random.Generator, z: np.ndarray, x_ns: np.ndarray, n: int, resampling: bool):
    """Final position-error estimate (2,) km of one run (same algorithm as ``mp.run_filter``)."""
    x = np.empty((n, 6))
    x[:, :2] = p["sigma_bar"] * rng.standard_normal((n, 2))
    xv = np.einsum("ij,naj->nai", p["chol_p0"], rng.standard_normal((n, 2, 2)))
    x[:, 2:4], x[:, 4:6] = xv[:, :, 0], xv[:, :, 1]
    c_mean, c_var, w = np.zeros(n), p["sigma_c"] ** 2, np.full(n, 1.0 / n)
    for zi, xi in zip(z, x_ns):
        d = x[:, :2] + x[:, 2:4]
        g = np_bilinear(p["values"], p["origin"], p["spacing"], xi - d)
        s = c_var + p["sigma_v"] ** 2
        r = zi - g - c_mean
        q = -0.5 * r * r / s
        w = w * np.exp(q - q.max())
        w /= w.sum()
        gain = c_var / s
        c_mean = c_mean + gain * r
        c_var = (1 - gain) * c_var
        mean = w @ d
        if resampling:
            cdf = np.cumsum(w)
            cdf[-1] = 1.0
            idx = np.minimum(np.searchsorted(cdf, (rng.random() + np.arange(n)) / n, side="right"), n - 1)
            x, c_mean, w = x[idx], c_mean[idx], np.full(n, 1.0 / n)
        xv = np.stack([x[:, 2:4], x[:, 4:6]], -1)
        xv = np.einsum("ij,naj->nai", p["phi"], xv) + np.einsum(
            "ij,naj->nai", p["chol_q"], rng.standard_normal((n, 2, 2))
        )
        x = np.concatenate([x[:, :2], xv[:, :, 0], xv[:, :, 1]], 1)
    return mean


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=8)
    ap.add_argument("--particles", type=int, default=10_000)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--json", default=None)
    a = ap.parse_args()
    cfg = Config()
    model = error_model(cfg, make_maps(cfg)[2])
    tr = jnp.asarray(track(cfg))
    keys = jax.random.split(jax.random.PRNGKey(0), a.runs)
    sims = [jax.jit(mp.simulate_run)(model, k, tr) for k in keys]
    x_ns = jnp.stack([s[0] for s in sims])
    z = jnp.stack([s[1] for s in sims])
    err = np.stack([np.asarray(s[2][-1]) for s in sims])
    p = {k: np.asarray(getattr(model, k)) for k in ("values", "origin", "phi", "chol_q", "chol_p0")}
    p |= {k: float(getattr(model, k)) for k in ("sigma_bar", "sigma_c", "sigma_v", "spacing")}
    one = jax.jit(mp.run_filter, static_argnums=(4, 5))
    many = jax.jit(jax.vmap(mp.run_filter, (None, 0, 0, 0, None, None)), static_argnums=(4, 5))
    ps = a.runs * a.particles * cfg.n_fixes
    out = {"runs": a.runs, "particles": a.particles, "fixes": cfg.n_fixes}
    rms = lambda m: 1e3 * float(np.sqrt(np.mean((np.asarray(m) - err) ** 2)))  # noqa: E731
    for res in (False, True):
        tag = "resampled" if res else "sis"
        rng = np.random.default_rng(1)

        def run_np():
            return np.stack(
                [np_filter(p, rng, np.asarray(z[r]), np.asarray(x_ns[r]), a.particles, res) for r in range(a.runs)]
            )

        def run_one():
            return np.stack(
                [np.asarray(one(model, keys[r], z[r], x_ns[r], a.particles, res).mean[-1]) for r in range(a.runs)]
            )

        def run_vmap():
            return np.asarray(many(model, keys, z, x_ns, a.particles, res).mean[:, -1])

        for name, fn in (("numpy", run_np), ("jax_loop", run_one), ("jax_vmap", run_vmap)):
            final = fn()  # warm-up / compile
            t = median_time(fn, a.repeats)
            out[f"{tag}_{name}_s"] = t
            out[f"{tag}_{name}_particle_steps_per_s"] = ps / t
            out[f"{tag}_{name}_rms_m"] = rms(final)
            print(
                f"{tag:9s} {name:9s} median {t:8.3f} s  {ps / t:10.3e} particle-steps/s  final RMS {rms(final):6.0f} m"
            )
        for name in ("jax_loop", "jax_vmap"):
            ratio = out[f"{tag}_numpy_s"] / out[f"{tag}_{name}_s"]
            out[f"{tag}_speedup_{name}_over_numpy"] = ratio
            print(f"{tag:9s} speed-up {name} / numpy: {ratio:.2f}×")
    write_json(a.json, out)


if __name__ == "__main__":
    main()
