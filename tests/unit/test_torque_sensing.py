"""The follower's torque observations: exact in a noise-free world, free for the default path."""

from __future__ import annotations

import numpy as np
import pytest

from aerodock.rng import TrialRNG
from aerodock.world import World, hover_command


def _world(cfg, n: int = 3, seed: int = 4) -> World:
    world = World(cfg, n, TrialRNG(seed, n))
    leader = np.tile([0.0, 0.0, -3.0], (n, 1))
    offset = np.array([[0.08, 0.0, 0.5], [0.0, -0.12, 0.45], [0.3, 0.3, 0.6]])[:n]
    world.reset(leader, leader + offset)
    return world


def _fly(world: World, periods: int, read_torque: bool) -> list:
    """Open-loop hover commands; the accelerometer every period, the torques if asked."""
    cmd = hover_command(world.vehicle, world.n)
    readings = []
    world.observed_accel()
    if read_torque:
        world.observed_torque()
    for _ in range(periods):
        world.advance(cmd, cmd)
        readings.append(world.observed_accel())
        if read_torque:
            readings.append(world.observed_torque())
    return readings


def test_noise_free_observations_explain_the_wake_torque_exactly(ideal_cfg):
    """No gyro noise or filter and no thrust-gain or inertia error: obs - rotor is the wake
    torque to rounding (the window of the kinematic torque and of the sums line up step for
    step)."""
    quiet = ideal_cfg.with_overrides({"imu": {"gyro_noise_radps": 0.0},
                                      "vehicle": {"thrust_gain_sd": 0.0}})
    world = _world(quiet)
    readings = _fly(world, 30, read_torque=True)[1::2]
    for reading in readings[1:]:
        true = reading.true_wake_nm
        np.testing.assert_allclose(reading.kinematic_nm - reading.rotor_nm, true, atol=1e-9)
    assert np.abs(readings[-1].true_wake_nm[:2, :2]).max() > 0.01  # off-axis: a real torque
    assert readings[-1].body_rates_radps.shape == (3, 3)


def test_a_second_read_in_one_period_is_the_same_reading(cfg):
    world = _world(cfg)
    _fly(world, 3, read_torque=True)
    first, again = world.observed_torque(), world.observed_torque()
    assert first is again


def test_reading_torques_changes_nothing_else(cfg):
    """The torque log draws no random numbers: the world flies bit for bit the same."""
    plain, logged = _world(cfg), _world(cfg)
    accel_plain = _fly(plain, 20, read_torque=False)
    accel_logged = _fly(logged, 20, read_torque=True)[0::2]
    np.testing.assert_array_equal(np.array(accel_plain), np.array(accel_logged))
    for name in ("p", "v", "R", "w", "rotor_speed"):
        np.testing.assert_array_equal(getattr(plain.follower, name),
                                      getattr(logged.follower, name))
    assert plain.state.torque_log is None  # nobody asked: nothing computed


def test_point_mass_worlds_have_no_torque_observations(cfg):
    world = _world(cfg.with_overrides({"vehicle": {"model": "point-mass"}}))
    with pytest.raises(ValueError, match="rigid-body"):
        world.observed_torque()
