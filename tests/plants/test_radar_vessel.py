"""Seed 003's plants: the turning vessel (coordinated-turn geometry) and the 2-D radar plots."""

from __future__ import annotations

import math

import jax
import numpy as np
import pytest

from jaxsim.plants.radar import (
    PAPER_BEARING_RESOLUTION,
    cartesian_covariance,
    measure,
    polar,
    radar,
    radar_sensor,
    scan_times,
)
from jaxsim.plants.vessel_target import vessel_manoeuvre, vessel_state


@pytest.mark.parametrize("speed", [10.0, 20.0])
def test_vessel_turn_is_a_300m_arc_at_constant_speed(speed):
    m = vessel_manoeuvre(speed=speed, turn_radius=300.0, turn_start=45.0, turn_angle=math.pi / 2, heading=0.3)
    t = np.linspace(0.0, 120.0, 2401)
    s = vessel_state(m, t)
    pos = np.asarray(s.position)
    v_fd = np.linalg.norm(np.diff(pos, axis=0), axis=1) / np.diff(t)
    np.testing.assert_allclose(v_fd, speed, rtol=1e-4)  # constant speed, continuous path
    np.testing.assert_allclose(np.linalg.norm(s.velocity, axis=1), speed, rtol=1e-12)
    p0 = np.asarray(vessel_state(m, 45.0).position)
    centre = p0 + 300.0 * np.array([-math.sin(0.3), math.cos(0.3)])  # left turn: centre on the left
    arc = (t >= 45.0) & (t <= 45.0 + 300.0 * (math.pi / 2) / speed)
    np.testing.assert_allclose(np.linalg.norm(pos[arc] - centre, axis=1), 300.0, rtol=1e-12)
    np.testing.assert_allclose(float(m.turn_duration), 300.0 * math.pi / 2 / speed, rtol=1e-12)
    np.testing.assert_allclose(s.heading[-1], 0.3 + math.pi / 2, rtol=1e-12)
    np.testing.assert_array_equal(s.turning, (t > 45.0) & (t < 45.0 + 300.0 * (math.pi / 2) / speed))


def test_noise_free_radar_without_quantisation_returns_the_truth():
    sensor = radar(0.0, 0.0, range_resolution=0.0, bearing_resolution=0.0, position=(100.0, -50.0))
    p = np.array([[-600.0, 8000.0], [3000.0, 4000.0], [-2500.0, -100.0]])
    np.testing.assert_allclose(measure(sensor, jax.random.PRNGKey(0), p), p, rtol=0, atol=1e-9)
    r, b = polar(sensor, p)
    np.testing.assert_allclose(r, np.hypot(p[:, 0] - 100, p[:, 1] + 50), rtol=1e-14)


def test_plots_sit_at_the_centre_of_the_6m_by_0p03deg_resolution_cell():
    sensor = radar(0.0, 0.0)  # the paper's resolutions, no noise
    p = np.array([[-600.0, 8000.0], [1234.5, 6789.1]])
    z = np.asarray(measure(sensor, jax.random.PRNGKey(1), p))
    r, b = np.hypot(z[:, 0], z[:, 1]), np.arctan2(z[:, 1], z[:, 0])
    np.testing.assert_allclose(r / 6.0, np.round(r / 6.0), atol=1e-9)
    np.testing.assert_allclose(b / PAPER_BEARING_RESOLUTION, np.round(b / PAPER_BEARING_RESOLUTION), atol=1e-7)
    r_true, b_true = np.hypot(p[:, 0], p[:, 1]), np.arctan2(p[:, 1], p[:, 0])
    assert np.all(np.abs(r - r_true) <= 3.0 + 1e-9) and np.all(
        np.abs(b - b_true) <= PAPER_BEARING_RESOLUTION / 2 + 1e-12
    )


def test_converted_plot_covariance_matches_sampling_and_closed_form():
    sensor = radar(7.0, 7.0 / 8000.0, range_resolution=0.0, bearing_resolution=0.0)
    p = np.array([0.0, 8000.0])  # bearing 90°: x is cross-range, y is range
    cov = np.asarray(cartesian_covariance(sensor, p))
    np.testing.assert_allclose(cov, np.diag([49.0, 49.0]), atol=1e-9)
    z = np.asarray(measure(sensor, jax.random.PRNGKey(2), np.broadcast_to(p, (40_000, 2))))
    emp = np.cov((z - p).T)
    np.testing.assert_allclose(emp, cov, atol=49.0 * 0.04)  # 40k draws: ~1 % standard error


def test_scan_times_and_sensor_wrapper():
    sensor = radar(period=3.0)
    np.testing.assert_allclose(scan_times(sensor, 120.0), np.arange(41) * 3.0)
    assert radar_sensor(sensor).period == 3.0


@pytest.mark.parametrize("period", [0.0, -3.0, float("nan")])
def test_non_positive_scan_period_raises(period):
    with pytest.raises(ValueError, match="period"):
        radar(period=period)


def test_other_bad_inputs_raise():
    with pytest.raises(ValueError, match="range_std"):
        radar(-1.0)
    with pytest.raises(ValueError, match="position"):
        radar(position=(0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="speed"):
        vessel_manoeuvre(speed=0.0)
    with pytest.raises(ValueError, match="turn_radius"):
        vessel_manoeuvre(turn_radius=-300.0)
