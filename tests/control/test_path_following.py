"""Track generator, natural spline (vs SciPy), Newton projection (vs brute force), look-ahead law and
the dynamic allocation flow (vs the closed-form minimum-norm allocation)."""

import math

import jax.numpy as jnp
import numpy as np
import pytest
from scipy.interpolate import CubicSpline

from jaxsim.control import path_following as pf

SEG = [
    (200.0, 0.0),
    (50.0, 1.5 * math.pi),
    (100.0, 0.0),
    (25.0, 0.5 * math.pi),
    (50.0, 0.0),
    (25.0, 0.5 * math.pi),
    (125.0, 0.0),
]


def test_track_length_heading_and_geometry():
    tr = pf.track(SEG, 2.0)
    assert tr["s"][-1] == pytest.approx(
        200 + 75 * math.pi + 100 + 12.5 * math.pi + 50 + 12.5 * math.pi + 125, rel=1e-13
    )
    assert math.degrees(tr["heading"][-1]) == pytest.approx(450.0, abs=1e-9)
    chords = np.linalg.norm(np.diff(tr["xy"], axis=0), axis=1)
    ds = np.diff(tr["s"])
    # chord = 2R sin(ds/2R) on arcs, = ds on straights
    assert np.all(chords <= ds + 1e-9) and np.all(chords >= 2 * 25 * np.sin(ds / 50) - 1e-9)
    # end of the 270° arc: centre at (200, 50), exit point (150, 50) heading −Y ... heading 270°
    k = np.searchsorted(tr["s"], 200 + 75 * math.pi - 1e-9)
    np.testing.assert_allclose(tr["xy"][k], [150.0, 50.0], atol=1e-9)
    with pytest.raises(ValueError, match="ds"):
        pf.track(SEG, 0.0)


def test_natural_spline_matches_scipy():
    tr = pf.track(SEG, 5.0)
    coef = pf.natural_spline(jnp.asarray(tr["s"]), jnp.asarray(tr["xy"]))
    ref = CubicSpline(tr["s"], tr["xy"], bc_type="natural")
    for s in np.linspace(0, tr["s"][-1], 37):
        p, d1, d2 = pf.spline_eval(jnp.asarray(tr["s"]), coef, s)
        np.testing.assert_allclose(p, ref(s), atol=1e-8)
        np.testing.assert_allclose(d1, ref(s, 1), atol=1e-8)
        np.testing.assert_allclose(d2, ref(s, 2), atol=1e-8)


def test_projection_matches_dense_brute_force():
    tr = pf.track(SEG, 5.0)
    knots = jnp.asarray(tr["s"])
    coef = pf.natural_spline(knots, jnp.asarray(tr["xy"]))
    ref = CubicSpline(tr["s"], tr["xy"], bc_type="natural")
    dense = np.linspace(0, tr["s"][-1], 400001)
    pts = ref(dense)
    rng = np.random.default_rng(0)
    for s_true in rng.uniform(10, tr["s"][-1] - 10, 12):
        c, d1, _ = pf.spline_eval(knots, coef, s_true)
        nrm = np.array([-d1[1], d1[0]]) / np.linalg.norm(d1)
        off = rng.uniform(-1.5, 1.5)
        p = np.asarray(c) + off * nrm
        s = float(pf.project(knots, coef, jnp.asarray(p), s_true + rng.uniform(-3, 3)))
        i = np.argmin(np.linalg.norm(pts - p, axis=1))
        assert s == pytest.approx(dense[i], abs=5e-3)
        assert float(pf.cross_track(knots, coef, jnp.asarray(p), s)) == pytest.approx(off, abs=1e-6)


def test_lookahead_law():
    e = jnp.array([0.0, 1.0, 100.0])
    np.testing.assert_allclose(pf.lookahead(e, 10.0, 4.0, 0.5), [10.0, 6 * math.exp(-0.5) + 4, 4.0], rtol=1e-14)


def test_allocation_flow_converges_to_min_norm():
    B = jnp.array([[9.6, 1.0]])
    W = jnp.diag(jnp.array([1.0, 20.0]))
    tau = jnp.array([0.3])
    z = jnp.zeros(3)
    errs = []
    for _ in range(60):
        z = pf.allocate(z, tau, B, W, 1.0, 1.0, 0.01, 4)
        errs.append(abs(float(tau[0] - B[0] @ z[:2])))
    assert errs[-1] < 1e-7 and errs[5] < errs[0] and errs[20] < 1e-2 * 0.3
    # KKT closed form, computed independently in NumPy
    Wi = np.linalg.inv(np.asarray(W))
    Bn = np.asarray(B)
    u_star = Wi @ Bn.T @ np.linalg.solve(Bn @ Wi @ Bn.T, np.asarray(tau))
    np.testing.assert_allclose(z[:2], u_star, atol=1e-7)
    np.testing.assert_allclose(pf.min_norm_allocation(tau, B, W), u_star, rtol=1e-12)
