"""Agreement of :mod:`jaxsim.lti` with python-control (and SciPy) on random systems.

For every function of the python-control vocabulary: the number of random systems tried, what
they were, and the worst difference from python-control.  Differences are normwise relative,
``max|ours − theirs| / max|theirs|`` per case (a scalar: ``|ours − theirs|/|theirs|``; an ``inf``
margin must be ``inf`` on both sides, a NaN frequency NaN on both sides).  Gradients are checked
against central finite differences of our own function (relative step ``1e-6``), with the same
metric.

Random systems: ``control.rss`` (stable) with the sizes ``(n, p, m)`` of :data:`SIZES` in turn
(SISO, square and non-square MIMO), transfer functions with random coefficients, loop transfer
functions ``L = k·P·C`` (a random stable plant of order 2 or 3, a PI or lead controller, ``k``
log-uniform) for the margins, sampled with ``c2d`` for the discrete ones.
python-control's own numbers come from its polynomial methods, so the worst differences also
measure how well conditioned the random cases are.

Usage: ``python -m experiments.benchmarks.python_control_agreement [--n 6] [--seed 0] [--json out.json]``
(about 3 minutes of CPU time at the default ``--n``, most of it XLA compilation; ``tests/lti`` runs the
same comparisons on fewer systems).
"""

from __future__ import annotations

import argparse
import time
import warnings
from typing import Any, Callable

import control as ct
import jax
import jax.numpy as jnp
import numpy as np

import jaxsim  # noqa: F401  (float64)
import jaxsim.lti as lt
import jaxsim.lti.compat as jc
from experiments.benchmarks.timing import write_json

FD_STEP = 1e-6
SIZES = ((2, 1, 1), (3, 2, 2), (4, 1, 2))
"""``(n, p, m)`` of the random systems, in turn: SISO, square MIMO, non-square MIMO.  A handful of fixed
sizes, because every new size costs an XLA compilation of each function."""


def size(i: int, square: bool = False, siso: bool = False) -> tuple[int, int, int]:
    """The ``i``-th entry of :data:`SIZES` (cyclic), made square (``p = m = min``) or SISO if asked."""
    n, p, m = SIZES[i % len(SIZES)]
    if siso:
        return n, 1, 1
    return (n, min(p, m), min(p, m)) if square else (n, p, m)


# --- random systems --------------------------------------------------------------------------------


def random_ss(rng: np.random.Generator, n: int, p: int = 1, m: int = 1, dt: float | None = None) -> ct.StateSpace:
    """A random stable python-control system (``rss``/``drss`` seeded from ``rng``), with a random ``D``."""
    np.random.seed(int(rng.integers(2**31)))
    sys = ct.rss(n, p, m) if dt is None else ct.drss(n, p, m, dt=dt)
    d = rng.normal(size=(p, m)) * (rng.random() < 0.5)
    return ct.ss(sys.A, sys.B, sys.C, d, sys.dt)


def random_tf(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    """A random proper SISO ``num/den`` with a stable denominator of degree ``n``."""
    poles = -rng.uniform(0.2, 5.0, n).astype(complex)
    for i in range(0, n - 1, 2):  # some complex pairs
        if rng.random() < 0.5:
            wd = rng.uniform(0.2, 5.0)
            poles[i], poles[i + 1] = poles[i].real + 1j * wd, poles[i].real - 1j * wd
    den = np.real(np.poly(poles)) * rng.uniform(0.5, 2.0)
    num = rng.normal(size=int(rng.integers(1, n + 2)))
    return num, den


def random_loop(
    rng: np.random.Generator, dt: float | None = None, integrator: bool = True, order: int = 2
) -> ct.TransferFunction:
    """A loop transfer function ``k·P·C``: random stable plant of ``order`` states, PI (if
    ``integrator``) or lead controller.  Kept a transfer function: python-control's polynomial
    margins of an ``ss`` go through ``ss → tf``, whose rounding-level leading numerator coefficients
    it reports as phase crossovers near 10⁸ rad/s (gain margins of 10¹⁵)."""
    num, den = random_tf(rng, order)
    plant = ct.tf(num[-1:], den)  # low-pass plant
    if integrator and rng.random() < 0.5:
        ctrl = ct.tf([1.0, rng.uniform(0.1, 2.0)], [1.0, 0.0])  # PI
    else:
        z = rng.uniform(0.1, 2.0)
        ctrl = ct.tf([1.0, z], [1.0, z * rng.uniform(3.0, 20.0)])  # lead
    loop = 10 ** rng.uniform(-0.5, 1.5) * plant * ctrl
    return loop if dt is None else ct.c2d(loop, dt, "zoh")


def to_ours(sys: ct.StateSpace | ct.TransferFunction) -> Any:
    """The python-control system as ours (a transfer function through its state-space realisation)."""
    if isinstance(sys, ct.TransferFunction):
        sys = ct.ss(sys)
    return lt.ss(sys.A, sys.B, sys.C, sys.D, None if sys.dt in (0, None) else sys.dt)


# --- differences -----------------------------------------------------------------------------------


def rel_diff(ours: Any, theirs: Any) -> float:
    """Normwise relative difference; matching inf/NaN patterns count as equal, mismatches as inf."""
    a = np.asarray(ours, dtype=complex).ravel()
    b = np.asarray(theirs, dtype=complex).ravel()
    if a.shape != b.shape:
        return float("inf")
    bad_a, bad_b = ~np.isfinite(a), ~np.isfinite(b)
    if np.any(bad_a != bad_b) or np.any(np.isinf(a[bad_a]) != np.isinf(b[bad_b])):
        return float("inf")
    a, b = a[~bad_a], b[~bad_b]
    if a.size == 0:
        return 0.0
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


def sorted_roots(r: Any) -> np.ndarray:
    r = np.asarray(r, dtype=complex)
    return r[np.lexsort((np.round(r.imag, 8), np.round(r.real, 8)))]


def fd_gradient(f: Callable[[jax.Array], jax.Array], x: jax.Array) -> np.ndarray:
    """Central differences of a scalar ``f`` along each entry of ``x``."""
    x = np.asarray(x, dtype=float)
    out = np.zeros_like(x)
    for idx in np.ndindex(x.shape):
        h = FD_STEP * max(1.0, abs(x[idx]))
        e = np.zeros_like(x)
        e[idx] = h
        out[idx] = (float(f(jnp.asarray(x + e))) - float(f(jnp.asarray(x - e)))) / (2 * h)
    return out


# --- the checks: each returns (systems description, list of differences) ---------------------------


def check_construct(rng, n):
    diffs = {"ss": [], "tf": [], "zpk": []}
    w = np.logspace(-2, 2, 25)
    for i in range(n):
        sys = random_ss(rng, *size(i))
        diffs["ss"].append(
            rel_diff(
                lt.frequency_response(to_ours(sys), w, squeeze=False).response,
                ct.frequency_response(sys, w, squeeze=False).complex,
            )
        )
        num, den = random_tf(rng, size(i)[0])
        diffs["tf"].append(rel_diff(lt.evalfr(lt.tf(num, den), 1j * w)[:, 0, 0], ct.tf(num, den)(1j * w)))
        z, p, k = np.roots(num) if len(num) > 1 else [], np.roots(den), num[0] / den[0]
        diffs["zpk"].append(rel_diff(lt.evalfr(lt.zpk(z, p, k), 1j * w)[:, 0, 0], ct.zpk(z, p, k)(1j * w)))
    return [
        ("ss", "rss (n,p,m) in SIZES, D random", diffs["ss"]),
        ("tf", "random num/den, n in SIZES", diffs["tf"]),
        ("zpk", "roots of random num/den", diffs["zpk"]),
    ]


def check_interconnect(rng, n):
    out = {"series": [], "parallel": [], "feedback": []}
    w = np.logspace(-2, 2, 25)
    for i in range(n):
        nx, p, m = size(i)
        g1 = random_ss(rng, nx, p, m)
        g2 = random_ss(rng, size(i + 1)[0], m, p)
        g3 = random_ss(rng, size(i + 2)[0], p, m)
        g2 = ct.ss(g2.A, g2.B, g2.C, 0.3 * g2.D)  # keep I + D1 D2 well conditioned
        resp = lambda s: lt.frequency_response(s, w, squeeze=False).response  # noqa: E731
        ref = lambda s: ct.frequency_response(s, w, squeeze=False).complex  # noqa: E731
        out["series"].append(rel_diff(resp(lt.series(to_ours(g1), to_ours(g2))), ref(ct.series(g1, g2))))
        out["parallel"].append(rel_diff(resp(lt.parallel(to_ours(g1), to_ours(g3))), ref(ct.parallel(g1, g3))))
        out["feedback"].append(rel_diff(resp(lt.feedback(to_ours(g1), to_ours(g2))), ref(ct.feedback(g1, g2))))
    desc = "rss pairs, sizes from SIZES, with D"
    return [(k, desc, v) for k, v in out.items()]


def check_c2d(rng, n):
    rows = []
    for method in ("zoh", "foh", "tustin", "matched"):
        diffs = []
        for i in range(n):
            siso = method == "matched"
            sys = random_ss(rng, *size(i, siso=siso))
            ts = float(rng.uniform(0.05, 0.5))
            ref = ct.c2d(ct.tf(sys) if siso else sys, ts, method)
            ours = lt.c2d(to_ours(sys), ts, method)
            z = np.exp(1j * np.linspace(0.01, 0.99 * np.pi, 25))
            diffs.append(rel_diff(lt.evalfr(ours, z), np.moveaxis(ref(z, squeeze=False), -1, 0)))
        rows.append((f"c2d {method}", "rss, SIZES (SISO for matched), Ts∈[0.05, 0.5]", diffs))
    return rows


def check_structure(rng, n):
    out = {"ctrb": [], "obsv": [], "pole": [], "zero": [], "dcgain": []}
    for i in range(n):
        sys = random_ss(rng, *size(i, square=True))
        ours = to_ours(sys)
        out["ctrb"].append(rel_diff(lt.ctrb(sys.A, sys.B), ct.ctrb(sys.A, sys.B)))
        out["obsv"].append(rel_diff(lt.obsv(sys.A, sys.C), ct.obsv(sys.A, sys.C)))
        out["pole"].append(rel_diff(sorted_roots(lt.pole(ours)), sorted_roots(ct.poles(sys))))
        zr = ct.zeros(sys)
        zr = zr[np.abs(zr) < 1e8]  # python-control's QZ reports some infinite zeros as huge finite ones
        out["zero"].append(rel_diff(sorted_roots(lt.zero(ours)), sorted_roots(zr)))
        out["dcgain"].append(rel_diff(lt.dcgain(ours), ct.dcgain(sys)))
    desc = "rss, SIZES made square (p = m)"
    return [(k, desc, v) for k, v in out.items()]


def check_placement(rng, n):
    siso, mimo, ack = [], [], []
    for i in range(n):
        nx = (3, 5)[i % 2]
        a, b = rng.normal(size=(nx, nx)), rng.normal(size=(nx, 2))
        poles = -rng.uniform(0.5, 4.0, nx).astype(complex)
        if nx >= 2:
            wd = rng.uniform(0.5, 3.0)
            poles[0], poles[1] = poles[0].real + 1j * wd, poles[0].real - 1j * wd
        siso.append(rel_diff(lt.place(a, b[:, :1], poles), ct.place(a, b[:, :1], poles)))
        ack.append(rel_diff(lt.acker(a, b[:, :1], poles), ct.acker(a, b[:, :1], poles)))
        k = np.asarray(lt.place(a, b, poles))
        mimo.append(rel_diff(sorted_roots(np.linalg.eigvals(a - b @ k)), sorted_roots(poles)))
    return [
        ("place (1 input), K", "random A, B (n = 3, 5), poles with a complex pair", siso),
        ("place (2 inputs), eig(A−BK)", "same, vs the requested poles", mimo),
        ("acker", "random A, b (n = 3, 5)", ack),
    ]


def check_design(rng, n):
    out = {k: [] for k in ("lqr", "lqr N", "dlqr", "care S E", "dare S E", "lqe", "dlqe")}
    failed = {k: 0 for k in out}

    def compare(name, ours, reference, idx=(0, 1)):
        """``max`` difference of the entries ``idx`` (the gain and the Riccati solution); a case that
        python-control's own solver rejects (``LinAlgError``: no stabilising solution it can find)
        is counted and left out."""
        try:
            ref = reference()
        except np.linalg.LinAlgError:
            failed[name] += 1
            return
        got = ours()
        out[name].append(max(rel_diff(got[i], ref[i]) for i in idx))

    for i in range(n):
        nx, _, nu = size(i)
        a, b = rng.normal(size=(nx, nx)), rng.normal(size=(nx, nu))
        ad = a / (1.2 * max(1.0, np.max(np.abs(np.linalg.eigvals(a)))))
        q, r = np.diag(rng.uniform(0.5, 2, nx)), np.diag(rng.uniform(0.5, 2, nu))
        nn = 0.1 * rng.normal(size=(nx, nu))
        e = np.eye(nx) + 0.1 * rng.normal(size=(nx, nx))
        c = rng.normal(size=(nu, nx))
        compare("lqr", lambda: jc.lqr(a, b, q, r), lambda: ct.lqr(a, b, q, r))
        compare("lqr N", lambda: jc.lqr(a, b, q, r, nn), lambda: ct.lqr(a, b, q, r, nn))
        compare("dlqr", lambda: jc.dlqr(ad, b, q, r), lambda: ct.dlqr(ad, b, q, r))
        compare(
            "care S E", lambda: jc.care(a, b, q, r, nn, e), lambda: ct.care(a, b, q, r, nn, e, method="scipy"), (0, 2)
        )
        compare(
            "dare S E", lambda: jc.dare(ad, b, q, r, nn, e), lambda: ct.dare(ad, b, q, r, nn, e, method="scipy"), (0, 2)
        )
        compare("lqe", lambda: jc.lqe(a, np.eye(nx), c, q, r), lambda: ct.lqe(a, np.eye(nx), c, q, r))
        compare("dlqe", lambda: jc.dlqe(ad, np.eye(nx), c, q, r), lambda: ct.dlqe(ad, np.eye(nx), c, q, r))
    desc = "random A, B (n, m from SIZES), diagonal weights; K/L and S/P/X"
    return [
        (k, desc + (f"; {failed[k]} left out: python-control found no solution" if failed[k] else ""), v)
        for k, v in out.items()
    ]


def check_time(rng, n):
    out = {
        k: []
        for k in (
            "step_response",
            "impulse_response",
            "initial_response",
            "forced_response",
            "step_response (discrete)",
            "forced_response (discrete)",
            "step_info",
        )
    }
    for i in range(n):
        nx, p, m = size(i)
        sys = random_ss(rng, nx, p, m)
        ours = to_ours(sys)
        t = np.linspace(0.0, 8.0, 161)
        u = rng.normal(size=(m, t.size))
        x0 = rng.normal(size=sys.nstates)
        both = lambda o, r: max(rel_diff(o.outputs, r.outputs), rel_diff(o.states, r.states))  # noqa: E731
        out["step_response"].append(both(lt.step_response(ours, t), ct.step_response(sys, t)))
        out["impulse_response"].append(both(lt.impulse_response(ours, t), ct.impulse_response(sys, t)))
        out["initial_response"].append(both(lt.initial_response(ours, t, x0), ct.initial_response(sys, t, x0)))
        out["forced_response"].append(
            both(
                lt.forced_response(ours, t, u if m > 1 else u[0], x0),
                ct.forced_response(sys, t, u if m > 1 else u[0], x0),
            )
        )
        dsys = random_ss(rng, nx, p, m, dt=0.1)
        td = np.arange(60) * 0.1
        ud = rng.normal(size=(m, td.size))
        out["step_response (discrete)"].append(both(lt.step_response(to_ours(dsys), td), ct.step_response(dsys, td)))
        out["forced_response (discrete)"].append(
            both(
                lt.forced_response(to_ours(dsys), td, ud if m > 1 else ud[0]),
                ct.forced_response(dsys, td, ud if m > 1 else ud[0]),
            )
        )
        siso = ct.ss(sys.A, sys.B[:, :1], sys.C[:1], sys.D[:1, :1])
        resp = lt.step_response(to_ours(siso), np.linspace(0.0, 15.0, 1501))
        yf = float(ct.dcgain(siso))
        try:  # the definitions on identical samples (python-control fails if y never reaches 90 %)
            ref = ct.step_info(np.asarray(resp.outputs), np.asarray(resp.time), yfinal=yf)
        except IndexError:
            continue
        mine = lt.step_info(resp, yfinal=yf).as_dict()
        out["step_info"].append(max(rel_diff(mine[k], ref[k]) for k in ref))
    return [
        ("step_response", "rss, SIZES, 161 points", out["step_response"]),
        ("impulse_response", "same", out["impulse_response"]),
        ("initial_response", "same, random X0", out["initial_response"]),
        ("forced_response", "same, random U (linear between samples), X0", out["forced_response"]),
        ("step_response (discrete)", "drss, SIZES, dt=0.1, 60 samples", out["step_response (discrete)"]),
        ("forced_response (discrete)", "same, random U", out["forced_response (discrete)"]),
        ("step_info", "SISO rss step responses (1501 points), all nine entries, same samples", out["step_info"]),
    ]


def check_frequency(rng, n):
    fr, bd = [], []
    w = np.logspace(-2, 2, 50)
    for i in range(n):
        sys = random_ss(rng, *size(i))
        ours, ref = lt.frequency_response(to_ours(sys), w), ct.frequency_response(sys, w)
        fr.append(max(rel_diff(ours.magnitude, ref.magnitude), rel_diff(ours.phase, ref.phase)))
        siso = ct.ss(sys.A, sys.B[:, :1], sys.C[:1], sys.D[:1, :1])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", FutureWarning)
            mag, phase, _ = ct.bode(siso, w, plot=False)
        ob = lt.bode(to_ours(siso), w)
        bd.append(max(rel_diff(ob.magnitude, mag), rel_diff(ob.phase, phase)))
    return [
        ("frequency_response", "rss, SIZES, 50 frequencies: mag and phase", fr),
        ("bode", "SISO rss, unwrapped phase", bd),
    ]


def _reference_margins(loop: ct.StateSpace):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # python-control's FRD fallback (a warning) is not comparable
        sm = ct.stability_margins(loop)
        allm = ct.stability_margins(loop, returnall=True)
    pm_all, wgc_all = allm[1], allm[4]
    dm = np.min(np.radians(np.mod(pm_all, 360.0)) / wgc_all) if len(wgc_all) else np.inf
    return sm, dm


def _spurious_sm(loop: ct.StateSpace, ref) -> bool:
    """python-control's polynomial method can report a stationary point of ``|1 + L|`` far above every
    break frequency, with ``|1 + L| = 1`` (rounding in the ``ss → tf`` numerator): not a minimum."""
    features = np.abs(np.concatenate([ct.poles(loop), ct.zeros(loop)]))
    features = features[np.isfinite(features) & (features > 0)]
    return bool(np.isfinite(ref[5]) and ref[5] > 1e4 * np.max(features) and abs(ref[2] - 1.0) < 1e-6)


def check_margins(rng, n):
    rows = {
        k: []
        for k in (
            "gm pm wpc wgc",
            "sm wms",
            "margin",
            "delay margin",
            "discrete gm pm wpc wgc",
            "discrete sm",
            "discrete wms",
        )
    }
    skipped, spurious = 0, 0
    for i in range(2 * n):
        discrete = i >= n
        loop = random_loop(
            rng, dt=float(rng.uniform(0.1, 0.3)) if discrete else None, integrator=not discrete, order=2 + i % 2
        )
        try:
            ref, dm_ref = _reference_margins(loop)
        except (UserWarning, RuntimeWarning):
            skipped += 1
            continue
        ours = lt.stability_margins(to_ours(loop))
        main = max(rel_diff(ours[j], ref[j]) for j in (0, 1, 3, 4))
        if discrete:
            rows["discrete gm pm wpc wgc"].append(main)
            rows["discrete sm"].append(rel_diff(ours[2], ref[2]))
            rows["discrete wms"].append(rel_diff(ours[5], ref[5]))
            continue
        rows["gm pm wpc wgc"].append(main)
        if _spurious_sm(loop, ref):
            spurious += 1
        else:
            rows["sm wms"].append(max(rel_diff(ours[2], ref[2]), rel_diff(ours[5], ref[5])))
        m = lt.margin(to_ours(loop))
        rows["margin"].append(max(rel_diff(o, r) for o, r in zip(m[:4], ct.margin(loop))))
        rows["delay margin"].append(rel_diff(m.dm, dm_ref))
    loops = "k·P·C (stable plant of order 2 or 3, PI or lead, k∈[0.3, 30])"
    note = f"; {skipped} skipped: python-control fell back to its FRD method" if skipped else ""
    return [
        ("stability_margins: gm pm wpc wgc", loops, rows["gm pm wpc wgc"]),
        (
            "stability_margins: sm wms",
            loops + f"; {spurious} left out: python-control's spurious "
            "stationary point at |1+L| = 1 far above the break frequencies",
            rows["sm wms"],
        ),
        ("margin", loops + ": gm pm wcg wcp", rows["margin"]),
        ("delay margin", "same, vs min over python-control's crossovers of (PM mod 360°)/ω", rows["delay margin"]),
        (
            "stability_margins (discrete): gm pm wpc wgc",
            "lead loops, c2d zoh, dt∈[0.1, 0.3]" + note,
            rows["discrete gm pm wpc wgc"],
        ),
        ("stability_margins (discrete): sm", "same (python-control: scipy.optimize.minimize)", rows["discrete sm"]),
        ("stability_margins (discrete): wms", "same", rows["discrete wms"]),
    ]


# gradients: jitted once, the random data passed as arguments (shapes fixed: n = 3, SISO)
_T, _W = jnp.linspace(0.0, 5.0, 51), jnp.logspace(-1, 1, 7)
_POLES = jnp.array([-1.0 + 0j, -2.0 + 1.0j, -2.0 - 1.0j])
_MARGIN_FIELDS = ("gm", "pm", "sm", "wpc", "wgc", "wms")


@jax.jit
def _grad_targets(a, b, c, d):
    """Scalar functions of ``A`` (with ``B, C, D``) whose gradients are compared with finite differences."""
    zeros = lt.zero(lt.ss(a, b, c, d))
    return jnp.stack(
        [
            jnp.sum(lt.step_response(lt.ss(a, b, c, d), _T).outputs ** 2),
            jnp.sum(lt.frequency_response(lt.ss(a, b, c, d), _W).magnitude),
            jnp.sum(jnp.where(jnp.isfinite(zeros), jnp.abs(zeros), 0.0)),
            jnp.sum(lt.place(a, b, _POLES) ** 2),
            jnp.sum(lt.c2d(lt.ss(a, b, c, d), 0.2).b ** 2),
        ]
    )


_GRAD_NAMES = ("d step_response/dA", "d frequency_response/dA", "d zero/dA", "d place/dA (1 input)", "d c2d(zoh)/dA")


@jax.jit
def _margin_targets(theta, num, den):
    """The six stability margins and the delay margin of ``k(s + z)/s · num/den``, ``θ = (k, z)``."""
    pi = lt.tf(jnp.stack([theta[0], theta[0] * theta[1]]), jnp.array([1.0, 0.0]))
    loop = lt.series(pi, lt.tf(num, den))
    return jnp.stack(list(lt.stability_margins(loop)) + [lt.margin(loop).dm])


def check_gradients(rng, n):
    out = {k: [] for k in _GRAD_NAMES + ("d margins/d(k, z)",)}
    for _ in range(n):
        sys = random_ss(rng, 3, 1, 1)
        a0, b, c, d = (jnp.asarray(x) for x in (sys.A, sys.B, sys.C, sys.D))
        jac = jax.jacrev(_grad_targets)(a0, b, c, d)
        for i, name in enumerate(_GRAD_NAMES):
            out[name].append(rel_diff(jac[i], fd_gradient(lambda a, i=i: _grad_targets(a, b, c, d)[i], a0)))
        num, den = random_tf(rng, 2)
        num, den = jnp.asarray(num[-1:]), jnp.asarray(den)
        theta0 = jnp.array([float(10 ** rng.uniform(0.0, 1.0)), float(rng.uniform(0.2, 1.0))])
        values = np.asarray(_margin_targets(theta0, num, den))
        jac = jax.jacrev(_margin_targets)(theta0, num, den)
        for i in np.flatnonzero(np.isfinite(values)):
            fd = fd_gradient(lambda th, i=i: _margin_targets(th, num, den)[i], theta0)
            out["d margins/d(k, z)"].append(rel_diff(jac[i], fd))
    desc = {
        "d step_response/dA": "rss n=3 SISO, Σy² over 51 points",
        "d frequency_response/dA": "same, Σ|G| over 7 frequencies",
        "d margins/d(k, z)": "(finite ones of) the six margins and the delay margin of k(s+z)/s · P, P of order 2",
        "d zero/dA": "rss n=3, Σ|zeros|",
        "d place/dA (1 input)": "rss n=3, ΣK² for fixed poles",
        "d c2d(zoh)/dA": "rss n=3, ΣBd², Ts=0.2",
    }
    return [(k + " vs FD", desc[k], v) for k, v in out.items()]


CHECKS = (
    check_construct,
    check_interconnect,
    check_c2d,
    check_structure,
    check_placement,
    check_design,
    check_time,
    check_frequency,
    check_margins,
    check_gradients,
)


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=6, help="random systems per function (sizes cycle through SIZES)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--json", default=None, help="write the table to this file")
    args = ap.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    rows = []
    start = time.perf_counter()
    seconds = {}
    for check in CHECKS:
        t0 = time.perf_counter()
        for name, desc, diffs in check(rng, args.n if check is not check_gradients else max(1, args.n // 4)):
            rows.append(
                {
                    "function": name,
                    "systems": f"{len(diffs)} × {desc}",
                    "worst": float(np.max(diffs)) if diffs else float("nan"),
                }
            )
        seconds[check.__name__] = time.perf_counter() - t0
    width = max(len(r["function"]) for r in rows)
    print(f"jaxsim.lti vs python-control {ct.__version__} (seed {args.seed}, {time.perf_counter() - start:.0f} s)\n")
    print(f"| {'function':{width}s} | worst difference | systems tried |")
    print(f"|{'-' * (width + 2)}|------------------|---------------|")
    for r in rows:
        print(f"| {r['function']:{width}s} | {r['worst']:16.1e} | {r['systems']} |")
    print(
        "\nseconds per check (mostly XLA compilation): "
        + ", ".join(f"{k.removeprefix('check_')} {v:.0f}" for k, v in seconds.items())
    )
    out = {"seed": args.seed, "n": args.n, "python_control": ct.__version__, "rows": rows, "seconds": seconds}
    write_json(args.json, out)
    return out


if __name__ == "__main__":
    main()
