"""The flight computer's IMU chain and attitude estimate (filtered chain)."""

from __future__ import annotations

import numpy as np
import pytest

from aerodock.geometry import euler_to_rotmat
from aerodock.rng import TrialRNG
from aerodock.world import World, hover_command
from aerodock.world.attitude_estimator import AttitudeEstimatorParams, estimate_step
from aerodock.world.imu import Biquad, FilterState, filter_sample

G = 9.81
DT = 0.002


def _tilt_deg(rot: np.ndarray) -> np.ndarray:
    return np.degrees(np.arccos(np.clip(rot[:, 2, 2], -1.0, 1.0)))


def test_biquad_is_a_butterworth_low_pass():
    """DC passes unchanged, the cut-off is 3 dB down, ten times the cut-off about 40 dB."""
    quad = Biquad.butterworth(20.0, DT)
    t = np.arange(4000) * DT

    def gain(freq_hz: float) -> float:
        sig = np.sin(2 * np.pi * freq_hz * t)[None, :].repeat(3, 0)
        state = FilterState.at(np.zeros((3, 1)), quad, 0)
        out = np.array([filter_sample(state, sig[:, k:k + 1], quad)[0, 0] for k in range(t.size)])
        return float(np.max(np.abs(out[2000:])))

    assert gain(0.5) == pytest.approx(1.0, abs=0.01)
    assert gain(20.0) == pytest.approx(1 / np.sqrt(2), abs=0.02)
    assert gain(200.0) < 0.02
    assert Biquad.butterworth(0.0, DT) is None  # a cut-off of 0: no filter
    # Settled at a constant it stays there; the delay line delays.
    state = FilterState.at(np.full((3, 2), 4.0), quad, 0)
    np.testing.assert_allclose(filter_sample(state, np.full((3, 2), 4.0), quad), 4.0)
    state = FilterState.at(np.full((3, 2), 4.0), None, 2)
    assert np.all(filter_sample(state, np.full((3, 2), 5.0), None) == 4.0)
    assert np.all(filter_sample(state, np.full((3, 2), 5.0), None) == 4.0)  # two steps late
    assert np.all(filter_sample(state, np.full((3, 2), 5.0), None) == 5.0)


def test_estimate_converges_to_the_gravity_the_accelerometer_sees():
    """At rest, an estimate 5 degrees off levels at the correction gain's rate (1/k_p)."""
    params = AttitudeEstimatorParams(accel_gain_radps=0.5, heading_gain_radps=0.0)
    truth = euler_to_rotmat(np.zeros(1), np.zeros(1), np.zeros(1))
    est = euler_to_rotmat(np.deg2rad([5.0]), np.zeros(1), np.zeros(1))
    force = -G * truth[:, 2, :].T  # R^T (-g e3)
    errors = []
    for _ in range(int(4.0 / DT)):  # two time constants
        est = estimate_step(est, np.zeros((3, 1)), force, np.zeros((1, 3)), np.zeros(1), params,
                            DT)
        errors.append(_tilt_deg(est)[0])
    assert errors[int(2.0 / DT)] == pytest.approx(5.0 * np.exp(-1.0), rel=0.05)
    assert errors[-1] == pytest.approx(5.0 * np.exp(-2.0), rel=0.05)
    np.testing.assert_allclose(np.einsum("nij,nik->njk", est, est)[0], np.eye(3), atol=1e-12)


def test_the_navigations_acceleration_keeps_a_push_from_reading_as_a_tilt():
    """A level vehicle pushed sideways at 2 m/s^2 (a specific force the accelerometer reads):
    without the navigation's acceleration the estimate tilts towards it (as Mahony's filter
    does); with it, it stays level."""
    params = AttitudeEstimatorParams(accel_gain_radps=0.4, heading_gain_radps=0.0)
    level = euler_to_rotmat(np.zeros(1), np.zeros(1), np.zeros(1))
    push = np.array([[0.0, 2.0, 0.0]])  # world NED acceleration, east
    force = (level.transpose(0, 2, 1) @ (push - [0.0, 0.0, G])[:, :, None])[:, :, 0].T
    tilted, aided = level.copy(), level.copy()
    for _ in range(int(1.0 / DT)):
        tilted = estimate_step(tilted, np.zeros((3, 1)), force, np.zeros((1, 3)), np.zeros(1),
                               params, DT)
        aided = estimate_step(aided, np.zeros((3, 1)), force, push, np.zeros(1), params, DT)
    expected = np.degrees(np.arctan(2.0 / G)) * (1 - np.exp(-0.4))
    assert _tilt_deg(tilted)[0] == pytest.approx(expected, rel=0.1)
    assert _tilt_deg(aided)[0] < 1e-6


def test_a_vehicle_flies_on_its_estimate_and_the_estimate_follows_it(cfg):
    """Hovering on the filtered chain: the autopilot holds the vehicle level on its estimate,
    which stays within a fraction of a degree of the truth."""
    c = cfg.with_overrides({"imu": {"chain": "filtered"}})
    world = World(c, 8, TrialRNG(4, 8))
    world.reset(np.array([0.0, 0.0, -3.0]), np.array([4.0, 0.0, -3.0]))
    assert world.state.imu is not None
    lead = hover_command(world.params.leader_vehicle, world.n)
    fol = hover_command(world.params.vehicle, world.n)
    err = []
    for _ in range(1500):  # 3 s
        world.step(lead, fol)
        d = np.einsum("nij,nik->njk", world.state.imu.attitude[8:], world.follower.R)
        err.append(np.degrees(np.arccos(np.clip((np.trace(d, axis1=1, axis2=2) - 1) / 2, -1,
                                                1))))
    assert np.max(err) < 1.0
    assert np.all(_tilt_deg(world.follower.R) < 2.0)
    # The accelerometer reads about gravity's reaction plus the bias and the filtered noise.
    assert np.all(np.abs(world.observed_accel()) < 1.0)


def test_readings_clip_at_the_range(cfg):
    """A rate beyond the gyro's range reads as the range."""
    c = cfg.with_overrides({"imu": {"chain": "filtered", "gyro_range_dps": 100.0,
                                    "gyro_cutoff_hz": 0.0, "latency_s": 0.0}})
    world = World(c, 1, TrialRNG(0, 1))
    world.reset(np.array([0.0, 0.0, -3.0]), np.array([4.0, 0.0, -3.0]))
    from dataclasses import replace
    world.follower = replace(world.follower, w=np.array([[0.0, 0.0, np.deg2rad(300.0)]]))
    world.step(hover_command(world.params.leader_vehicle, 1),
               hover_command(world.params.vehicle, 1))
    assert world.state.imu.gyro_radps[1, 2] == pytest.approx(np.deg2rad(100.0))
