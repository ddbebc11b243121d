"""Every function of :mod:`jaxsim.lti` against python-control on seeded random systems (SISO and MIMO
where python-control supports it), values within 1e-9 relative.

Sizes are few and fixed (``n = 3``; SISO and 2 × 2) so that the jit caches are shared between tests;
the wider random sweep is ``experiments/benchmarks/python_control_agreement.py``.
"""

import warnings

import control as ct
import numpy as np
import pytest

import jaxsim.lti as lt
import jaxsim.lti.compat as jc
from experiments.benchmarks.python_control_agreement import (
    random_ss,
    random_tf,
    rel_diff,
    sorted_roots,
    to_ours,
)

TOL = 1e-9
N = 3


def _systems(seed: int):
    """A SISO and a 2 × 2 stable system with feedthrough, both of order ``N``."""
    rng = np.random.default_rng(seed)
    siso = random_ss(rng, N, 1, 1)
    mimo = random_ss(rng, N, 2, 2)
    d = rng.normal(size=(2, 2))
    return ct.ss(siso.A, siso.B, siso.C, rng.normal()), ct.ss(mimo.A, mimo.B, mimo.C, d)


@pytest.mark.parametrize("method", ["zoh", "foh", "tustin", "matched"])
def test_c2d(method):
    siso, mimo = _systems(10)
    ts = 0.3
    z = np.exp(1j * np.linspace(0.01, 0.99 * np.pi, 17))
    cases = [siso] if method == "matched" else [siso, mimo]
    for sys in cases:
        ours = lt.c2d(to_ours(sys), ts, method)
        ref = ct.c2d(ct.tf(sys) if method == "matched" else sys, ts, method)
        assert isinstance(ours, lt.StateSpace) and ours.dt == ts
        assert rel_diff(lt.evalfr(ours, z), np.moveaxis(ref(z, squeeze=False), -1, 0)) < TOL
        assert rel_diff(sorted_roots(lt.pole(ours)), sorted_roots(ct.poles(ref))) < TOL


def test_tustin_prewarp():
    siso, _ = _systems(11)
    ours = lt.c2d(to_ours(siso), 0.2, "tustin", prewarp_frequency=3.0)
    ref = ct.c2d(siso, 0.2, "tustin", prewarp_frequency=3.0)
    z = np.exp(1j * np.linspace(0.01, 0.99 * np.pi, 17))
    assert rel_diff(lt.evalfr(ours, z)[:, 0, 0], ref(z)) < TOL


@pytest.mark.parametrize("seed", [0, 1])
def test_structure(seed):
    for sys in _systems(seed):
        ours = to_ours(sys)
        assert rel_diff(lt.ctrb(sys.A, sys.B), ct.ctrb(sys.A, sys.B)) < TOL
        assert rel_diff(lt.obsv(sys.A, sys.C), ct.obsv(sys.A, sys.C)) < TOL
        assert rel_diff(sorted_roots(lt.pole(ours)), sorted_roots(ct.poles(sys))) < TOL
        ref_zeros = ct.zeros(sys)
        ref_zeros = ref_zeros[np.abs(ref_zeros) < 1e8]  # QZ reports some infinite zeros as huge ones
        assert rel_diff(sorted_roots(lt.zero(ours)), sorted_roots(ref_zeros)) < TOL
        assert rel_diff(lt.dcgain(ours), ct.dcgain(sys)) < TOL


def test_zero_of_a_siso_tf_is_its_numerators_roots():
    num, den = [2.0, 3.0, -5.0], [1.0, 4.0, 6.0, 4.0]
    assert rel_diff(sorted_roots(lt.zero(lt.tf(num, den))), sorted_roots(np.roots(num))) < TOL


def test_place_and_acker():
    rng = np.random.default_rng(3)
    a, b = rng.normal(size=(N, N)), rng.normal(size=(N, 2))
    poles = np.array([-1.0 + 2.0j, -1.0 - 2.0j, -3.0])
    assert rel_diff(lt.place(a, b[:, :1], poles), ct.place(a, b[:, :1], poles)) < TOL
    assert rel_diff(lt.acker(a, b[:, :1], poles), ct.acker(a, b[:, :1], poles)) < TOL
    # several inputs: the gain depends on the method (SciPy: Yang–Tits), the poles do not
    k = np.asarray(lt.place(a, b, poles))
    assert rel_diff(sorted_roots(np.linalg.eigvals(a - b @ k)), sorted_roots(poles)) < TOL


@pytest.mark.parametrize(
    "m, poles",
    [
        (2, [-1.0, -1.0, -2.0, -2.0]),  # each pole repeated rank(B) times
        (4, [-1.0 + 1.0j, -1.0 - 1.0j, -2.0, -3.0]),  # B square
        (4, [-1.0, -1.0, -1.0, -1.0]),
    ],
)
def test_place_repeated_poles_and_square_b(m, poles):
    """Both gave NaN gains before: the starting eigenvectors of a repeated pole (or, with ``B``
    square, of every pole) coincided."""
    rng = np.random.default_rng(4)
    a, b = rng.normal(size=(4, 4)), rng.normal(size=(4, m))
    k = np.asarray(lt.place(a, b, poles))
    assert np.all(np.isfinite(k))
    closed = np.linalg.eigvals(a - b @ k)
    assert rel_diff(sorted_roots(closed), sorted_roots(poles)) < 1e-7  # repeated: eigenvalues are ill-conditioned
    if m == 4:  # the normal closed loop: orthonormal eigenvectors, the best conditioned KNV can reach
        m_cl = a - b @ k
        np.testing.assert_allclose(m_cl @ m_cl.T, m_cl.T @ m_cl, atol=1e-10)


def test_design_functions():
    rng = np.random.default_rng(5)
    a, b, c = rng.normal(size=(N, N)), rng.normal(size=(N, 2)), rng.normal(size=(2, N))
    ad = a / (1.2 * max(1.0, np.max(np.abs(np.linalg.eigvals(a)))))
    q, r = np.diag(rng.uniform(0.5, 2.0, N)), np.diag(rng.uniform(0.5, 2.0, 2))
    nn = 0.1 * rng.normal(size=(N, 2))
    e = np.eye(N) + 0.1 * rng.normal(size=(N, N))

    def agree(ours, ref, eig=2):
        """python-control's three return values; the eigenvalues (entry ``eig``) in any order."""
        for i in range(3):
            got, want = (sorted_roots(ours[i]), sorted_roots(ref[i])) if i == eig else (ours[i], ref[i])
            assert rel_diff(got, want) < TOL

    agree(jc.lqr(a, b, q, r), ct.lqr(a, b, q, r))
    agree(jc.lqr(a, b, q, r, nn), ct.lqr(a, b, q, r, nn))
    agree(jc.lqr(to_ours(ct.ss(a, b, c, 0)), q, r), ct.lqr(ct.ss(a, b, c, 0), q, r))
    agree(jc.dlqr(ad, b, q, r), ct.dlqr(ad, b, q, r))
    agree(jc.dlqr(ad, b, q, r, nn), ct.dlqr(ad, b, q, r, nn))
    agree(jc.care(a, b, q, r, nn, e), ct.care(a, b, q, r, nn, e, method="scipy"), eig=1)
    agree(jc.dare(ad, b, q, r, nn, e), ct.dare(ad, b, q, r, nn, e, method="scipy"), eig=1)
    agree(jc.lqe(a, np.eye(N), c, q, r), ct.lqe(a, np.eye(N), c, q, r))
    agree(jc.dlqe(ad, np.eye(N), c, q, r), ct.dlqe(ad, np.eye(N), c, q, r))
    k, s, eigs = jc.lqr(a, b, q, r)  # python-control's unpacking
    assert k.shape == (2, N) and s.shape == (N, N) and eigs.shape == (N,)


T = np.linspace(0.0, 6.0, 61)


def _both(ours, ref):
    return max(rel_diff(ours.outputs, ref.outputs), rel_diff(ours.states, ref.states))


@pytest.mark.parametrize("seed", [0, 1])
def test_continuous_time_responses(seed):
    rng = np.random.default_rng(100 + seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # python-control: the D δ(t) impulse term is left out
        for sys in _systems(seed):
            ours = to_ours(sys)
            m = sys.ninputs
            x0 = rng.normal(size=N)
            u = rng.normal(size=(m, T.size))
            u = u[0] if m == 1 else u
            assert _both(lt.step_response(ours, T), ct.step_response(sys, T)) < TOL
            assert _both(lt.step_response(ours, T, X0=x0), ct.step_response(sys, T, X0=x0)) < TOL
            assert _both(lt.impulse_response(ours, T), ct.impulse_response(sys, T)) < TOL
            assert _both(lt.initial_response(ours, T, x0), ct.initial_response(sys, T, x0)) < TOL
            assert _both(lt.forced_response(ours, T, u, x0), ct.forced_response(sys, T, u, x0)) < TOL
            assert (
                _both(lt.step_response(ours, T, input=m - 1, output=0), ct.step_response(sys, T, input=m - 1, output=0))
                < TOL
            )


def test_discrete_time_responses():
    rng = np.random.default_rng(7)
    td = np.arange(40) * 0.1
    for p in (1, 2):
        sys = random_ss(rng, N, p, p, dt=0.1)
        ours = to_ours(sys)
        u = rng.normal(size=(p, td.size))
        u = u[0] if p == 1 else u
        assert _both(lt.step_response(ours, td), ct.step_response(sys, td)) < TOL
        assert _both(lt.impulse_response(ours, td), ct.impulse_response(sys, td)) < TOL
        assert _both(lt.forced_response(ours, td, u), ct.forced_response(sys, td, u)) < TOL


def test_response_shapes_follow_python_control():
    siso, mimo = _systems(0)
    for sys in (siso, mimo):
        ours, ref = lt.step_response(to_ours(sys), T), ct.step_response(sys, T)
        assert np.shape(ours.outputs) == np.shape(ref.outputs)
        assert np.shape(ours.states) == np.shape(ref.states)
        t, y, x = lt.forced_response(to_ours(sys), T, 0.0)
        ref = ct.forced_response(sys, T, 0.0)
        assert np.shape(y) == np.shape(ref.outputs) and np.shape(x) == np.shape(ref.states)


def test_step_info():
    siso, _ = _systems(2)
    resp = lt.step_response(to_ours(siso), np.linspace(0.0, 15.0, 751))
    yf = float(ct.dcgain(siso))
    ref = ct.step_info(np.asarray(resp.outputs), np.asarray(resp.time), yfinal=yf)
    mine = jc.step_info(resp, yfinal=yf)
    assert set(mine) == set(ref)
    for key in ref:
        assert rel_diff(mine[key], ref[key]) < TOL, key


@pytest.mark.parametrize("seed", [0, 1])
def test_frequency_response_and_bode(seed):
    w = np.logspace(-2, 2, 31)
    siso, mimo = _systems(seed)
    for sys in (siso, mimo):
        ours, ref = lt.frequency_response(to_ours(sys), w), ct.frequency_response(sys, w)
        assert rel_diff(ours.magnitude, ref.magnitude) < TOL
        assert rel_diff(ours.phase, ref.phase) < TOL
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FutureWarning)
        mag, phase, _ = ct.bode(siso, w, plot=False)
    ours = lt.bode(to_ours(siso), w)
    assert rel_diff(ours.magnitude, mag) < TOL and rel_diff(ours.phase, phase) < TOL


def _margins_reference(loop):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # python-control's FRD fallback would not be its exact definition
        sm = ct.stability_margins(loop)
        allm = ct.stability_margins(loop, returnall=True)
    dm = np.min(np.radians(np.mod(allm[1], 360.0)) / allm[4]) if len(allm[4]) else np.inf
    return sm, dm


def _loop(seed: int) -> ct.TransferFunction:
    """A fourth-order loop ``k·C·P``: a PI (even seeds) or lead controller ``C`` and a stable third-order
    plant ``P`` with random (seeded) coefficients (one size: one compilation of each margin function).  A transfer
    function: python-control's
    polynomial method on it is exact, while its ``ss → tf`` conversion leaves rounding-level leading
    coefficients that it reports as phase crossovers near 10⁸ rad/s."""
    rng = np.random.default_rng(seed)
    wn, zeta = rng.uniform(0.5, 3.0), rng.uniform(0.2, 1.0)
    plant = ct.tf([wn**2], [1.0, 2 * zeta * wn, wn**2]) * ct.tf([1.0], [rng.uniform(0.2, 2.0), 1.0])
    z = rng.uniform(0.1, 2.0)
    ctrl = ct.tf([1.0, z], [1.0, 0.0]) if seed % 2 == 0 else ct.tf([1.0, z], [1.0, z * rng.uniform(3.0, 20.0)])
    return 10 ** rng.uniform(-0.5, 1.0) * ctrl * plant


@pytest.mark.parametrize("seed", [0, 1, 2, 3, 4])
def test_margins(seed):
    """Gain margin, phase margin, the crossover frequencies, the stability margin and the delay
    margin at python-control's definitions, on random third-order loops (PI and lead)."""
    loop = _loop(seed)
    (gm, pm, sm, wpc, wgc, wms), dm = _margins_reference(loop)
    mine = lt.tf(loop.num[0][0], loop.den[0][0])
    ours = lt.stability_margins(mine)
    for got, want in zip(ours, (gm, pm, sm, wpc, wgc, wms)):
        assert rel_diff(got, want) < TOL
    assert np.isfinite(gm) or np.isfinite(pm)
    m = lt.margin(mine)
    assert rel_diff(jc.margin(mine), ct.margin(loop)) < TOL
    assert rel_diff(m.dm, dm) < TOL


def test_margins_of_a_known_loop():
    """``L = 2/(s + 1)⁴``: phase crossover at 1 rad/s (``4·atan ω = 180°``) with ``GM = 4/2 = 2``; the
    gain crossover where ``(ω² + 1)² = 2``."""
    den = [1.0, 4.0, 6.0, 4.0, 1.0]
    wgc = np.sqrt(np.sqrt(2.0) - 1.0)
    pm = 180.0 - 4 * np.degrees(np.arctan(wgc))
    gm, pm_ours, wcg, wcp, dm = lt.margin(lt.tf([2.0], den))
    np.testing.assert_allclose([gm, wcg, pm_ours, wcp, dm], [2.0, 1.0, pm, wgc, np.radians(pm) / wgc], rtol=1e-12)
    assert rel_diff(jc.margin(lt.tf([2.0], den)), ct.margin(ct.tf([2.0], den))) < TOL


def test_discrete_margins():
    """A sampled loop whose margins python-control computes with its polynomial method (no FRD
    fallback): gain and phase margins, crossovers and the stability margin (python-control finds the
    frequency of the latter with ``scipy.optimize.minimize``, to about 1e-5: not compared)."""
    loop = ct.c2d(
        ct.ss(ct.tf([40.0], [1.0, 1.0]) * ct.tf([1.0, 0.5], [1.0, 5.0]) * ct.tf([1.0], [1.0, 2.0])), 0.1, "zoh"
    )
    (gm, pm, sm, wpc, wgc, _), dm = _margins_reference(loop)
    ours = lt.stability_margins(to_ours(loop))
    for got, want in zip((ours.gm, ours.pm, ours.sm, ours.wpc, ours.wgc), (gm, pm, sm, wpc, wgc)):
        assert rel_diff(got, want) < TOL
    assert rel_diff(lt.margin(to_ours(loop)).dm, dm) < TOL


def test_interconnection_of_tf_with_random_coefficients():
    rng = np.random.default_rng(8)
    (n1, d1), (n2, d2) = random_tf(rng, 2), random_tf(rng, 2)
    w = np.logspace(-2, 2, 17)
    g1, g2 = ct.tf(n1, d1), ct.tf(n2, d2)
    ours = lt.feedback(lt.tf(n1, d1), lt.tf(n2, d2))
    assert rel_diff(lt.evalfr(ours, 1j * w)[:, 0, 0], ct.feedback(g1, g2)(1j * w)) < TOL


def test_a_nonlinear_plant_is_integrated_by_the_toolkits_solver():
    """The same linear system written as a generic :class:`Plant` (so not recognised as LTI) goes
    through RK4 with ``substeps`` steps per sample: fourth order, it agrees with python-control's
    exact response to ``O(h⁴)``."""
    from jaxsim.core.system import Plant

    siso, _ = _systems(3)
    a, b, c = (np.asarray(m) for m in (siso.A, siso.B, siso.C))
    plant = Plant(
        params=None,
        dynamics=lambda p, x, u, t: a @ x + b @ u,
        output=lambda p, x: c @ x,
        n_states=N,
        n_inputs=1,
        n_outputs=1,
        name="generic",
    )
    t = np.linspace(0.0, 4.0, 41)
    u = np.sin(t)
    ref = ct.forced_response(ct.ss(a, b, c, 0.0), t, u)
    for substeps, tol in ((5, 1e-6), (20, 5e-9)):
        ours = lt.forced_response(plant, t, u, substeps=substeps)
        assert rel_diff(ours.outputs, ref.outputs) < tol
    ref_step = ct.step_response(ct.ss(a, b, c, 0.0), t)
    assert rel_diff(lt.step_response(plant, t, substeps=20).outputs, ref_step.outputs) < 5e-9
