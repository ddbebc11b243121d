"""PIO loop (jaxsim.problem.pio), the corrective device (jaxsim.control.corrective_device) and the pitch
plant (jaxsim.plants.uav_pitch): the delayed linear loop against an exact-ZOH discrete simulation with a
shift-register delay, the device's first harmonic against its closed form, the surrogates, a gradient
against finite differences, bad inputs."""

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg

from jaxsim.control import corrective_device as ncd
from jaxsim.plants import uav_pitch as up
from jaxsim.problem import pio

DT, TAU = 0.005, 0.6


def test_delayed_linear_loop_against_exact_zoh_with_a_shift_register():
    # limits far away: the loop is linear; no device (straight wire)
    plant = dataclasses.replace(up.PitchParams(), rate_limit=1e3, delta_max=1e3)
    k_op, amp, t_final = 0.3, math.radians(5.0), 6.0
    run = jax.jit(lambda k: pio.simulate(plant, ncd.NCDParams(), k, amp, 0.0, t_final=t_final, dt=DT, tau=TAU))(k_op)
    a, b = (np.asarray(m) for m in up.linear_model(plant))
    m = scipy.linalg.expm(np.block([[a, b], [np.zeros((1, 6))]]) * DT)
    ad, bd = m[:5, :5], m[:5, 5]
    d = round(TAU / DT)
    n = round(t_final / DT)
    x, errors, theta = np.zeros(5), [], []
    for k in range(n):
        theta.append(x[2])
        errors.append((amp if k * DT >= 0.5 - 1e-12 else 0.0) - x[2])
        u = k_op * errors[k - d] if k >= d else 0.0
        x = ad @ x + bd * u
    theta = np.array(theta)
    assert np.max(np.abs(theta)) > 0.5 * amp  # the response is under way
    assert np.max(np.abs(np.asarray(run.theta) - theta)) < 1e-6 * amp
    # the delay is exact: the wire output (y = u) is K_op·e shifted by D steps
    assert np.asarray(run.y)[d:] == pytest.approx(k_op * np.asarray(run.error)[:-d], abs=1e-15)
    assert np.all(np.asarray(run.y)[:d] == 0.0)


def test_device_first_harmonic_phase_matches_the_closed_form():
    dev = ncd.NCDParams()
    w = 1.0 / math.sqrt(dev.T1 * dev.T2)  # maximum lead
    phi = float(ncd.lead_phase(dev, w))
    assert math.degrees(phi) == pytest.approx(math.degrees(math.asin(0.09 / 0.11)), rel=1e-12)
    th = np.linspace(0, 2 * np.pi, 4096, endpoint=False)
    t = th / w
    u = np.sin(w * t)
    z = np.sin(w * t - math.atan(w * dev.T1)) / math.hypot(1.0, w * dev.T1)  # steady filter state
    x = np.asarray(ncd.filter_output(dev, z, u))
    assert x == pytest.approx(abs((1 + 1j * w * dev.T2) / (1 + 1j * w * dev.T1)) * np.sin(w * t + phi), abs=1e-12)
    y = np.asarray(ncd.output(dev, z, u))
    b1, a1 = 2 * np.mean(y * np.sin(th)), 2 * np.mean(y * np.cos(th))
    want = math.atan2(2 / np.pi * math.sin(phi) ** 2, 1 - (2 * phi - math.sin(2 * phi)) / np.pi)
    assert math.atan2(a1, b1) == pytest.approx(want, abs=2e-3)
    assert math.atan2(a1, b1) > 0.5 * phi  # a phase lead, of the order of arg W
    # smooth surrogate: close to the exact output away from the switches
    ys = np.asarray(ncd.output(dev, z, u, (1e-4, 1e-4)))
    far = np.abs(x) > 1e-2
    assert np.max(np.abs(ys - y)[far]) < 1e-3


def test_smooth_tuning_loss_gradient_matches_finite_differences():
    prob = pio.tuning_problem(
        up.PitchParams(), 1.0, math.radians(40.0), t_final=3.0, dt=DT, tau=TAU, smooth=(0.01, 0.01)
    )
    p0 = {"k": jnp.asarray(0.8), "T1": jnp.asarray(0.01), "T2": jnp.asarray(0.15)}
    g = jax.jit(jax.grad(prob.loss))(p0)
    f = jax.jit(lambda t2: prob.loss({**p0, "T2": t2}))
    h = 1e-5
    fd = (float(f(0.15 + h)) - float(f(0.15 - h))) / (2 * h)
    assert float(g["T2"]) == pytest.approx(fd, rel=1e-4, abs=1e-9)


def test_bad_inputs_name_the_argument():
    with pytest.raises(ValueError, match="tau"):
        pio.delay_steps(0.6033, DT)
    with pytest.raises(ValueError, match="rate_limit"):
        up.check_params(dataclasses.replace(up.PitchParams(), rate_limit=0.0))
