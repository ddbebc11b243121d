"""Servo drive of joint 2: coupling against an independent Lagrangian, the reduced model identity, the loop."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxsim.estimation.reduced_order_smo import reduced_order_smo
from jaxsim.plants import servo_drive as sd

P = sd.ServoParams()


def _rot_z(a):
    c, s = jnp.cos(a), jnp.sin(a)
    return jnp.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _rot_y(a):
    c, s = jnp.cos(a), jnp.sin(a)
    return jnp.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def lagrangian(q, qd):
    """Independent oracle: L = T − V from forward kinematics of the RRR arm (frames, no closed forms)."""
    a = P.arm

    def bodies(q):
        r1 = _rot_z(q[0])
        r2 = r1 @ _rot_y(-q[1])
        r3 = r1 @ _rot_y(-(q[1] + q[2]))
        base = jnp.array([0.0, 0.0, a.l1])
        elbow = base + r2 @ jnp.array([a.l2, 0.0, 0.0])
        return [  # (rotation, centre of mass, mass, inertia in the body frame: x = longitudinal)
            (r1, base, 0.0, jnp.diag(jnp.array([0.0, 0.0, a.Js1]))),
            (r2, base + r2 @ jnp.array([a.lc2, 0.0, 0.0]), a.m2, jnp.diag(jnp.array([a.Js2, a.Jn2, a.Jn2]))),
            (r3, elbow + r3 @ jnp.array([a.lc3, 0.0, 0.0]), a.m3, jnp.diag(jnp.array([a.Js3, a.Jn3, a.Jn3]))),
            (r3, elbow + r3 @ jnp.array([a.l3, 0.0, 0.0]), a.m_load, jnp.zeros((3, 3))),
        ]

    _, tangents = jax.jvp(bodies, (q,), (qd,))
    T = V = 0.0
    for (R, c, m, I), (dR, dc, _, _) in zip(bodies(q), tangents):
        w_hat = dR @ R.T
        w = jnp.array([w_hat[2, 1], w_hat[0, 2], w_hat[1, 0]])
        T = T + 0.5 * m * dc @ dc + 0.5 * w @ (R @ I @ R.T) @ w
        V = V + m * a.g * c[2]
    return T - V


@jax.jit
def joint_torques(q, qd, qdd):
    dl_dqd = jax.grad(lagrangian, argnums=1)
    return (
        jax.jacfwd(dl_dqd, argnums=1)(q, qd) @ qdd
        + jax.jacfwd(dl_dqd, argnums=0)(q, qd) @ qd
        - jax.grad(lagrangian, argnums=0)(q, qd)
    )


@pytest.mark.parametrize("t, q2, dq2, ddq2", [(0.3, 0.2, 0.7, -1.3), (1.7, -0.9, -0.4, 2.0), (4.2, 1.1, 0.0, 0.5)])
def test_coupling_matches_lagrangian_of_the_arm(t, q2, dq2, ddq2):
    m = P.motion
    q = jnp.array([m.a1 * np.sin(m.w1 * t), q2, m.a3 * np.sin(m.w3 * t)])
    qd = jnp.array([m.a1 * m.w1 * np.cos(m.w1 * t), dq2, m.a3 * m.w3 * np.cos(m.w3 * t)])
    qdd = jnp.array([-m.a1 * m.w1**2 * np.sin(m.w1 * t), ddq2, -m.a3 * m.w3**2 * np.sin(m.w3 * t)])
    c = sd.coupling(P, jnp.asarray(q2), jnp.asarray(t))
    tau2 = float(joint_torques(q, qd, qdd)[1])
    assert float(c.H * ddq2 + c.h * dq2 + c.M) == pytest.approx(tau2, rel=1e-10, abs=1e-10)


def test_h_is_the_time_derivative_of_H():
    t, e = 1.234, 1e-6
    H = lambda tt: float(sd.inertia(P, jnp.asarray(tt))[0])  # noqa: E731
    assert float(sd.inertia(P, jnp.asarray(t))[1]) == pytest.approx((H(t + e) - H(t - e)) / (2 * e), rel=1e-7)


def test_rest_state_and_fault_torque():
    x0 = sd.initial_state(P, 0.3)
    acc = sd.dynamics(P, x0, jnp.array([x0[2] * P.drive.R_m / P.drive.k_y]), jnp.asarray(0.0))
    np.testing.assert_allclose(acc, 0.0, atol=1e-12)
    x = jnp.array([0.1, -20.0, 3.0])
    assert float(sd.fault_torque(P, x, jnp.asarray(2.99))) == 0.0
    assert float(sd.fault_torque(P, x, jnp.asarray(3.0))) == pytest.approx(0.5 * 0.005 * 20.0 + 0.5 * 0.02)


def test_reduced_model_is_an_exact_identity_along_any_motion():
    """ż of the true canonical state (by jvp) equals F z + r(t, y, u, z2) + D d: φ cancels the speed."""
    model = sd.reduced_model()
    rng = np.random.default_rng(1)
    for _ in range(5):
        x = jnp.asarray(rng.normal(size=3) * np.array([0.5, 50.0, 5.0]))
        t, u = jnp.asarray(rng.uniform(0.0, 6.0)), jnp.asarray(rng.normal(size=1) * 0.1)
        xdot = sd.dynamics(P, x, u, t)
        _, zdot = jax.jvp(lambda xx, tt: sd.reduced_state(P, xx, tt), (x, t), (xdot, jnp.ones(())))
        z, y = sd.reduced_state(P, x, t), sd.output(P, x)
        r1, r2 = model.known(model.params, t, y, u, z[1:])
        d = sd.fault_torque(P, x, t) / sd.total_inertia(P, t)
        rhs = jnp.concatenate(
            [
                jnp.reshape(model.F1 * z[0] + model.F2 @ z[1:] + r1 + model.D1 * d, (1,)),
                model.F3 * z[0] + model.F4 @ z[1:] + r2 + model.D2 * d,
            ]
        )
        np.testing.assert_allclose(zdot, rhs, rtol=1e-10, atol=1e-10)


def test_bad_parameters_and_unstable_coordinate_gain():
    with pytest.raises(ValueError, match="L_m"):
        sd.servo_drive_plant(sd.ServoParams(drive=sd.DriveParams(L_m=0.0)))
    with pytest.raises(ValueError, match="F4"):
        reduced_order_smo(sd.reduced_model(sd.ObserverModelParams(Q=0.5)))
