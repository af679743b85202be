"""Gripper: captures a bar at rest inside the aperture; a fast bar slips through."""

from __future__ import annotations

import numpy as np

from aerodock.world.gripper import (
    GateState,
    GripperParams,
    bar_in_gripper,
    calibrated_gripper,
    step_gripper,
)


def _fly(params, bar_p0, bar_v, follower_p, seconds=0.4, dt=0.002, active_at=None):
    """Follower fixed; the bar moves at constant velocity (stopped by the arm)."""
    rng = np.random.default_rng(0)
    n = bar_p0.shape[0]
    R = np.repeat(np.eye(3)[None], n, 0)
    state = calibrated_gripper(n, params, rng)
    bar_p = bar_p0.copy()
    for k in range(int(seconds / dt)):
        t = (k + 1) * dt
        bar_p = bar_p + bar_v * dt
        force, inside, _ = bar_in_gripper(follower_p, R, np.zeros((n, 3)), bar_p, bar_v,
                                          np.zeros(n), params)
        sample = int(t * params.sensor_rate_hz + 1e-9) != int((t - dt) * params.sensor_rate_hz
                                                              + 1e-9)
        close = np.full(n, active_at is not None and t >= active_at)
        state = step_gripper(state, t, force, inside, sample, close, params, rng)
    return state


def test_captures_bar_resting_on_the_arm(cfg):
    params = GripperParams.from_config(cfg)
    follower = np.zeros((1, 3))
    arm_z = -params.mount_height_m
    bar = np.array([[0.0, 0.01, arm_z + params.bar_radius_m - 0.002]])  # pressing on the arm
    state = _fly(params, bar, np.zeros((1, 3)), follower)
    assert state.gate[0] == GateState.CAPTURED
    assert state.triggered_by_contact[0]
    assert not state.slipped[0]


def test_fast_bar_slips_through_before_gate_closes(cfg):
    params = GripperParams.from_config(cfg)
    follower = np.zeros((1, 3))
    arm_z = -params.mount_height_m
    # touching the arm, moving sideways at 1 m/s: out of the 5 cm half-aperture in ~50 ms,
    # while sensing (12.5 ms) + latency (15 ms) + gate travel (80 ms) take longer.
    bar = np.array([[0.0, -0.02, arm_z + params.bar_radius_m - 0.002]])
    state = _fly(params, bar, np.array([[0.0, 1.0, 0.0]]), follower)
    assert state.gate[0] == GateState.MISSED
    assert state.slipped[0]


def test_active_trigger_captures_without_contact_and_misses_when_outside(cfg):
    params = GripperParams.from_config(cfg)
    follower = np.zeros((2, 3))
    arm_z = -params.mount_height_m
    bars = np.array([[0.0, 0.0, arm_z - 0.02],  # 2 cm above the arm, inside the gate
                     [0.0, 0.08, arm_z - 0.02]])  # 8 cm to the side: outside the aperture
    state = _fly(params, bars, np.zeros((2, 3)), follower, active_at=0.1)
    assert state.gate[0] == GateState.CAPTURED and not state.triggered_by_contact[0]
    assert state.gate[1] == GateState.MISSED and not state.slipped[1]
    # the gate resolves latency + travel after the command
    assert np.isclose(state.resolved_s[0], 0.1 + params.latency_s + params.close_time_s, atol=0.003)


def test_resting_bias_is_calibrated(cfg):
    params = GripperParams.from_config(cfg)
    state = calibrated_gripper(2000, params, np.random.default_rng(1))
    residual = state.bias_true_n - state.bias_est_n
    assert np.std(state.bias_true_n) > 0.1  # a real bias that would trigger without calibration
    assert np.max(np.abs(residual)) < params.contact_threshold_n / 2


def test_capture_geometry_includes_the_bar_radius_and_a_lower_limit(cfg):
    params = GripperParams.from_config(cfg)
    r = params.bar_radius_m
    half = params.aperture_m / 2
    arm_z = -params.mount_height_m
    R = np.repeat(np.eye(3)[None], 4, 0)  # noqa: N806
    bars = np.array([
        [0.0, half - r - 0.001, arm_z - 0.02],  # whole section inside the mouth
        [0.0, half - r / 2, arm_z - 0.02],  # centre inside the aperture, section is not
        [0.0, 0.0, arm_z - (params.gate_height_m - r / 2)],  # above the closed gate's reach
        [0.0, 0.0, arm_z + 2 * r],  # below the arm: passed under the gripper
    ])
    _, inside, _ = bar_in_gripper(np.zeros((4, 3)), R, np.zeros((4, 3)), bars, np.zeros((4, 3)),
                                  np.zeros(4), params)
    assert inside.tolist() == [True, False, False, False]
