"""Study ``ship_heading_robust``: robust-property optimisation of a ship-heading controller (seed 004
#4, Tomilova; spec seed004_part1 B9).  Plant and loop: :mod:`jaxsim.plants.nomoto_ship`.

The paper minimises J1 = max_ω |T(jω)| (its "narrowest corridor") over controllers whose closed-loop
roots lie in the sector C = {x ≤ −α, |y| ≤ |x| tan β}.  Here: a PID heading law on a Nomoto ship with a
rudder servo (the paper's model is lost); J1 on a log frequency grid; the pole sector as
differentiable constraints on ``eigvals`` of the closed loop; gain and phase margins from
:func:`jaxsim.lti.margins.margin` (differentiable) as further constraints; one penalised loss,
minimised by gradient (Adam through eigvals and the margins) and by PSO on equal budgets.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np
import optax

from experiments import figures, stages
from experiments.runner import Study, StudyResult, paper_facts
from jaxsim.lti.margins import margin
from jaxsim.plants import nomoto_ship as ship
from optim.pso import pso
from optim.tune import tune


@dataclass(frozen=True)
class Config:
    K: float = 0.1  # 1/s, Nomoto gain (assumed)
    T: float = 20.0  # s, Nomoto time constant (assumed)
    T_r: float = 2.0  # s, rudder servo (assumed)
    alpha: float = 0.03  # 1/s, sector: Re λ ≤ −α (settling ≈ 4/α)
    beta_deg: float = 45.0  # sector half-angle (damping ≥ cos β)
    pm_min_deg: float = 45.0
    gm_min: float = 2.0  # ratio (6 dB)
    gains0: tuple[float, float, float] = (1.0, 15.0, 0.02)  # hand PID (k_p, k_d, k_i)
    log_lo: tuple[float, float, float] = (-3.0, 0.0, -8.0)  # PSO box of log gains
    log_hi: tuple[float, float, float] = (2.0, 4.5, -1.0)
    n_freq: int = 300
    w_lo: float = 1e-4  # rad/s
    w_hi: float = 10.0
    penalty: float = 1e4
    margin_grid: int = 400  # jaxsim.lti.margins bracketing grid
    margin_crossings: int = 4
    grad_steps: int = 150
    grad_lr: float = 0.05
    grad_cost: float = 3.0
    pso_particles: int = 16
    seed: int = 0


def design_terms(cfg: Config, theta: jax.Array) -> dict[str, jax.Array]:
    """Log gains → J1, the sector residuals, GM, PM and the penalised loss."""
    p = ship.Params(K=cfg.K, T=cfg.T, T_r=cfg.T_r)
    g = jnp.exp(theta)
    w = jnp.logspace(math.log10(cfg.w_lo), math.log10(cfg.w_hi), cfg.n_freq)
    j1 = jnp.max(ship.complementary_sensitivity(p, g, w))
    eigs = jnp.linalg.eigvals(ship.closed_loop_matrix(p, g))
    sector = ship.sector_residuals(eigs, cfg.alpha, jnp.deg2rad(cfg.beta_deg))
    m = margin(ship.loop_transfer(p, g), n_grid=cfg.margin_grid, max_crossings=cfg.margin_crossings)
    gm = jnp.where(jnp.isfinite(m.gm), m.gm, 1e6)
    viol = jnp.concatenate(
        [sector.ravel(), jnp.stack([(cfg.pm_min_deg - m.pm) / 90.0, jnp.log(cfg.gm_min) - jnp.log(gm)])]
    )
    loss = j1 + cfg.penalty * jnp.sum(jax.nn.relu(viol) ** 2)
    return {"loss": loss, "j1": j1, "gm": m.gm, "pm": m.pm, "max_violation": jnp.max(viol), "eigs": eigs}


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    def loss(theta: jax.Array) -> jax.Array:
        return design_terms(cfg, theta)["loss"]

    theta0 = jnp.log(jnp.asarray(cfg.gains0))
    g_res = tune(loss, theta0, optimizer=optax.adam(cfg.grad_lr), steps=cfg.grad_steps, grad_cost=cfg.grad_cost)
    n_iters = max(1, math.ceil(cfg.grad_steps * cfg.grad_cost / cfg.pso_particles))
    p_res = pso(
        loss,
        jnp.asarray(cfg.log_lo),
        jnp.asarray(cfg.log_hi),
        n_particles=cfg.pso_particles,
        n_iters=n_iters,
        key=jax.random.PRNGKey(cfg.seed),
    )
    designs = {"hand": theta0, "gradient": jnp.asarray(g_res.params), "pso": jnp.asarray(p_res.params)}
    terms = jax.jit(jax.vmap(lambda t: design_terms(cfg, t)))(jnp.stack(list(designs.values())))
    rows = []
    for i, name in enumerate(designs):
        gains = np.exp(np.asarray(designs[name]))
        eigs = np.asarray(terms["eigs"][i])
        rows.append(
            {
                "design": name,
                "k_p": float(gains[0]),
                "k_d": float(gains[1]),
                "k_i": float(gains[2]),
                "j1_max_T": float(terms["j1"][i]),
                "gm": float(terms["gm"][i]),
                "pm_deg": float(terms["pm"][i]),
                "max_violation": float(terms["max_violation"][i]),
                "slowest_re": float(np.max(eigs.real)),
                "max_angle_deg": float(np.degrees(np.max(np.arctan2(np.abs(eigs.imag), -eigs.real)))),
                "loss": float(terms["loss"][i]),
            }
        )
    by = {r["design"]: r for r in rows}
    metrics: dict[str, float] = {}
    for name, r in by.items():
        for k in ("j1_max_T", "pm_deg", "max_violation", "slowest_re", "max_angle_deg", "loss"):
            metrics[f"{name}_{k}"] = r[k]
        metrics[f"{name}_gm_finite"] = float(np.isfinite(r["gm"]))
    metrics["gradient_over_pso_loss"] = by["gradient"]["loss"] / by["pso"]["loss"]
    metrics["gradient_over_hand_loss"] = by["gradient"]["loss"] / by["hand"]["loss"]
    metrics["gradient_sims"] = float(g_res.n_sims)
    metrics["pso_sims"] = float(p_res.n_sims)
    p = ship.Params(K=cfg.K, T=cfg.T, T_r=cfg.T_r)
    w = np.logspace(math.log10(cfg.w_lo), math.log10(cfg.w_hi), cfg.n_freq)
    curves = {
        name: (w, np.asarray(ship.complementary_sensitivity(p, jnp.exp(th), jnp.asarray(w))))
        for name, th in designs.items()
    }
    fig = figures.line_panels(
        [
            figures.panel(curves, "ω, rad/s", "|T(jω)|", log_y=True, title="complementary sensitivity"),
            figures.panel(
                {
                    "gradient": (np.asarray(g_res.history.sims), np.asarray(g_res.history.best_loss)),
                    "pso": (np.asarray(p_res.history.sims), np.asarray(p_res.history.best_loss)),
                },
                "simulations (loss evaluations)",
                "penalised J1",
                title="equal budgets",
            ),
        ]
    )
    fig.axes[0].set_xscale("log")
    note = (
        f"J1 = max|T| under the sector (α = {cfg.alpha:g}, β = {cfg.beta_deg:g}°), PM ≥ {cfg.pm_min_deg:g}°, "
        f"GM ≥ {cfg.gm_min:g}: hand J1 = {by['hand']['j1_max_T']:.4f} (max violation "
        f"{by['hand']['max_violation']:.3g}), gradient {by['gradient']['j1_max_T']:.4f} (violation "
        f"{by['gradient']['max_violation']:.3g}, PM {by['gradient']['pm_deg']:.1f}°, {int(g_res.n_sims)} sims, a "
        f"gradient counted as {cfg.grad_cost:g}), PSO {by['pso']['j1_max_T']:.4f} (violation "
        f"{by['pso']['max_violation']:.3g}, PM {by['pso']['pm_deg']:.1f}°, {int(p_res.n_sims)} sims). GM is "
        "infinite for a PID on this loop (the phase never crosses −180°)"
    )
    return stages.merge(stages.Stage(metrics=metrics, tables={"designs": rows}, figures={"designs": fig}, notes=[note]))


CLAIMS, ASSUMPTIONS = paper_facts("ship_heading_robust")

STUDY = Study(
    name="ship_heading_robust",
    description="Seed 004 #4: ship-heading PID minimising max|T| under a closed-loop pole sector and "
    "gain/phase margins (jaxsim.lti), gradient vs PSO",
    config=Config,
    presets={
        "quick": dict(grad_steps=80),
        "tiny": dict(grad_steps=10, pso_particles=6, n_freq=100, margin_grid=100, margin_crossings=2),
    },
    claims=CLAIMS,
    assumptions=ASSUMPTIONS,
    run=run,
)
