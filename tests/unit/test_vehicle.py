"""Vehicle dynamics: hover equilibrium, free fall, NED conventions."""

from __future__ import annotations

import numpy as np

from aerodock.world.vehicles.point_mass import (
    AttitudeCommand,
    VehicleParams,
    hover_state,
    step_vehicle,
)


def _run(params, state, cmd, seconds, dt=0.002):
    for _ in range(int(round(seconds / dt))):
        state, accel = step_vehicle(state, cmd, np.zeros((state.n, 3)), params, dt)
    return state, accel


def test_hover_equilibrium_with_thrust_mg(cfg):
    params = VehicleParams.from_config(cfg)
    state = hover_state(params, np.array([[0.0, 0.0, -2.0]]))
    cmd = AttitudeCommand(np.zeros(1), np.zeros(1), np.zeros(1), np.full(1, params.hover_thrust_n))
    end, accel = _run(params, state, cmd, 3.0)
    assert np.allclose(end.p, [[0.0, 0.0, -2.0]], atol=1e-9)
    assert np.allclose(accel, 0.0, atol=1e-9)
    assert np.isclose(end.thrust_n[0], params.mass_kg * params.gravity_mps2)


def test_free_fall_without_thrust_is_down_in_ned(cfg):
    params = VehicleParams.from_config(cfg.with_overrides({"vehicle": {"drag_coeff_kgps": 0.0,
                                                                       "tau_thrust_s": 1e-6}}))
    state = hover_state(params, np.array([[0.0, 0.0, -10.0]]))
    cmd = AttitudeCommand(np.zeros(1), np.zeros(1), np.zeros(1), np.zeros(1))
    t = 1.0
    end, accel = _run(params, state, cmd, t)
    # z grows (down) by ~g t^2 / 2; thrust decays within a step or two
    assert accel[0, 2] > 0.99 * params.gravity_mps2
    assert abs(end.p[0, 2] - (-10.0 + 0.5 * params.gravity_mps2 * t**2)) < 0.02
    assert np.allclose(end.p[0, :2], 0.0)


def test_frame_conventions(cfg):
    params = VehicleParams.from_config(cfg)
    state = hover_state(params, np.zeros((3, 3)))
    hover = params.hover_thrust_n
    # more thrust -> climbs (z decreases); positive roll (right wing down) -> east (+y);
    # positive pitch (nose up) -> south (-x).
    cmd = AttitudeCommand(np.array([0.0, 0.2, 0.0]), np.array([0.0, 0.0, 0.2]), np.zeros(3),
                          np.array([1.2 * hover, hover / np.cos(0.2), hover / np.cos(0.2)]))
    end, _ = _run(params, state, cmd, 1.0)
    assert end.p[0, 2] < -0.1
    assert end.p[1, 1] > 0.1 and abs(end.p[1, 0]) < 1e-6
    assert end.p[2, 0] < -0.1 and abs(end.p[2, 1]) < 1e-6


def test_inner_loop_respects_tilt_and_thrust_limits(cfg):
    params = VehicleParams.from_config(cfg)
    state = hover_state(params, np.zeros((1, 3)))
    cmd = AttitudeCommand(np.array([3.0]), np.array([-3.0]), np.zeros(1), np.array([1e3]))
    end, _ = _run(params, state, cmd, 1.0)
    assert abs(end.rpy[0, 0]) <= params.tilt_max_rad + 1e-12
    assert abs(end.rpy[0, 1]) <= params.tilt_max_rad + 1e-12
    assert end.thrust_n[0] <= params.thrust_max_n + 1e-9
