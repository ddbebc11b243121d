"""Isoline seeking (jaxsim.plants.unicycle_field, jaxsim.control.isoline_seeking, jaxsim.problem.isoline):
the exact arc step against SciPy's solve_ivp, the field's isoline, the distance against brute force, and the
closed loop on a straight isoline (F = y, no obstacles): reaches it and slides along it."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from jaxsim.control import isoline_seeking as ctl
from jaxsim.plants import unicycle_field as uf
from jaxsim.problem import isoline as iso


def test_arc_step_against_solve_ivp():
    pose, v, tau = np.array([0.3, -0.2, 0.7]), 1.0, 0.37
    for u in (0.0, 2.5, -10.0):
        ref = solve_ivp(lambda t, x: [v * np.cos(x[2]), v * np.sin(x[2]), u], (0, tau), pose, rtol=1e-12, atol=1e-13).y[
            :, -1
        ]
        assert np.asarray(uf.step(jnp.asarray(pose), u, v, tau)) == pytest.approx(ref, abs=1e-10)


def test_isoline_and_distance():
    phi = np.linspace(-np.pi, np.pi, 13)
    rho = np.asarray(uf.isoline_radius(phi, 1.0, 2.0, 0.5))
    pts = np.stack([rho * np.cos(phi), rho * np.sin(phi)])
    assert np.asarray(jax.vmap(lambda p: uf.field(p), in_axes=1)(pts)) == pytest.approx(1.0, rel=1e-12)
    discs = np.array([[1.0, 0.0, 0.5], [-2.0, 1.0, 0.3]])
    r = np.array([0.2, 0.9])
    brute = min(np.hypot(*(r - c[:2])) - c[2] for c in discs)
    assert float(uf.distance(jnp.asarray(r), jnp.asarray(discs))) == pytest.approx(brute, rel=1e-14)
    assert float(uf.distance(jnp.asarray(r), jnp.zeros((0, 3)))) == np.inf


def test_sliding_mode_reaches_and_tracks_a_straight_isoline():
    # F = y (unit gradient), f0 = 0: the robot must reach y = 0 and then move along it with |y| small
    g = ctl.SeekingGains()
    tau, n = 0.01, 2000

    @jax.jit
    def run(pose0):
        s = ctl.init(pose0[1], jnp.inf)

        def body(c, _):
            pose, s = c
            u, s = ctl.control(g, s, pose[1], jnp.inf, 0.0, tau, 1.0)
            pose = uf.step(pose, u, g.v, tau)
            return (pose, s), (pose, s.tracking, s.mode)

        _, out = jax.lax.scan(body, (pose0, s), None, length=n)
        return out

    poses, tracking, modes = (np.asarray(x) for x in run(jnp.array([0.0, 1.0, 0.3])))
    y = poses[:, 1]
    assert np.all(modes == ctl.MODE_I)
    # on the sliding surface ẏ = −μ·v·atan(y): |y| ≤ its solution from the first time |y| ≤ 0.5, plus the
    # chattering (≈ ū·v·τ² per switch); the isoline is reached (a crossing) within the run
    k = int(np.argmax(np.abs(y) <= 0.5))
    t = np.arange(len(y) - k) * tau
    bound = 0.5 * np.exp(-g.mu * g.v * t / (1 + 0.25))  # atan(y) ≥ y/(1 + y²) ≥ y/1.25 for |y| ≤ 0.5
    assert np.all(np.abs(y[k:]) <= bound + 0.02)
    assert tracking.any()
    tail = poses[-500:]
    assert np.max(np.abs(tail[:, 1])) < 0.05
    assert abs(tail[-1, 0] - tail[0, 0]) > 0.8 * g.v * (len(tail) - 1) * tau  # progresses along it


def test_outcome_flags_a_collision():
    discs = jnp.array([[2.3, 0.0, 0.4]])
    poses = jnp.stack([jnp.linspace(1.0, 3.0, 50), jnp.zeros(50), jnp.zeros(50)], axis=1)
    modes = jnp.zeros(49, int)
    tracking = jnp.ones(49, bool)
    out = jax.jit(iso.outcome)(poses, modes, tracking, discs)
    assert bool(out.collided) and float(out.min_distance) == pytest.approx(-0.4, abs=0.03) and not bool(out.success)
