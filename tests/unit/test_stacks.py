"""The flight stacks' autopilots (aerodock/world/vehicles/stacks.py, stack_kernel.py): their
published parameters bound to SI, ArduPilot's square-root controller, and each stack flying its
own vehicle: hover, a roll step, a constant torque trimmed out, a batch equal to its trials."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from aerodock.config import load_config
from aerodock.world.vehicles import stack_kernel
from aerodock.world.vehicles.point_mass import AttitudeCommand
from aerodock.world.vehicles.rigid_body import (
    RigidBodyParams,
    hover_rigid_state,
    step_with_autopilot,
)
from aerodock.world.vehicles.targets import rigid_targets

DT = 0.002
EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
# each stack on the vehicle it was published for
FLOWN = [("arducopter", None), ("crazyflie-pid", EXAMPLES / "crazyflie.toml"),
         ("crazyflie-sjc", EXAMPLES / "crazyflie.toml")]


def _params(stack: str, path: Path | None) -> RigidBodyParams:
    cfg = load_config(path).with_overrides({"autopilot": {"stack": stack}}, source="test")
    return RigidBodyParams.from_config(cfg)


def _rows(params: RigidBodyParams) -> np.ndarray:
    return params.stack_constants[:45].reshape(15, 3)


def test_arducopter_gains_in_si():
    """ATC_RAT_RLL_P 0.135 mixer units per rad/s is 0.135 sqrt(2) L T_max N m per rad/s (QUAD
    X: four motors at L / sqrt(2), each +-0.5 T_max at full command); yaw through 2 Q_max; the
    angle loop's acceleration limit half of ATC_ACCEL_R_MAX (1100 deg/s^2), clipped to 720."""
    cfg = load_config()
    p = _params("arducopter", None)
    arm = cfg.vehicle.diagonal_m / 2
    t_max = cfg.vehicle.thrust_max_g * cfg.vehicle.mass_kg * cfg.sim.gravity_mps2 / 4
    full = math.sqrt(2) * arm * t_max
    rows = _rows(p)
    assert rows[4, 0] == pytest.approx(0.135 * full)
    assert rows[4, 2] == pytest.approx(0.18 * 2 * cfg.vehicle.rotor_torque_ratio_m * t_max)
    assert rows[6, 0] == pytest.approx(0.0036 * full)
    assert rows[7, 0] == pytest.approx(0.5 / 0.135)  # IMAX over KI: the integral's limit, rad
    assert math.degrees(rows[1, 0]) == pytest.approx(550.0)
    assert math.degrees(rows[1, 2]) == pytest.approx(120.0)  # yaw: 135 clipped to 120
    assert p.stack_constants[45] == 0.15
    assert p.autopilot_state_columns == stack_kernel.STATE_COLUMNS


def test_crazyflie_pid_gains_in_si():
    """The firmware's rate KP 250 command units per deg/s: a unit is 0.12 / 65535 N on a motor,
    the legacy mixer adds roll / 2 to each, four motors at 0.046 / sqrt(2) m: 1.706e-3 N m per
    rad/s on the stock Crazyflie 2.1 (the figure worked by hand from the firmware's sources)."""
    rows = _rows(_params("crazyflie-pid", EXAMPLES / "crazyflie.toml"))
    assert rows[4, 0] == pytest.approx(1.706e-3, rel=2e-3)
    assert rows[0, 0] == 6.0 and rows[2, 0] == 3.0
    assert rows[11].tolist() == [1.0, 1.0, 1.0]  # D on the gyro
    # the output saturates at 32767 units: 3.90e-3 N m
    assert rows[13, 0] == pytest.approx(32767 / (250 * 180 / math.pi) * rows[4, 0], rel=1e-9)
    assert rows[13, 0] == pytest.approx(3.90e-3, rel=2e-3)


def test_generic_autopilot_has_no_stack():
    p = RigidBodyParams.from_config(load_config().with_overrides(
        {"autopilot": {"stack": "generic"}}))
    assert p.stack_constants is None and p.autopilot_state_columns == 3


@pytest.mark.parametrize("accel", [0.0, 9.6])
def test_sqrt_controller_as_ardupilot(accel):
    """Linear within accel / p^2 of the target; beyond it the rate a constant deceleration stops
    at the target from, continuous at the knee."""
    p = 4.5
    knee = accel / p**2 if accel else math.inf
    for e in (-2.0, -0.3, -0.01, 0.0, 0.02, 0.4, 1.5):
        got = stack_kernel.sqrt_controller(e, p, accel)
        if abs(e) <= knee:
            assert got == pytest.approx(p * e)
        else:
            assert got == pytest.approx(math.copysign(math.sqrt(2 * accel * (abs(e) - knee / 2)),
                                                      e))
    if accel:
        below = stack_kernel.sqrt_controller(knee * (1 - 1e-9), p, accel)
        above = stack_kernel.sqrt_controller(knee * (1 + 1e-9), p, accel)
        assert above == pytest.approx(below, rel=1e-6)


def _fly(params, state, cmd, seconds, torque=None):
    n = state.n
    for k in range(int(round(seconds / DT))):
        if k % 5 == 0:
            targets = rigid_targets(cmd, state, params, n)
        state, _ = step_with_autopilot(state, targets, np.zeros((n, 3)), torque, params, DT)
    return state


def _cmd(params, n, roll=0.0):
    hover = params.hover_thrust_n / math.cos(roll)
    return AttitudeCommand(np.full(n, roll), np.zeros(n), np.zeros(n), np.full(n, hover))


@pytest.mark.parametrize("stack, path", FLOWN)
def test_stack_hovers_follows_a_step_and_trims_a_torque(stack, path):
    """Level hover is an equilibrium; a 5 deg roll step is reached within 10 % in a second and
    5 % in three, without more than 20 % overshoot (the Crazyflie PID's attitude integral
    settles at KI / KP = 0.5 per second); a constant torque that tilts the vehicle at first is
    trimmed out by the integrators."""
    p = _params(stack, path)
    state = hover_rigid_state(p, np.zeros((1, 3)), 0.0, np.ones(1))
    level = _fly(p, state, _cmd(p, 1), 1.0)
    assert np.allclose(level.rpy, 0.0, atol=1e-9) and np.allclose(level.p, 0.0, atol=1e-9)
    step = math.radians(5.0)
    roll = []
    s = state
    for _ in range(300):  # 3 s in 10 ms pieces
        s = _fly(p, s, _cmd(p, 1, step), 0.01)
        roll.append(s.rpy[0, 0])
    roll = np.asarray(roll)
    assert abs(roll[99] - step) < 0.1 * step, roll[99]
    assert abs(roll[-1] - step) < 0.05 * step, roll[-1]
    assert roll.max() < 1.2 * step
    torque = np.array([[0.05 * p.mass_kg * 9.81 * p.rotor_offsets_m[0, 0], 0.0, 0.0]])
    early = _fly(p, state, _cmd(p, 1), 0.1, torque)
    late = _fly(p, early, _cmd(p, 1), 4.0, torque)
    assert early.rpy[0, 0] > 1e-3
    assert abs(late.rpy[0, 0]) < 0.1 * early.rpy[0, 0]


@pytest.mark.parametrize("stack, path", FLOWN)
def test_a_batch_flies_as_its_trials(stack, path):
    """Each vehicle's numbers in a batch of three are those it has flown alone, to the bit."""
    p = _params(stack, path)
    rolls = np.array([0.05, -0.1, 0.02])
    batch = _fly(p, hover_rigid_state(p, np.zeros((3, 3)), 0.0, np.ones(3)),
                 AttitudeCommand(rolls, np.zeros(3), np.full(3, 0.1),
                                 np.full(3, p.hover_thrust_n)), 0.3)
    for i in range(3):
        alone = _fly(p, hover_rigid_state(p, np.zeros((1, 3)), 0.0, np.ones(1)),
                     AttitudeCommand(rolls[i:i + 1], np.zeros(1), np.full(1, 0.1),
                                     np.full(1, p.hover_thrust_n)), 0.3)
        assert np.array_equal(batch.R[i], alone.R[0])
        assert np.array_equal(batch.autopilot_state[i], alone.autopilot_state[0])


def test_the_leader_flies_its_own_autopilot(tmp_path):
    """``[leader_autopilot]`` sets the leader's stack and gains alone (a stack's gains are a
    vehicle type's); its values are checked as ``[autopilot]``'s, named as the leader's."""
    from aerodock.config import ConfigError
    from aerodock.world.params import WorldParams

    path = tmp_path / "cf.toml"
    path.write_text((EXAMPLES / "crazyflie.toml").read_text()
                    + '\n[leader_autopilot]\nstack = "crazyflie-pid"\n')
    cfg = load_config(path)
    assert cfg.leader_differs
    assert cfg.autopilot.stack == "crazyflie-sjc" and cfg.leader_autopilot.stack == "crazyflie-pid"
    world = WorldParams.from_config(cfg)
    lead, fol = world.leader_fleet.params, world.follower_fleet.params
    assert _rows(lead)[11].tolist() == [1.0, 1.0, 1.0]  # the PID's D on the gyro
    assert _rows(fol)[4].tolist() == [2.0e-3, 2.0e-3, 1.0e-3]  # SJC's K, the small type's
    # the SJC firmware's mixer clips each rotor on its own; the PID flies the world's
    assert fol.stack_constants[46] == 1.0 and lead.stack_constants[46] == 0.0
    assert lead.autopilot_state_columns == fol.autopilot_state_columns \
        == stack_kernel.STATE_COLUMNS
    # a generic leader beside a stack's follower: the pair's halves are joined after every
    # step, so both keep the wider state
    mixed = load_config(path).with_overrides({"leader_autopilot": {"stack": "generic"}})
    world = WorldParams.from_config(mixed)
    assert world.leader_fleet.params.stack_constants is None
    assert world.leader_fleet.params.autopilot_state_columns == stack_kernel.STATE_COLUMNS
    from aerodock.mission import MissionSpec, run_campaign

    result = run_campaign(cfg, MissionSpec(trials=2, seed=1))
    assert result.success.shape == (2,) and not result.nan_state.any()
    path.write_text('[leader_autopilot]\nsjc_lambda = [1.0, 2.0]\n')
    with pytest.raises(ConfigError, match="'leader_autopilot.sjc_lambda' must be 3 numbers"):
        load_config(path)
    path.write_text('[leader_autopilot]\nstack = "px4"\n')
    with pytest.raises(ConfigError, match="'leader_autopilot.stack' must be one of"):
        load_config(path)


def test_sjc_holds_station_with_its_own_mixer():
    """The Crazyflie world's SJC followers, drawn from the world's spread and flown on the
    filtered IMU chain, hold station in free air: with the world's attitude-first mixer instead
    of the firmware's (each rotor clipped on its own) a quarter of them fell into a limit cycle
    that took the collective with them (docs/world.md, "The autopilots")."""
    from aerodock.control.controller import PositionController, Reference
    from aerodock.downwash import build_field
    from aerodock.mission.settle import reset_controllers
    from aerodock.rng import TrialRNG
    from aerodock.world import World

    n = 8
    cfg = load_config(EXAMPLES / "crazyflie.toml")
    assert cfg.autopilot.stack == "crazyflie-sjc"
    world = World(cfg, n, TrialRNG(0, n), field=build_field(cfg))
    lead_p, fol_p = np.tile([0.0, 0.0, -2.5], (n, 1)), np.tile([3.0, 0.0, -2.5], (n, 1))
    world.reset(lead_p, fol_p)
    ctls = [PositionController(cfg, n, use_observer=True) for _ in range(2)]
    reset_controllers(world, *ctls)
    zero = np.zeros((n, 3))
    refs = [Reference(p, zero, zero, np.zeros(n), np.zeros(n)) for p in (lead_p, fol_p)]
    for _ in range(200):  # 2 s
        obs = world.observe()
        world.advance(*(c.step(o.p, o.v, o.rpy, r).command for c, o, r in zip(ctls, obs, refs)))
    assert np.linalg.norm(world.follower.p - fol_p, axis=1).max() < 0.1
