"""Study ``tilt_rotor_failure``: a tilt-rotor quadcopter returns to base and lands on its two front rotors
(seed 004 part 3, #8, Shavin & Pritykin; spec ``seed004_part3.md`` §2.8).

Plant :mod:`jaxsim.plants.tilt_rotor` (6-DOF rigid body, quaternion attitude, per-rotor tilted thrust and
reaction torque, failure mask, linear drag in wind); controller :mod:`jaxsim.control.tilt_rotor`.  The
paper prints one number — a return-to-base error of at most 25 cm with two working motors — and no
parameter; every physical value is assumed (listed in ``experiments/papers/tilt_rotor_failure.toml``).

Stages:

1. **Trim.** The six equilibrium equations are solved for ``u = [ω_1, ω_4, ϑ_1, ϑ_4]`` and the body's
   roll and pitch (Levenberg–Marquardt, vmapped starts); with the body held level the least residual is
   reported (positive: no level hover exists on two adjacent rotors — the body must pitch).
2. **Design.** Linearisation at the trim (15 error states with the position integral), controllability
   rank, LQR gains and the closed-loop spectrum.
3. **Tuning.** The LQR weights tuned by gradient (through the Riccati solver's implicit derivatives) and by
   a particle swarm on equal budgets, against the return-to-base tracking loss in a nominal wind.
4. **Monte Carlo** of the hand and tuned designs over the start point, the wind and the initial attitude:
   the return-to-base error at the end of the flight (the paper's ≤ 25 cm) and its quantiles.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np

import jaxsim.montecarlo as mc
from experiments import stages
from experiments.runner import Study, StudyResult, paper_facts
from jaxsim.control import tilt_rotor as tc
from jaxsim.core import ClosedLoop, Timing
from jaxsim.core.costs import combine, control_energy, ise, terminal
from jaxsim.core.pytree import replace
from jaxsim.core.rotations import quat_exp, quat_mul
from jaxsim.plants import tilt_rotor as trp
from jaxsim.problem import Param, ParamSpace, Problem, Scenario

WEIGHTS = ("w_position", "w_velocity", "w_attitude", "w_rate", "w_integral", "r_scale")


@dataclass(frozen=True)
class Config:
    # return-to-base flight (assumed: the paper gives no trajectory)
    start: tuple[float, float, float] = (20.0, -15.0, 10.0)  # m, world frame (z up), base at the origin
    t_transit: float = 20.0  # s, level flight to above the base
    t_descent: float = 12.0  # s, descent to the base
    t_hold: float = 3.0  # s after the reference touches down; the error is read at the end
    dt: float = 0.005  # s, RK4 step
    ts: float = 0.01  # s, controller period
    tilt_max_deg: float = 90.0  # servo limit
    omega_max_factor: float = 1.6  # ω_max = factor × two-rotor hover speed
    # nominal wind of the tuning scenario and the Monte-Carlo ranges (assumed)
    wind: tuple[float, float] = (2.0, 1.0)  # m/s
    wind_max: float = 3.0  # m/s, each horizontal component uniform in ±wind_max
    start_offset: float = 5.0  # m, start point uniform in ±start_offset around `start` (x, y)
    tilt0_max: float = 0.1  # rad, initial roll and pitch error uniform in ±tilt0_max
    # hand-set LQR weights (Bryson-like, the design the tuners start from)
    hand_weights: tuple[float, ...] = (1.0, 1.0, 10.0, 1.0, 0.1, 10.0)
    rho_energy: float = 1e-4  # weight of ∫(ω − ω_trim)² in the loss (1/(rad/s)² per m²)
    trim_starts: int = 32
    budget: int = 64
    n_particles: int = 8
    n_starts: int = 1
    learning_rate: float = 0.2
    mc_runs: int = 256
    seed: int = 0


def failed_plant(wind: Any = (0.0, 0.0, 0.0)) -> trp.TiltRotorParams:
    """The vehicle after the aft pair (rotors 2 and 3) failed, in ``wind (3,)`` m/s."""
    return trp.TiltRotorParams(alive=(1.0, 0.0, 0.0, 1.0), wind=wind)


def trim_of(cfg: Config) -> tc.Trim:
    p = failed_plant()
    w = trp.hover_speed(p, 2)
    rng = np.random.default_rng(cfg.seed)
    n = cfg.trim_starts
    starts = np.column_stack([w * rng.uniform(0.7, 1.5, (n, 2)), rng.uniform(-1.6, 1.6, (n, 4))])
    trim = jax.jit(lambda s: tc.hover_trim(p, s, np.deg2rad(cfg.tilt_max_deg)))(jnp.asarray(starts))
    if not np.isfinite(float(trim.cost)):
        raise RuntimeError("no hover equilibrium within the servo limits was found from the trim starts")
    return trim


def weight_matrices(theta: dict[str, Any], omega_hover: float) -> tuple[jax.Array, jax.Array]:
    """``Q (15, 15)`` and ``R (4, 4)`` from the six weights (``R`` in units of ω_hover² and rad²)."""
    blocks = [theta["w_position"], theta["w_velocity"], theta["w_attitude"], theta["w_rate"], theta["w_integral"]]
    q = jnp.diag(jnp.concatenate([jnp.full(3, 1.0) * b for b in blocks]))
    r = theta["r_scale"] * jnp.diag(jnp.array([1 / omega_hover**2, 1 / omega_hover**2, 1.0, 1.0]))
    return q, r


def hand_design(cfg: Config) -> dict[str, jax.Array]:
    """The hand weights as float64 arrays (the tuners' dtype: no second compilation for this design)."""
    return {k: jnp.asarray(v, dtype=jnp.float64) for k, v in zip(WEIGHTS, cfg.hand_weights)}


linearised = jax.jit(lambda trim: tc.linearise(failed_plant(), trim))


def problem_of(cfg: Config, trim: tc.Trim) -> Problem:
    p0 = failed_plant()
    w = trp.hover_speed(p0, 2)
    a, b = linearised(trim)
    hand = dict(zip(WEIGHTS, cfg.hand_weights))
    space = ParamSpace(**{k: Param(lo=v / 100.0, hi=v * 100.0, init=v, log=True) for k, v in hand.items()})
    start = jnp.asarray(cfg.start)
    u_trim_full = tc.full_input(trim.u)
    t_final = cfg.t_transit + cfg.t_descent + cfg.t_hold

    def build(theta: dict[str, Any], d: dict[str, Any]) -> Scenario:
        q, r = weight_matrices(theta, w)
        ctrl = tc.lqr_controller(
            tc.lqr_params(a, b, q, r, trim, cfg.omega_max_factor * w, np.deg2rad(cfg.tilt_max_deg))
        )
        s0 = start + jnp.stack([d["dx"], d["dy"], 0.0])
        path = tc.ReturnPath(
            start=s0, base=jnp.zeros(3), t_transit=cfg.t_transit, t_descent=cfg.t_descent, q_trim=trim.q
        )
        plant = trp.tilt_rotor(replace(p0, wind=jnp.stack([d["wind_x"], d["wind_y"], 0.0])))
        q0 = quat_mul(trim.q, quat_exp(jnp.stack([d["roll0"], d["pitch0"], 0.0])))
        return Scenario(
            ClosedLoop(plant, ctrl, reference=path), tc.hover_state(q0, s0), Timing(t_final, cfg.dt, cfg.ts)
        )

    return Problem(
        "tilt_rotor_return",
        space,
        combine(
            tracking=ise(channels=(0, 1, 2)),
            energy=(cfg.rho_energy, control_energy(offset=u_trim_full[jnp.array([0, 3])], channels=(0, 3))),
            return_error_m=(0.0, terminal(lambda tick: jnp.linalg.norm(tick.y[:3]))),
        ),
        build,
        nominal={"dx": 0.0, "dy": 0.0, "wind_x": cfg.wind[0], "wind_y": cfg.wind[1], "roll0": 0.0, "pitch0": 0.0},
        uncertainty={
            "dx": mc.uniform(-cfg.start_offset, cfg.start_offset),
            "dy": mc.uniform(-cfg.start_offset, cfg.start_offset),
            "wind_x": mc.uniform(-cfg.wind_max, cfg.wind_max),
            "wind_y": mc.uniform(-cfg.wind_max, cfg.wind_max),
            "roll0": mc.uniform(-cfg.tilt0_max, cfg.tilt0_max),
            "pitch0": mc.uniform(-cfg.tilt0_max, cfg.tilt0_max),
        },
    )


def trim_stage(cfg: Config, trim: tc.Trim) -> stages.Stage:
    p = failed_plant()
    w = trp.hover_speed(p, 2)
    rng = np.random.default_rng(cfg.seed + 1)
    level_starts = np.column_stack([w * rng.uniform(0.7, 1.5, (16, 2)), rng.uniform(-1.6, 1.6, (16, 2))])
    level = float(jax.jit(lambda s: tc.level_hover_defect(p, s))(jnp.asarray(level_starts)))
    a, b = linearised(trim)
    ctrb = np.hstack([np.linalg.matrix_power(np.asarray(a), i) @ np.asarray(b) for i in range(a.shape[0])])
    u = np.asarray(trim.u)
    metrics = {
        "trim_omega_rad_s": float(u[0]),
        "trim_omega_ratio_to_4_rotor_hover": float(u[0] / trp.hover_speed(p, 4)),
        "trim_tilt1_deg": float(np.rad2deg(u[2])),
        "trim_tilt4_deg": float(np.rad2deg(u[3])),
        "trim_roll_deg": float(np.rad2deg(trim.roll)),
        "trim_pitch_deg": float(np.rad2deg(trim.pitch)),
        "trim_residual": float(trim.cost),
        "level_hover_least_residual": level,
        "controllability_rank": float(np.linalg.matrix_rank(ctrb, tol=1e-9 * np.linalg.norm(ctrb))),
    }
    return stages.Stage(
        metrics=metrics,
        tables={"trim": [{k: v for k, v in metrics.items()}]},
        notes=[
            f"hover on rotors 1 and 4: ω = {u[0]:.1f} rad/s ({metrics['trim_omega_ratio_to_4_rotor_hover']:.3f}× "
            f"the four-rotor hover speed), tilts ±{abs(metrics['trim_tilt1_deg']):.2f}°, body pitched "
            f"{metrics['trim_pitch_deg']:.2f}° (Levenberg–Marquardt, residual {float(trim.cost):.1e})",
            f"with the body held level the least residual is {level:.3g} (m/s²)² + (rad/s²)²: no level hover "
            "exists — the front thrust's pitch moment is cancelled only by tilting the rotors and pitching the body",
        ],
    )


def run(cfg: Config, progress: Callable[..., Any]) -> StudyResult:
    trim = trim_of(cfg)
    trim_st = trim_stage(cfg, trim)
    problem = problem_of(cfg, trim)
    hand = hand_design(cfg)
    key = jax.random.PRNGKey(cfg.seed)
    tuned = stages.tune_and_compare(
        problem,
        cfg.budget,
        ("gradient", "pso"),
        key=key,
        learning_rate=cfg.learning_rate,
        n_starts=cfg.n_starts,
        n_particles=cfg.n_particles,
        progress=progress,
        loss_label="J = ∫‖r − r_ref‖² dt + ρ∫(ω − ω_trim)² dt (m²·s)",
    )
    designs = {"hand": hand, **tuned.designs}
    # jitted: an eager evaluate compiles its rollout's scan afresh on every call (0.6–0.9 s each)
    nominal = {name: float(problem.jitted.evaluate(prm).terms["return_error_m"]) for name, prm in designs.items()}
    steps = stages.responses(problem, designs, y_label="x position, m", title="return to base (x), nominal wind")
    robust = stages.robustness(
        problem, designs, cfg.mc_runs, cfg.seed, y_label="x position, m", channel=0, progress=progress
    )
    metrics = {f"return_error_nominal_{k}": v for k, v in nominal.items()}
    metrics["loss_ratio_gradient_to_pso"] = tuned.metrics["loss_gradient"] / tuned.metrics["loss_pso"]
    metrics["loss_ratio_gradient_to_hand"] = tuned.metrics["loss_gradient"] / float(problem.jitted.loss(hand))
    return stages.merge(trim_st, tuned, steps, robust, metrics=metrics)


CLAIMS, ASSUMPTIONS = paper_facts("tilt_rotor_failure")

STUDY = Study(
    name="tilt_rotor_failure",
    description="Seed 004 #8 (part 3): tilt-rotor quadcopter after the aft motors fail — trim on two "
    "rotors by Newton, LQR with integral action, weights by gradient vs PSO, return-to-base Monte Carlo",
    config=Config,
    presets={
        "quick": dict(budget=24, mc_runs=64),
        "tiny": dict(
            start=(4.0, -3.0, 4.0),
            t_transit=4.0,
            t_descent=3.0,
            t_hold=1.0,
            dt=0.01,
            start_offset=1.0,
            trim_starts=8,
            budget=4,
            n_particles=2,
            mc_runs=8,
        ),
    },
    claims=CLAIMS,
    assumptions=ASSUMPTIONS,
    run=run,
)
