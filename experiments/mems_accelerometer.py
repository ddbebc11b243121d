"""Study ``mems_accelerometer``: nonlinear capacitive MEMS accelerometer under vibration (seed 004
#35; spec seed004_part2 §2.7).  Plant and kernels: :mod:`jaxsim.plants.mems_accelerometer`.

* **Sweeps.** Up and down stepped-sine sweeps of equation (1) around the primary resonance with
  the state carried over (jumps, hysteresis), batched by ``vmap`` over the vibration amplitude F
  and the sweep direction, in one compiled call together with the secondary resonances: the
  superharmonic (Ω ≈ ω0/3, the 3Ω component) and the subharmonic (Ω ≈ 3ω0, the Ω/3 component,
  started on the subharmonic branch).
* **Self-check.** First-order multiple scales (cubic and quintic terms of the electrostatic
  expansion): the peak F/(cω0), the backbone at the simulated peak, the saddle-node (jump)
  frequencies; the small-amplitude resonance against ω0 = √(1−4β).
* **Pull-in.** The static boundary a*(β) by batched bisection on g'(x) = 0, and independently by
  batched bisection on the amplitude of a slowly ramped then held acceleration that collapses the
  simulated plates.
* **Design.** V (through β) and κ by gradient (Adam, constraints built into the parametrisation) to maximise the static
  pull-in acceleration under a sensitivity floor 1/(1−4β) ≥ S_min and a flatness bound
  |εκ − 8β| ≤ γ on the effective cubic coefficient; the optimum is the vertex β = β_min,
  εκ = 8β_min + γ (a* falls with β and rises with κ), which the gradient result is checked against.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np
import optax

from experiments import figures, stages
from experiments.runner import Study, StudyResult, paper_facts
from jaxsim.plants import mems_accelerometer as mm


@dataclass(frozen=True)
class Config:
    eps: float = 0.1  # assumed nondimensional parameters (paper prints none), see Params
    mu: float = 0.1
    kappa: float = 1.0
    beta: float = 0.1
    forces: tuple[float, ...] = (0.001, 0.002, 0.004)  # F of the primary sweeps
    omega_lo: float = 0.6  # primary sweep band (ω0 = 0.775 at β = 0.1)
    omega_hi: float = 0.95
    n_omega: int = 141
    n_periods: int = 60  # periods per frequency step (the last n_measure measured)
    n_measure: int = 6
    steps_per_period: int = 64
    f_super: float = 0.05  # F of the superharmonic sweep (Ω ≈ ω0/3)
    f_sub: float = 0.3  # F of the subharmonic sweep (Ω ≈ 3ω0)
    sub_x0: float = 0.2  # initial displacement that puts the subharmonic sweep on its branch
    pull_betas: tuple[float, ...] = (0.02, 0.05, 0.1, 0.15, 0.2)
    ramp_time: float = 400.0  # nondimensional time of the slow acceleration ramp
    ramp_dt: float = 0.1
    ramp_bisections: int = 16
    # design: MEMS geometry (assumed typical, spec §2.7 item 4)
    area_m2: float = 1e-7  # plate area S
    gap_m: float = 2e-6  # gap d
    stiffness_n_per_m: float = 5.0  # suspension stiffness c
    s_min: float = 1.25  # sensitivity floor 1/(1−4β) (25 % electrostatic softening)
    gamma: float = 0.2  # flatness bound |εκ − 8β|
    design_steps: int = 400
    design_lr: float = 0.1  # Adam, cosine-decayed to 0


def _params(cfg: Config, **kw: Any) -> mm.Params:
    p = mm.Params(eps=cfg.eps, mu=cfg.mu, kappa=cfg.kappa, beta=cfg.beta, F=cfg.forces[-1])
    mm.validate(p)
    return replace(p, **kw)


def sweep_stage(cfg: Config) -> stages.Stage:
    p0 = _params(cfg)
    w0 = float(mm.linear_frequency(p0))
    n = cfg.n_omega
    up = np.linspace(cfg.omega_lo, cfg.omega_hi, n)
    rows_om, rows_f, rows_x0 = [], [], []
    for f in cfg.forces:
        for om in (up, up[::-1]):
            rows_om.append(om)
            rows_f.append(f)
            rows_x0.append((0.0, 0.0))
    sup = np.linspace(0.25 * w0, 0.4 * w0, n)[::-1]  # superharmonic, down sweep
    sub = np.linspace(3.1 * w0, 2.8 * w0, n)  # subharmonic, down sweep from above 3ω0
    rows_om += [sup, sub]
    rows_f += [cfg.f_super, cfg.f_sub]
    rows_x0 += [(0.0, 0.0), (cfg.sub_x0, 0.0)]

    def one(f: jax.Array, om: jax.Array, x0: jax.Array) -> mm.Sweep:
        return mm.sweep(replace(p0, F=f), om, x0, cfg.n_periods, cfg.n_measure, cfg.steps_per_period)

    res = jax.jit(jax.vmap(one))(jnp.asarray(rows_f), jnp.asarray(np.stack(rows_om)), jnp.asarray(rows_x0))
    om, c1, c3, c13 = (np.asarray(v) for v in (res.omega, res.c1, res.c3, res.c13))
    dead = np.asarray(res.collapsed)

    metrics: dict[str, float] = {"omega0_linear": w0}
    rows = []
    for i, f in enumerate(cfg.forces):
        pf = replace(p0, F=f)
        a_ms = float(mm.ms_peak_amplitude(pf))
        for d, name in ((0, "up"), (1, "down")):
            k = 2 * i + d
            j = int(np.argmax(c1[k]))
            a_pk, w_pk = float(c1[k, j]), float(om[k, j])
            jumps = np.abs(np.diff(c1[k]))
            jj = int(np.argmax(jumps))
            rows.append(
                {
                    "F": f,
                    "sweep": name,
                    "peak_amplitude": a_pk,
                    "peak_omega": w_pk,
                    "ms_peak_amplitude": a_ms,
                    "ms_backbone_at_peak": float(mm.ms_backbone(pf, a_pk)),
                    "largest_step_omega": float(0.5 * (om[k, jj] + om[k, jj + 1])),
                    "largest_step": float(jumps[jj]),
                    "collapsed": bool(dead[k].any()),
                }
            )
    # smallest F: resonance vs √(1−4β); largest F: peak, backbone and jumps vs multiple scales
    small_down = rows[1]
    metrics["small_f_peak_omega_over_w0"] = small_down["peak_omega"] / w0
    big_up, big_down = rows[-2], rows[-1]
    pbig = replace(p0, F=cfg.forces[-1])
    ms_dn, ms_up = mm.ms_jump_frequencies(pbig)
    dw = (cfg.omega_hi - cfg.omega_lo) / (n - 1)
    metrics.update(
        {
            "peak_amp_over_ms": big_down["peak_amplitude"] / big_down["ms_peak_amplitude"],
            "peak_omega_minus_backbone": big_down["peak_omega"] - big_down["ms_backbone_at_peak"],
            "peak_omega_down": big_down["peak_omega"],
            "jump_omega_up": big_up["largest_step_omega"],
            "jump_omega_down": big_down["largest_step_omega"],
            "ms_jump_omega_up": ms_up,
            "ms_jump_omega_down": ms_dn,
            "jump_up_minus_ms": big_up["largest_step_omega"] - ms_up,
            "jump_down_minus_ms": big_down["largest_step_omega"] - ms_dn,
            "hysteresis_width": big_up["largest_step_omega"] - big_down["largest_step_omega"],
            "ms_hysteresis_width": ms_up - ms_dn,
            "omega_step": dw,
            "peak_amp_up_over_down": big_up["peak_amplitude"] / big_down["peak_amplitude"],
            "softening_shift": big_down["peak_omega"] - w0,
        }
    )
    # secondary resonances
    ks, kb = 2 * len(cfg.forces), 2 * len(cfg.forces) + 1
    js = int(np.argmax(c3[ks]))
    jb = int(np.argmax(c13[kb]))
    metrics.update(
        {
            "super_peak_omega": float(om[ks, js]),
            "super_peak_omega_times3_over_w0": float(3 * om[ks, js] / w0),
            "super_peak_c3_over_c1": float(c3[ks, js] / c1[ks, js]),
            "super_collapsed": float(dead[ks].any()),
            "sub_max_c13": float(c13[kb].max()),
            "sub_c13_over_c1": float(c13[kb, jb] / c1[kb, jb]),
            "sub_omega_at_max": float(om[kb, jb]),
            "sub_omega_over_3w0": float(om[kb, jb] / (3 * w0)),
            "sub_collapsed": float(dead[kb].any()),
        }
    )
    sweep_rows = [
        {
            "F": rows_f[k],
            "row": k,
            "omega": float(om[k, j]),
            "c1": float(c1[k, j]),
            "c3": float(c3[k, j]),
            "c13": float(c13[k, j]),
            "collapsed": bool(dead[k, j]),
        }
        for k in range(len(rows_f))
        for j in range(n)
    ]
    a_grid = np.linspace(1e-3, float(mm.ms_peak_amplitude(pbig)), 400)
    lo_b, hi_b = (np.asarray(b) for b in mm.ms_response_branches(pbig, jnp.asarray(a_grid)))
    curves: dict[str, Any] = {}
    for i, f in enumerate(cfg.forces):
        curves[f"F={f:g} up"] = (om[2 * i], c1[2 * i])
        curves[f"F={f:g} down"] = (om[2 * i + 1], c1[2 * i + 1], "--")
    curves[f"MS F={cfg.forces[-1]:g}"] = (np.r_[lo_b, hi_b[::-1]], np.r_[a_grid, a_grid[::-1]], ":")
    curves["MS backbone"] = (np.asarray(mm.ms_backbone(p0, jnp.asarray(a_grid))), a_grid, ":")
    fig = figures.line_panels(
        [
            figures.panel(curves, "Ω", "|x| at Ω", title=f"primary resonance, β = {cfg.beta:g}"),
            figures.panel(
                {"3Ω component": (om[ks], c3[ks]), "Ω component": (om[ks], c1[ks], "--")},
                "Ω",
                "amplitude",
                title=f"superharmonic (F = {cfg.f_super:g})",
            ),
            figures.panel(
                {"Ω/3 component": (om[kb], c13[kb]), "Ω component": (om[kb], c1[kb], "--")},
                "Ω",
                "amplitude",
                title=f"subharmonic (F = {cfg.f_sub:g})",
            ),
        ]
    )
    note = (
        f"sweeps: {n} frequencies, {cfg.n_periods} periods each ({cfg.n_measure} measured), RK4 "
        f"{cfg.steps_per_period}/period, state carried over; F = {cfg.forces[-1]:g}: up sweep jumps at "
        f"Ω = {metrics['jump_omega_up']:.4f} (MS {ms_up:.4f}), down at {metrics['jump_omega_down']:.4f} "
        f"(MS {ms_dn:.4f}); down-sweep peak {big_down['peak_amplitude']:.4f} at {big_down['peak_omega']:.4f} "
        f"(MS peak {big_down['ms_peak_amplitude']:.4f}, backbone there {big_down['ms_backbone_at_peak']:.4f}); "
        f"softening (εκ − 8β = {cfg.eps * cfg.kappa - 8 * cfg.beta:.2f}). Superharmonic 3Ω peak at "
        f"Ω = {metrics['super_peak_omega']:.4f} (×3/ω0 = {metrics['super_peak_omega_times3_over_w0']:.3f}); "
        f"subharmonic Ω/3 component up to {metrics['sub_max_c13']:.4f} at Ω = {metrics['sub_omega_at_max']:.4f}"
    )
    return stages.Stage(
        metrics=metrics,
        tables={"primary_peaks": rows, "sweeps": sweep_rows},
        figures={"frequency_response": fig},
        notes=[note],
    )


def pull_in_stage(cfg: Config) -> stages.Stage:
    betas = jnp.asarray(cfg.pull_betas, dtype=float)
    p0 = _params(cfg)
    static = jax.jit(jax.vmap(lambda b: mm.pull_in(replace(p0, beta=b))))(betas)
    n_steps = int(round(1.5 * cfg.ramp_time / cfg.ramp_dt))

    def collapses(p: mm.Params, a: jax.Array) -> jax.Array:
        def rhs(t: jax.Array, x: jax.Array) -> jax.Array:
            return mm.dynamics(p, x, jnp.atleast_1d(a * jnp.minimum(t / cfg.ramp_time, 1.0)), t)

        def step(c: tuple[jax.Array, jax.Array], t: jax.Array) -> tuple[Any, None]:
            x, dead = c
            h = cfg.ramp_dt
            k1 = rhs(t, x)
            k2 = rhs(t + h / 2, x + h / 2 * k1)
            k3 = rhs(t + h / 2, x + h / 2 * k2)
            k4 = rhs(t + h, x + h * k3)
            xn = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            dead = dead | (xn[0] >= 0.95) | ~jnp.all(jnp.isfinite(xn))
            return (jnp.where(dead, x, xn), dead), None

        (_, dead), _ = jax.lax.scan(step, (jnp.zeros(2), jnp.array(False)), cfg.ramp_dt * jnp.arange(n_steps))
        return dead

    def dynamic(b: jax.Array) -> jax.Array:
        p = replace(p0, beta=b)
        hi = 1.5 * mm.pull_in(p).a + 0.05  # bracket from above (collapses), 0 from below

        def body(_: int, lh: tuple[jax.Array, jax.Array]) -> tuple[jax.Array, jax.Array]:
            lo, h = lh
            mid = 0.5 * (lo + h)
            c = collapses(p, mid)
            return jnp.where(c, lo, mid), jnp.where(c, mid, h)

        lo, h = jax.lax.fori_loop(0, cfg.ramp_bisections, body, (jnp.zeros_like(hi), hi))
        return 0.5 * (lo + h)

    dyn = np.asarray(jax.jit(jax.vmap(dynamic))(betas))
    xs, a_s = np.asarray(static.x), np.asarray(static.a)
    rows = [
        {
            "beta": float(b),
            "x_pull_in": float(x),
            "a_pull_in_static": float(a),
            "a_pull_in_ramp": float(d),
            "ramp_over_static": float(d / a),
        }
        for b, x, a, d in zip(cfg.pull_betas, xs, a_s, dyn)
    ]
    ratio = dyn / a_s
    metrics = {
        "pull_in_ramp_over_static_max_dev": float(np.max(np.abs(ratio - 1.0))),
        "pull_in_a_at_beta": float(a_s[int(np.argmin(np.abs(np.asarray(cfg.pull_betas) - cfg.beta)))]),
        "pull_in_x_at_beta": float(xs[int(np.argmin(np.abs(np.asarray(cfg.pull_betas) - cfg.beta)))]),
    }
    note = (
        f"pull-in: static a*(β) by bisection on g'(x) = 0 and by bisection ({cfg.ramp_bisections} halvings) on "
        f"the amplitude of a ramp ({cfg.ramp_time:g} time units, then held) that collapses the plates: largest "
        f"|ramp/static − 1| = {metrics['pull_in_ramp_over_static_max_dev']:.2e} over β = {list(cfg.pull_betas)}"
    )
    return stages.Stage(metrics=metrics, tables={"pull_in": rows}, notes=[note])


def design_map(cfg: Config, z: jax.Array) -> tuple[jax.Array, jax.Array]:
    """Unconstrained ``z`` → ``(β, κ)`` inside the design constraints: ``β = β_min + softplus(z₀)/10``
    (sensitivity ``1/(1−4β) ≥ S_min``) and ``εκ = 8β + γ·tanh(z₁)`` (flatness ``|εκ − 8β| ≤ γ``)."""
    b_min = (1.0 - 1.0 / cfg.s_min) / 4.0
    beta = jnp.minimum(b_min + jax.nn.softplus(z[0]) / 10.0, 0.2499)
    return beta, (8.0 * beta + cfg.gamma * jnp.tanh(z[1])) / cfg.eps


def design_loss(cfg: Config, z: jax.Array) -> tuple[jax.Array, dict[str, jax.Array]]:
    """``−a*`` (static pull-in acceleration) at the design ``z`` (see :func:`design_map`)."""
    beta, kappa = design_map(cfg, z)
    a = mm.pull_in(replace(_params(cfg), beta=beta, kappa=kappa)).a
    v = mm.voltage_from_beta(beta, cfg.area_m2, cfg.gap_m, cfg.stiffness_n_per_m)
    return -a, {
        "a": a,
        "beta": beta,
        "kappa": kappa,
        "v": v,
        "sens": 1.0 / (1.0 - 4.0 * beta),
        "flat": cfg.eps * kappa - 8 * beta,
    }


def design_stage(cfg: Config) -> stages.Stage:
    geo = (cfg.area_m2, cfg.gap_m, cfg.stiffness_n_per_m)
    b_min = (1.0 - 1.0 / cfg.s_min) / 4.0
    # start: the nominal β and flatness εκ − 8β = εκ_nominal − 8β_nominal clipped into the bound
    z0 = jnp.array([np.log(np.expm1(10.0 * (cfg.beta - b_min))), np.arctanh(0.0)])
    opt = optax.adam(optax.cosine_decay_schedule(cfg.design_lr, cfg.design_steps))

    def step(c: tuple[jax.Array, Any], _: Any) -> tuple[Any, jax.Array]:
        z, st = c
        (loss, _), g = jax.value_and_grad(lambda t: design_loss(cfg, t), has_aux=True)(z)
        upd, st = opt.update(g, st, z)
        return (optax.apply_updates(z, upd), st), loss

    (theta, _), losses = jax.jit(lambda t: jax.lax.scan(step, (t, opt.init(t)), None, cfg.design_steps))(z0)
    _, aux = design_loss(cfg, theta)
    _, aux0 = design_loss(cfg, z0)
    # the vertex optimum
    b_opt = (1.0 - 1.0 / cfg.s_min) / 4.0
    k_opt = (8.0 * b_opt + cfg.gamma) / cfg.eps
    a_opt = float(mm.pull_in(replace(_params(cfg), beta=b_opt, kappa=k_opt)).a)
    v_opt = float(mm.voltage_from_beta(b_opt, *geo))
    metrics = {
        "design_v": float(aux["v"]),
        "design_kappa": float(aux["kappa"]),
        "design_beta": float(aux["beta"]),
        "design_pull_in_a": float(aux["a"]),
        "design_sensitivity": float(aux["sens"]),
        "design_flatness": float(aux["flat"]),
        "design_start_pull_in_a": float(aux0["a"]),
        "vertex_v": v_opt,
        "vertex_kappa": k_opt,
        "vertex_pull_in_a": a_opt,
        "design_a_over_vertex": float(aux["a"]) / a_opt,
    }
    rows = [{"step": i, "loss": float(v)} for i, v in enumerate(np.asarray(losses))]
    note = (
        f"design: Adam ({cfg.design_steps} steps, cosine-decayed lr {cfg.design_lr:g}) on (V, κ) mapped into "
        f"the constraints, from V = {float(aux0['v']):.3f} V, κ = {float(aux0['kappa']):.3f} "
        f"(a* = {float(aux0['a']):.4f}) "
        f"→ V = {float(aux['v']):.4f} V, κ = {float(aux['kappa']):.3f}, a* = {float(aux['a']):.4f}, "
        f"sensitivity {float(aux['sens']):.4f} "
        f"(floor {cfg.s_min:g}), εκ − 8β = {float(aux['flat']):.4f} (bound {cfg.gamma:g}); the vertex "
        f"β = {b_opt:.4f} (V = {v_opt:.4f} V), κ = {k_opt:.3f} gives a* = {a_opt:.4f}. Geometry assumed: "
        f"S = {cfg.area_m2:g} m², d = {cfg.gap_m:g} m, c = {cfg.stiffness_n_per_m:g} N/m"
    )
    return stages.Stage(metrics=metrics, tables={"design_history": rows}, notes=[note])


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    return stages.merge(sweep_stage(cfg), pull_in_stage(cfg), design_stage(cfg))


CLAIMS, ASSUMPTIONS = paper_facts("mems_accelerometer")

STUDY = Study(
    name="mems_accelerometer",
    description="Seed 004 #35: nonlinear capacitive MEMS accelerometer — batched up/down sweeps (jumps, "
    "hysteresis, 1/3 and 3 resonances), multiple-scales check, pull-in by bisection, (V, κ) by gradient",
    config=Config,
    presets={
        "quick": dict(n_omega=71, n_periods=40),
        "tiny": dict(
            n_omega=36,
            n_periods=30,
            steps_per_period=32,
            pull_betas=(0.05, 0.1),
            ramp_time=200.0,
            ramp_dt=0.2,
            ramp_bisections=10,
            design_steps=150,
        ),
    },
    claims=CLAIMS,
    assumptions=ASSUMPTIONS,
    run=run,
)
