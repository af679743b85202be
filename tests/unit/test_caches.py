"""The hot loop's caches never return a stale value: an array modified in place gives the numbers
of a fresh array with the same values, or the write raises (the arrays the world creates are
read-only, so a cache keyed by one of them is keyed by its numbers)."""

from __future__ import annotations

import copy
import pickle
from dataclasses import replace

import numpy as np
import pytest
from jets import default_jet

from aerodock.downwash.base import BodyState
from aerodock.downwash.jet import RoundJetField
from aerodock.geometry import rpy_to_rotmat
from aerodock.rng import TrialRNG
from aerodock.world import World
from aerodock.world.gripper import GateState
from aerodock.world.vehicles.autopilot import AutopilotGains, autopilot_constants
from aerodock.world.vehicles.fleet import PointMassFleet
from aerodock.world.vehicles.point_mass import VehicleParams, hover_state
from aerodock.world.vehicles.rigid_body import (
    RigidBodyParams,
    body_wrench,
    hover_rigid_state,
    step_rigid_body,
)

N, DT = 3, 0.002


def _pair(mass: np.ndarray) -> tuple[BodyState, BodyState]:
    """Leaders hovering 0.6 m above followers (a little off the axis, tilted): the wake is felt
    unevenly by the disks (a torque), and the mass matters (the ingest exponent is not 2)."""
    leader = BodyState(np.tile([0.0, 0.0, -2.0], (N, 1)), np.zeros((N, 3)),
                       np.repeat(np.eye(3)[None], N, axis=0), np.full(N, 0.7 * 9.81),
                       np.full(N, 0.7))
    p = np.array([[0.05, 0.0, -1.4], [0.0, -0.08, -1.4], [0.1, 0.1, -1.3]])
    rot = rpy_to_rotmat(np.array([[0.1, 0.0, 0.3], [0.0, -0.05, 0.0], [0.02, 0.03, -1.0]]))
    follower = BodyState(p, np.full((N, 3), 0.1), rot, np.full(N, 0.7 * 9.81), mass)
    return leader, follower


def _field() -> RoundJetField:
    field = default_jet()
    field.reset(N, TrialRNG(3, N))
    return field


def _assert_same(a, b) -> None:
    for x, y in zip(a, b, strict=True):
        np.testing.assert_array_equal(x, y)


@pytest.mark.parametrize("call", ["acceleration", "wrench"])
def test_the_field_after_the_mass_is_changed_in_place(call):
    mass = np.array([0.7, 0.8, 0.65])
    offsets = default_jet().rotor_offsets_body_m

    def run(field, masses):
        out = []
        for m in masses:
            leader, follower = _pair(m)
            if call == "acceleration":
                out.append((field.acceleration(leader, follower, DT),))
            else:
                out.append(field.wrench(leader, follower, offsets, DT))
        return out

    before = mass.copy()
    in_place = _field()
    first = run(in_place, [mass])
    mass *= 1.5
    second = run(in_place, [mass])
    fresh = run(_field(), [before, mass.copy()])
    _assert_same(first[0], fresh[0])
    _assert_same(second[0], fresh[1])


def test_the_field_after_a_parameter_is_changed():
    """The force coefficients are kept for a read-only mass array, and for the field's
    parameters they were computed with."""
    mass = np.array([0.7, 0.8, 0.65])
    mass.flags.writeable = False
    leader, follower = _pair(mass)
    field = _field()
    field.acceleration(leader, follower, DT)
    field.ingest_coeff = 0.3
    changed = field.acceleration(leader, follower, DT)
    fresh = default_jet(ingest_coeff=0.3)
    fresh.reset(N, TrialRNG(3, N))
    fresh.acceleration(leader, follower, DT)
    np.testing.assert_array_equal(changed, fresh.acceleration(leader, follower, DT))


def test_the_wrench_after_the_offsets_are_changed_in_place():
    """The disks' points, torque arms and pair distance (the turbulence's share) follow the
    offsets' numbers."""
    offsets = np.array(default_jet().rotor_offsets_body_m)
    leader, follower = _pair(np.array([0.7, 0.8, 0.65]))
    before = offsets.copy()
    in_place = _field()
    first = in_place.wrench(leader, follower, offsets, DT)
    offsets *= 1.3
    second = in_place.wrench(leader, follower, offsets, DT)
    fresh = _field()
    _assert_same(first, fresh.wrench(leader, follower, before, DT))
    _assert_same(second, fresh.wrench(leader, follower, offsets.copy(), DT))


def test_the_fields_own_offsets_are_read_only():
    with pytest.raises(ValueError):
        default_jet().rotor_offsets_body_m[0, 0] = 0.2


def _gains() -> AutopilotGains:
    return AutopilotGains(np.array([6.0, 6.0, 3.0]), np.array([20.0, 20.0, 10.0]),
                          np.array([5.0, 5.0, 2.0]), 10.0, np.array([3.0, 3.0, 2.0]))


def test_autopilot_constants_after_the_inertia_is_changed_in_place():
    gains, inertia = _gains(), np.array([0.008, 0.008, 0.014])
    autopilot_constants(gains, inertia)
    inertia *= 2.0
    np.testing.assert_array_equal(autopilot_constants(gains, inertia),
                                  autopilot_constants(_gains(), inertia.copy()))


def test_autopilot_constants_after_a_gain_is_changed_in_place():
    gains, inertia = _gains(), np.array([0.008, 0.008, 0.014])
    inertia.flags.writeable = False
    autopilot_constants(gains, inertia)
    rate_p = gains.rate_p
    rate_p *= 2.0
    fresh = replace(_gains(), rate_p=gains.rate_p.copy())
    np.testing.assert_array_equal(autopilot_constants(gains, inertia),
                                  autopilot_constants(fresh, inertia))


def test_the_vehicle_parameters_are_read_only(cfg):
    params = RigidBodyParams.from_config(cfg)
    for array in (params.inertia_kgm2, params.rotor_offsets_m, params.gains.rate_p):
        with pytest.raises(ValueError):
            array *= 2.0


def test_the_point_mass_rotation_after_the_angles_are_changed_in_place(cfg):
    made = hover_state(VehicleParams.from_config(cfg), np.zeros((N, 3)), 0.3)
    state = replace(made, rpy=np.array(made.rpy))  # someone's writable angles
    first = state.R
    state.rpy[1] = [0.1, -0.2, 0.4]
    np.testing.assert_array_equal(state.R, rpy_to_rotmat(state.rpy.copy()))
    np.testing.assert_array_equal(first, rpy_to_rotmat(made.rpy))
    assert not first.flags.writeable  # kept and shared: read-only
    with pytest.raises(ValueError):  # the angles a state is made with are read-only
        made.rpy[0, 0] = 0.1


def test_a_point_mass_on_its_stand_has_the_rotation_of_its_held_angles(cfg):
    fleet = PointMassFleet(VehicleParams.from_config(cfg))
    old = fleet.hover(np.zeros((2 * N, 3)), 0.5, np.ones(2 * N))
    moved = replace(old, rpy=np.full((2 * N, 3), 0.2))
    moved.rpy.flags.writeable = False
    assert moved.R.shape == (2 * N, 3, 3)  # kept for the moved angles
    held = fleet.hovering(moved, old, slice(None, N))
    np.testing.assert_array_equal(held.rpy[:N], old.rpy[:N])
    np.testing.assert_array_equal(held.R, rpy_to_rotmat(held.rpy.copy()))


def _rigid(cfg):
    params = RigidBodyParams.from_config(cfg)
    return params, hover_rigid_state(params, np.zeros((N, 3)), 0.0, np.array([1.0, 0.95, 1.05]))


def test_rigid_body_thrust_after_the_gain_is_changed_in_place(cfg):
    params, made = _rigid(cfg)
    state = replace(made, thrust_gain=np.array(made.thrust_gain))  # someone's writable gains
    command = np.array(state.rotor_speed) * 1.02
    force = np.zeros((N, 3))
    step_rigid_body(state, command, force, None, params, DT)
    gain = state.thrust_gain
    gain *= 1.1
    after, accel = step_rigid_body(state, command, force, None, params, DT)
    fresh, fresh_accel = step_rigid_body(replace(state, thrust_gain=gain.copy()), command, force,
                                         None, params, DT)
    np.testing.assert_array_equal(after.thrust_n, fresh.thrust_n)
    np.testing.assert_array_equal(accel, fresh_accel)
    still = np.zeros((N, 3))
    np.testing.assert_array_equal(
        body_wrench(state.rotor_speed, gain, still, still, params)[0],
        body_wrench(state.rotor_speed, gain.copy(), still, still, params)[0])
    with pytest.raises(ValueError):  # the gains a state is made with are read-only
        made.thrust_gain[0] = 1.1


def test_a_vehicle_body_is_read_only(cfg):
    _, state = _rigid(cfg)
    body = state.body
    for name in ("mass_kg", "mass_rows_kg", "inertia_kgm2", "torque_gain", "motor_tau_s"):
        with pytest.raises(ValueError):
            getattr(body, name)[0] *= 2.0


def _world_state(cfg):
    world = World(cfg, N, TrialRNG(0, N))
    world.reset(np.tile([0.0, 0.0, -2.0], (N, 1)), np.tile([0.0, 0.0, -1.4], (N, 1)))
    return world.state


def test_a_gripper_state_is_read_only(cfg):
    gripper = _world_state(cfg).gripper
    with pytest.raises(ValueError):  # a changed gripper is a new state
        gripper.gate[0] = GateState.CAPTURED
    with pytest.raises(ValueError):
        gripper.servo_start_s[0] = 0.0


def test_the_gripper_flags_after_the_gate_is_changed_in_place(cfg):
    state = _world_state(cfg)
    captured, any_captured, idle = state.gripper_flags()
    assert not any_captured and idle and not captured.flags.writeable
    gate = state.gripper.gate
    gate.flags.writeable = True  # on purpose
    gate[0] = GateState.CAPTURED
    captured, any_captured, idle = state.gripper_flags()
    assert captured.tolist() == [True, False, False] and any_captured and not idle


def test_copies_stay_read_only(cfg):
    """A copied or unpickled field, body or gripper keeps its arrays read-only (a copied array
    is writable): its caches still hold, and in-place writes still raise."""
    state = _world_state(cfg)
    for obj, name in ((default_jet(), "rotor_offsets_body_m"),
                      (state.both.body, "inertia_kgm2"), (state.gripper, "gate")):
        for copied in (copy.deepcopy(obj), pickle.loads(pickle.dumps(obj))):
            assert not getattr(copied, name).flags.writeable, (type(obj).__name__, name)
            np.testing.assert_array_equal(getattr(copied, name), getattr(obj, name))
