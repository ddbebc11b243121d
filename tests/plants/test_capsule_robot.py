"""The capsule robot (body + internal mass + Coulomb friction) and its gaits: the exact stick–slip
step against an independent event-resolving NumPy reference, acceleration control against a
fine-step reference, the closed-form optima, the admissible-gait map's constraints, and the gradient
against finite differences."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.control import capsule_gait as cg
from jaxsim.core.dry_friction import catch_up, slide
from jaxsim.plants import capsule_robot as cr

P = cr.Params()
MU = float(cr.mass_ratio(P))
KG = P.k * P.g


def event_reference_velocity_control(u: np.ndarray, dt: float, u_before: float = 0.0):
    """Body [x, w] after each step for relative velocities ``u`` held over steps of ``dt``: an impulse
    −μΔu at each step's start, then Coulomb sliding resolved by its stopping event (plain Python)."""
    x, w, prev, out = 0.0, 0.0, u_before, []
    for ui in u:
        w -= MU * (ui - prev)
        prev = ui
        t_stop = abs(w) / KG
        if t_stop >= dt:
            x += w * dt - np.sign(w) * KG * dt * dt / 2
            w -= np.sign(w) * KG * dt
        else:
            x += w * t_stop / 2
            w = 0.0
        out.append((x, w))
    return np.array(out)


def event_reference_acceleration_control(a: np.ndarray, dt: float):
    """Body [x, w] at the end of each segment of constant relative acceleration ``a`` (the true
    continuous dynamics ẇ = −μa − kg·sgn w, stick when |μa| ≤ kg), every stop resolved exactly."""
    x, w, out = 0.0, 0.0, []
    for ai in a:
        c, t = -MU * ai, dt
        while t > 0:
            if w == 0.0:
                if abs(c) <= KG:
                    break
                acc = c - np.sign(c) * KG  # starts sliding in the push's direction
                x += acc * t * t / 2
                w = acc * t
                t = 0.0
            else:
                acc = c - np.sign(w) * KG
                t_zero = -w / acc if acc * w < 0 else np.inf
                h = min(t, t_zero)
                x += w * h + acc * h * h / 2
                w = 0.0 if h == t_zero else w + acc * h
                t -= h
        out.append((x, w))
    return np.array(out)


def test_dry_friction_slide_and_catch_up():
    d, w = slide(jnp.asarray(2.0), 1.0, 0.5)  # keeps sliding
    assert float(d) == pytest.approx(2.0 * 0.5 - 0.125) and float(w) == pytest.approx(1.5)
    d, w = slide(jnp.asarray(-0.3), 1.0, 0.5)  # stops after 0.3
    assert float(d) == pytest.approx(-0.045) and float(w) == 0.0
    assert float(catch_up(jnp.asarray(0.2), 0.25)) == 0.0  # stick inside the friction bound


def test_step_is_exact_for_piecewise_constant_relative_velocity():
    rng = np.random.default_rng(0)
    u = rng.normal(0.0, 0.4, 200) * np.sqrt(KG * P.L / MU)
    dt = 0.3 * float(cr.time_unit(P))
    ours = np.asarray(cr.rollout(P, jnp.asarray(u), dt))
    ref = event_reference_velocity_control(u, dt)
    scale = float(cr.speed_unit(P))
    np.testing.assert_allclose(ours[:, 1], ref[:, 1], atol=1e-12 * scale)
    np.testing.assert_allclose(ours[:, 0], ref[:, 0], atol=1e-12 * scale * dt * 200)
    assert np.mean(ours[:, 1] == 0.0) > 0.1  # the input makes the body stick often


def test_acceleration_control_converges_to_the_event_resolving_reference():
    """A random piecewise-constant relative acceleration (pushes both below and above the holding
    limit kg/μ): the staircase of u through the plant converges to the exact continuous motion as
    the step shrinks, at first order."""
    rng = np.random.default_rng(1)
    a_seg = rng.uniform(-3.0, 3.0, 20) * KG / MU
    seg = 0.5 * float(cr.time_unit(P))
    ref = event_reference_acceleration_control(a_seg, seg)
    x_err, w_err = [], []
    for sub in (8, 32, 128):
        dt = seg / sub
        a = np.repeat(a_seg, sub)
        u = np.cumsum(a) * dt - a * dt / 2  # the relative velocity at each step's midpoint
        states = np.asarray(cr.rollout(P, jnp.asarray(u), dt))[sub - 1 :: sub]
        x_err.append(np.max(np.abs(states[:, 0] - ref[:, 0])))
        w_err.append(np.max(np.abs(states[:, 1] - ref[:, 1])))
    assert x_err[-1] < 1e-2 * np.max(np.abs(ref[:, 0])) and x_err[-1] < x_err[0] / 5
    assert w_err[-1] < 1e-2 * np.max(np.abs(ref[:, 1]))
    assert w_err[0] / w_err[1] > 3 and w_err[1] / w_err[2] > 3  # first order (×4 per ×4 steps)


def test_three_phase_gait_reaches_the_closed_form_and_the_body_never_backs_up():
    opt = cg.three_phase_optimum(P)
    unit = float(cr.speed_unit(P))
    assert float(opt["speed"]) / unit == pytest.approx(np.sqrt(0.5), rel=1e-12)
    gaps = []
    for n in (64, 256, 1024):
        u, dt = cg.three_phase_gait(P, n)
        assert float(cg.max_acceleration_of(u, dt)) == pytest.approx(float(cr.hold_acceleration(P)), rel=1e-9)
        assert float(cg.stroke_of(u, dt)) == pytest.approx(P.L, rel=1e-12)
        gaps.append(float(opt["speed"] - cr.periodic_speed(P, u, dt)) / unit)
        w = np.asarray(cr.rollout(P, jnp.tile(u, 2), dt, u[-1]))[:, 1]
        assert w.min() >= -1e-12 * unit  # the jumps sit exactly on the holding limit: rounding only
    assert 0 < gaps[2] < gaps[1] < gaps[0] < 0.04
    assert gaps[0] / gaps[2] > 12  # first order in 1/N


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_bounded_acceleration_gait_is_admissible(seed):
    theta = jax.random.normal(jax.random.PRNGKey(seed), (48,)) * 3
    a_max = float(cr.hold_acceleration(P))
    dt = 2.5 * float(cr.time_unit(P)) / 48
    u = cg.bounded_acceleration_gait(theta, a_max, P.L, dt)
    assert abs(float(jnp.sum(u))) < 1e-12 * float(jnp.max(jnp.abs(u)))  # ξ periodic
    assert float(cg.stroke_of(u, dt)) <= P.L * (1 + 1e-12)
    assert float(cg.max_acceleration_of(u, dt)) <= a_max * (1 + 1e-12)
    w = np.asarray(cr.rollout(P, jnp.tile(u, 3), dt, u[-1]))[:, 1]
    assert w.min() >= -1e-12 * float(cr.speed_unit(P))  # the drive never pushes the body backwards


def test_gait_speed_gradient_matches_finite_differences():
    n = 24
    dt = 2.8 * float(cr.time_unit(P)) / n
    a_max = float(cr.hold_acceleration(P))

    def v(theta):
        return cr.periodic_speed(P, cg.bounded_acceleration_gait(theta, a_max, P.L, dt), dt) / cr.speed_unit(P)

    theta = 2.0 * jnp.cos(2 * jnp.pi * jnp.arange(n) / n) + 0.1 * jax.random.normal(jax.random.PRNGKey(3), (n,))
    g = jax.grad(v)(theta)
    direction = jax.random.normal(jax.random.PRNGKey(4), (n,))
    h = 1e-6
    fd = (v(theta + h * direction) - v(theta - h * direction)) / (2 * h)
    assert float(g @ direction) == pytest.approx(float(fd), rel=1e-5, abs=1e-9)
    assert float(jnp.linalg.norm(g)) > 1e-3


def test_resting_two_phase_family_against_the_plant_and_its_limit():
    """u1 = 1, u2 = 2 (mass speed units): the plant on a grid aligned with the phases gives the
    event-exact family value; an instant return gives u1/(1 + u1²) for u1 ≤ 1 and 1/(2·u1) above
    (the back-slide then outlasts the forward phase), at most 1/2 at u1 = 1."""
    unit = float(cr.speed_unit(P))
    scale = float(cr.mass_speed_unit(P))
    tu = float(cr.time_unit(P))
    family = float(cg.resting_two_phase_speed(P, 1.0, 2.0)) / unit
    # natural units: back-slide stops at t = 1 = end of phase 1; the +3 jump slides 0.5 → w = 2.5;
    # the −2 jump leaves 0.5, which stops after 0.5: rest 0.5 → period 2
    n1, n2, n3 = 400, 200, 200
    dt = tu / n1
    u = np.concatenate([np.full(n1, 1.0), np.full(n2, -2.0), np.zeros(n3)]) * scale
    plant = float(cr.periodic_speed(P, jnp.asarray(u), dt, 2)) / unit
    assert plant == pytest.approx(family, rel=1e-9)
    for u1 in (0.3, 1.0, 2.0):
        limit = u1 / (1 + u1**2) if u1 <= 1 else 1 / (2 * u1)
        assert float(cg.resting_two_phase_speed(P, u1, 1e7)) / unit == pytest.approx(limit, rel=1e-5)


def test_symmetric_gait_without_rest_grows_without_bound():
    unit = float(cr.speed_unit(P))
    scale = float(cr.mass_speed_unit(P))
    v = [abs(float(cr.periodic_speed(P, *cg.symmetric_two_phase_gait(P, s * scale, 64), 1))) / unit for s in (1, 4)]
    assert v[1] > 3 * v[0] > 0


def test_without_friction_the_centre_of_mass_stays_put():
    """k → 0: no external force, so M·x + m·(x + ξ) is constant — the body moves by −μ·Δξ, whatever
    the relative velocities (a momentum invariant, independent of the friction step)."""
    p = cr.Params(k=1e-15)
    u = jax.random.normal(jax.random.PRNGKey(5), (300,)) * 0.2
    dt = 0.01
    states = cr.rollout(p, u, dt)
    xi = jnp.cumsum(u) * dt
    np.testing.assert_allclose(np.asarray(states[:, 0]), -float(cr.mass_ratio(p)) * np.asarray(xi), atol=1e-12)


def test_bad_sizes_are_refused_by_name():
    with pytest.raises(ValueError, match="n: must be even"):
        cg.three_phase_gait(P, 63)
    with pytest.raises(ValueError, match="n: must be a positive integer, got 0"):
        cg.symmetric_two_phase_gait(P, 1.0, 0)
    with pytest.raises(ValueError, match="periods: must be a positive integer, got 0"):
        cr.periodic_speed(P, jnp.ones(4), 0.1, 0)
