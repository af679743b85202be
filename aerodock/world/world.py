"""The simulated world as one object: N trials of two quadrotors, the wake, the bar, the gripper.

A thin facade over the pieces of :mod:`aerodock.world`: the constants bound once
(:class:`~aerodock.world.params.WorldParams`), the batch state
(:class:`~aerodock.world.state.WorldState`), the step (the named terms of
:data:`aerodock.world.step.WORLD_STEP`) and the sensors (:mod:`aerodock.world.sensors`).

Batch-first and fixed-step: :meth:`World.step` advances N independent trials by one physics step
(``1 / sim.physics_rate_hz``); controllers run outside, every ``substeps`` steps, and see the world
only through :meth:`World.observe` (motion capture with noise and latency), :meth:`World.
observed_accel` (the follower's IMU) and :meth:`World.observed_torque` (its gyro and rotor-speed
torques). All randomness comes from the generator given to the constructor: same config and
seed, same numbers.
"""

from __future__ import annotations

import copy
from dataclasses import replace
from typing import Any

import numpy as np

from aerodock.config import Config
from aerodock.downwash import BodyState, DownwashField, build_field
from aerodock.downwash.mean import mean_acceleration_fn
from aerodock.frozen import freeze
from aerodock.rng import TrialRNG
from aerodock.rows import as_rows
from aerodock.world import sensors
from aerodock.world.gripper import (
    GateState,
    GripperParams,
    GripperState,
    calibrated_gripper,
)
from aerodock.world.imu import start_imu
from aerodock.world.params import WorldParams
from aerodock.world.period import STOP_DRAWS, STOP_UNCOVERED, covered, run_period, runs_step
from aerodock.world.platform import BarState, PlatformParams, anchor_point, hanging_bar
from aerodock.world.sensors import Observation
from aerodock.world.state import AccelWindow, BatchConstants, WorldState
from aerodock.world.step import WORLD_STEP, Term, step_world
from aerodock.world.terms import snapshot
from aerodock.world.torque_sensing import TorqueReading
from aerodock.world.vehicles.body import draw_body
from aerodock.world.vehicles.fleet import Fleet, PointMassFleet, RigidBodyFleet
from aerodock.world.vehicles.point_mass import AttitudeCommand, VehicleParams, VehicleState


class World:
    """N trials of the two-vehicle docking world.

    Args:
        cfg: configuration (``[vehicle] model`` chooses rigid-body or point-mass vehicles); its
            constants are bound once, here.
        n: number of trials.
        rng: the only source of randomness; a :class:`aerodock.rng.TrialRNG` makes every trial's
            numbers independent of the batch size.
        field: downwash field (default: the configured one).
        leader_fixed: hold the leader on a rigid stand at hover thrust (cable-length study).
        triggers: which gripper triggers are armed, ``(passive, active)``, each for every trial
            or one flag per trial (default: the configuration's ``gripper.trigger``).
        step: the physics terms of a step, in order (default :data:`~aerodock.world.step.
            WORLD_STEP`; see :mod:`aerodock.world.step` to add one).
    """

    def __init__(self, cfg: Config, n: int, rng: np.random.Generator | TrialRNG,
                 field: DownwashField | None = None, leader_fixed: bool = False,
                 triggers: tuple[bool | np.ndarray, bool | np.ndarray] | None = None,
                 step: tuple[Term, ...] = WORLD_STEP):
        if n < 1:
            raise ValueError(f"number of trials must be >= 1, got {n}")
        params = WorldParams.from_config(cfg)
        if triggers is not None:
            params = params.with_triggers(*triggers)
        self.params = params
        self.n = n
        self.rng = rng
        self.field = field if field is not None else build_field(cfg)
        self.leader_fixed = leader_fixed
        self.terms = step
        rigid = params.rigid
        offsets = params.follower_fleet.params.rotor_offsets_m if rigid else np.zeros((1, 3))
        freeze(offsets)  # the field's geometry is cached by it (read-only)
        self.constants = BatchConstants(
            bar_mass_kg=np.full(n, params.platform.bar_mass_kg),
            no_close=np.zeros(n, dtype=bool),
            gravity_mps2=np.array([0.0, 0.0, params.vehicle.gravity_mps2]),
            rotor_offsets_m=offsets,
            hover_thrust_n=np.concatenate([np.full(n, params.leader_vehicle.hover_thrust_n),
                                           np.full(n, params.vehicle.hover_thrust_n)]),
        )
        self._mean_fn: Any = None  # built on first use (estimating a mean copies the field)
        self.state: WorldState | None = None

    # -- constants -----------------------------------------------------------------------------
    @property
    def vehicle(self) -> VehicleParams:
        """The quadrotors' common constants."""
        return self.params.vehicle

    @property
    def fleet(self) -> Fleet:
        """What flies the 2n batch (one fleet, or a pair of them)."""
        return self.params.fleet

    @property
    def follower_fleet(self) -> PointMassFleet | RigidBodyFleet:
        """The follower's vehicle model and nominal parameters."""
        return self.params.follower_fleet

    @property
    def leader_fleet(self) -> PointMassFleet | RigidBodyFleet:
        """The leader's vehicle model and nominal parameters."""
        return self.params.leader_fleet

    @property
    def rigid(self) -> bool:
        """Rigid-body vehicles (rather than point masses)."""
        return self.params.rigid

    @property
    def platform(self) -> PlatformParams:
        """The bar and its cables."""
        return self.params.platform

    @property
    def gripper_params(self) -> GripperParams:
        """The gripper's constants, with the triggers armed for these trials."""
        return self.params.gripper

    @property
    def dt_s(self) -> float:
        """Physics step, s."""
        return self.params.dt_s

    @property
    def substeps(self) -> int:
        """Physics steps per control period."""
        return self.params.substeps

    @property
    def dt_control_s(self) -> float:
        """Control period, s."""
        return self.params.dt_control_s

    # -- set-up ------------------------------------------------------------------------------
    def reset(self, leader_p_m: np.ndarray, follower_p_m: np.ndarray,
              leader_yaw_rad: np.ndarray | float = 0.0,
              follower_yaw_rad: np.ndarray | float = 0.0) -> None:
        """Both vehicles at rest at the given positions (n, 3), the bar hanging still.

        Random draws, in order: the thrust gains (leader, follower), the other spreads of each
        vehicle's true constants (leader, follower; none when no spread is set), the strain
        gauge's bias and calibration, the field's own, the follower's accelerometer bias (and
        with the filtered IMU chain the leader's).
        """
        n, rng, params = self.n, self.rng, self.params
        lead_sd, fol_sd = params.leader_spread, params.spread
        ones = np.ones(n)
        lead_gain = (ones if self.leader_fixed or lead_sd.thrust_coeff_sd <= 0
                     else 1.0 + lead_sd.thrust_coeff_sd * rng.standard_normal(n))
        fol_gain = (ones if fol_sd.thrust_coeff_sd <= 0
                    else 1.0 + fol_sd.thrust_coeff_sd * rng.standard_normal(n))
        lead_fleet, fol_fleet = params.leader_fleet, params.follower_fleet
        lead_body = lead_fleet.nominal_body(n)
        if not self.leader_fixed:
            lead_body = draw_body(lead_body, lead_sd, rng)
        fol_body = draw_body(fol_fleet.nominal_body(n), fol_sd, rng)
        leader = lead_fleet.hover(np.broadcast_to(leader_p_m, (n, 3)), leader_yaw_rad, lead_gain,
                                  lead_body)
        follower = fol_fleet.hover(np.broadcast_to(follower_p_m, (n, 3)), follower_yaw_rad,
                                   fol_gain, fol_body)
        anchor = anchor_point(leader.p, leader.R, params.platform)
        bar = hanging_bar(anchor, leader.v, leader.rpy[:, 2], params.platform)
        cable = np.tile([0.0, 0.0, params.platform.bar_mass_kg * params.vehicle.gravity_mps2],
                        (n, 1))
        gripper = calibrated_gripper(n, params.gripper, rng)
        self.field.reset(n, rng)
        bias = (params.imu.accel_bias_sd_mps2 * rng.standard_normal((n, 3)) if params.rigid
                else np.zeros((n, 3)))
        imu = None
        if params.filtered_imu:  # the leader's accelerometer has its own bias too
            lead_bias = params.imu.accel_bias_sd_mps2 * rng.standard_normal((n, 3))
            attitude = np.concatenate([leader.R, follower.R])
            imu = start_imu(attitude, np.concatenate([lead_bias, bias]),
                            params.vehicle.gravity_mps2, params.imu.chain, params.gyro_filter,
                            params.accel_filter, params.latency_steps + params.substeps)
        state = WorldState(
            n=n, fleet=params.fleet, rng=rng, field=self.field, leader_fixed=self.leader_fixed,
            constants=self.constants, bar=bar, cable_force_n=cable, gripper=gripper,
            accel_bias_body_mps2=bias,
            accel_window=AccelWindow(v_mps=follower.v.copy(), t_s=0.0, step_index=0),
            leader_accel=np.zeros((n, 3)), follower_accel=np.zeros((n, 3)),
            last_downwash_mps2=np.zeros((n, 3)), contact_seen=np.zeros(n, dtype=bool),
            contact_sensed=np.zeros(n, dtype=bool),
            ground_contact=np.zeros(n, dtype=bool), imu=imu,
        )
        state.leader, state.follower = leader, follower
        # The motion-capture buffer: the last latency_steps + 1 true states (the arrays
        # themselves: states are never modified in place, every step makes new ones).
        state.history = [snapshot(state, params)] * (params.latency_steps + 1)
        self.state = state

    def take_rows(self, rows: np.ndarray) -> World:
        """The trials at ``rows`` (indices into this batch) as a world of their own, exactly where
        they stand: same constants, their own random streams (a :class:`aerodock.rng.TrialRNG`)
        and turbulence, copies of their state. A trial flies on in it as it would have in this
        batch (tested bit for bit).

        Raises:
            TypeError: the random source is not per trial, or the field cannot split its state
                (a field without ``take_rows(rows, rng)``, e.g. a plug-in).
            ValueError: no state yet (:meth:`reset` first), or the torques are being logged.
        """
        if not self.splittable:
            raise TypeError("this world cannot be split into trials: it needs a TrialRNG and a "
                            "downwash field with take_rows(rows, rng)")
        if self.state is None:
            raise ValueError("reset the world before taking trials out of it")
        rows = as_rows(rows, self.n)
        out = copy.copy(self)
        out.n = int(rows.size)
        out.rng = self.rng.take_rows(rows)
        out.field = self.field.take_rows(rows, out.rng)
        out.state = self.state.take_rows(rows, out.rng, out.field)
        out.constants = out.state.constants
        out._mean_fn = None
        return out

    @property
    def splittable(self) -> bool:
        """Whether :meth:`take_rows` can take trials out of this world (a per-trial random
        source and a field that splits its own state)."""
        return isinstance(self.rng, TrialRNG) and hasattr(self.field, "take_rows")

    def set_rotor_loss(self, loss: np.ndarray) -> None:
        """Injected fault: the follower's rotors lose these fractions (n, 4) of their thrust
        (rigid-body model; the autopilot is not told, it can only react)."""
        if not self.rigid:
            raise ValueError("rotor thrust loss needs vehicle.model = 'rigid-body'")
        loss = np.asarray(loss, dtype=float)
        self.state.rotor_loss = loss if loss.any() else None

    def set_velocities(self, leader_v_mps: np.ndarray | None = None,
                       bar_v_mps: np.ndarray | None = None) -> None:
        """Start the leader (and the bar) moving: (n, 3) or (3,) velocities, NED."""
        n, state = self.n, self.state
        if leader_v_mps is not None:
            state.leader = replace(state.leader,
                                   v=np.array(np.broadcast_to(leader_v_mps, (n, 3))))
        if bar_v_mps is not None:
            state.bar = replace(state.bar, v=np.array(np.broadcast_to(bar_v_mps, (n, 3))))

    def disarm_gate(self, mask: np.ndarray) -> None:
        """Stop the gates of the trials in ``mask`` (n,) from closing (an aborted approach).

        A gate still open never closes (a trigger waiting out the software latency is
        cancelled); one already closing finishes.
        """
        g = self.state.gripper
        idle = mask & (g.gate == GateState.OPEN)
        if idle.any():
            self.state.gripper = replace(g, servo_start_s=np.where(idle, np.inf,
                                                                   g.servo_start_s))

    # -- the batch state -------------------------------------------------------------------
    @property
    def leader(self) -> Any:
        """The leaders' state (n trials)."""
        return self.state.leader

    @leader.setter
    def leader(self, value: Any) -> None:
        self.state.leader = value

    @property
    def follower(self) -> Any:
        """The followers' state (n trials)."""
        return self.state.follower

    @follower.setter
    def follower(self, value: Any) -> None:
        self.state.follower = value

    def poses(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The leaders' and followers' positions (n, 3), m, and attitudes (n, 3, 3): the numbers
        of ``leader.p``, ``leader.R``, ``follower.p`` and ``follower.R``, read as the rows of
        the 2n batch without splitting it into the two halves' states (the split builds two
        records and their bodies', about 30 µs at a batch of 1, and the mission's metrics, the
        first to read the vehicles after a control period's steps, need only these). The
        batch is the one the next step reads (joined here if a half was replaced since)."""
        both, n = self.state.both, self.n
        p, rot = both.p, both.R
        return p[:n], rot[:n], p[n:], rot[n:]

    @property
    def bar(self) -> BarState:
        """The hanging bars."""
        return self.state.bar

    @property
    def gripper(self) -> GripperState:
        """The followers' grippers."""
        return self.state.gripper

    @gripper.setter
    def gripper(self, value: GripperState) -> None:
        self.state.gripper = value  # an injected gripper fault

    @property
    def captured(self) -> np.ndarray:
        """(n,) bool: the gripper holds the bar."""
        return self.state.gripper.gate == GateState.CAPTURED

    @property
    def cable_force_n(self) -> np.ndarray:
        """(n, 3) the cables' pull on the leader, N (last step)."""
        return self.state.cable_force_n

    @property
    def leader_accel(self) -> np.ndarray:
        """(n, 3) the leaders' acceleration in the last step, m/s²."""
        return self.state.leader_accel

    @property
    def follower_accel(self) -> np.ndarray:
        """(n, 3) the followers' acceleration in the last step, m/s²."""
        return self.state.follower_accel

    @property
    def last_downwash_mps2(self) -> np.ndarray:
        """(n, 3) the wake's force on the follower per unit mass in the last step."""
        return self.state.last_downwash_mps2

    @property
    def contact_seen(self) -> np.ndarray:
        """(n,) bool: any bar contact since the recorder last cleared this."""
        return self.state.contact_seen

    @property
    def contact_sensed(self) -> np.ndarray:
        """(n,) bool: the strain gauge sensed contact since the recorder last cleared this."""
        return self.state.contact_sensed

    @property
    def ground_contact(self) -> np.ndarray:
        """(n,) bool: a vehicle reached the ground at some step."""
        return self.state.ground_contact

    @property
    def t_s(self) -> float:
        """Simulation time, s."""
        return self.state.t_s if self.state is not None else 0.0

    @property
    def step_index(self) -> int:
        """Physics steps since the reset."""
        return self.state.step_index if self.state is not None else 0

    # -- what is seen --------------------------------------------------------------------------
    def body_states(self) -> tuple[BodyState, BodyState]:
        """True (leader, follower) states as the downwash field sees them."""
        lead, fol = self.leader, self.follower
        return (BodyState(lead.p, lead.v, lead.R, lead.thrust_n, lead.body.mass_kg),
                BodyState(fol.p, fol.v, fol.R, fol.thrust_n, fol.body.mass_kg))

    def true_mean_field_mps2(self) -> np.ndarray:
        """(n, 3) the field's mean (turbulence-free) acceleration on the follower: its own
        ``mean_acceleration``, or the estimate of :mod:`aerodock.downwash.mean` for a field
        without one (evaluation only: no controller or label reads it)."""
        if self._mean_fn is None:
            self._mean_fn = mean_acceleration_fn(self.field, dt_s=self.dt_s)
        return self._mean_fn(*self.body_states())

    def observe(self) -> tuple[Observation, Observation]:
        """Motion-capture measurements of (leader, follower), delayed and noisy
        (:func:`aerodock.world.sensors.motion_capture`)."""
        return sensors.motion_capture(self.state, self.params)

    def observed_accel(self) -> np.ndarray:
        """(n, 3) the follower's accelerometer, world NED, averaged since the last call
        (:func:`aerodock.world.sensors.accelerometer`)."""
        return sensors.accelerometer(self.state, self.params)

    def observed_torque(self) -> TorqueReading:
        """The follower's torque observations over the control period since the last call
        (:func:`aerodock.world.sensors.torque_observations`)."""
        return sensors.torque_observations(self.state, self.params)

    # -- dynamics ------------------------------------------------------------------------------
    def step(self, leader_cmd: AttitudeCommand, follower_cmd: AttitudeCommand,
             close_command: np.ndarray | None = None) -> None:
        """Advance every trial by one physics step."""
        step_world(self.state, self.params, self.terms, self._targets(leader_cmd, follower_cmd),
                   close_command)

    def advance(self, leader_cmd: AttitudeCommand, follower_cmd: AttitudeCommand,
                close_command: np.ndarray | None = None) -> None:
        """One control period: ``substeps`` physics steps with zero-order-hold commands. With
        the default step (:data:`~aerodock.world.step.WORLD_STEP`) in a world the compiled
        period covers, one compiled call runs them (:mod:`aerodock.world.period`: the same
        numbers), the per-step path the steps it leaves."""
        targets = self._targets(leader_cmd, follower_cmd)  # prepared once per period
        state, params, terms = self.state, self.params, self.terms
        left = params.substeps
        if runs_step(terms):  # the default step: one compiled call where it covers the world
            while left and covered(state, params):
                done, why = run_period(state, params, targets, close_command, left)
                left -= done
                if not left or why == STOP_UNCOVERED:
                    break
                if not done and why != STOP_DRAWS:  # (the draws refilled: the kernel goes on)
                    step_world(state, params, terms, targets, close_command)
                    left -= 1
        for _ in range(left):
            step_world(state, params, terms, targets, close_command)

    def _targets(self, leader_cmd: AttitudeCommand, follower_cmd: AttitudeCommand) -> Any:
        """Both vehicles' commands as one batch (a fixed leader's rows are unused)."""
        lead = follower_cmd if self.leader_fixed else leader_cmd
        return self.params.fleet.targets(lead, follower_cmd, self.state.both, self.n,
                                         self.params.dt_s)


def hover_command(params: VehicleParams, n: int) -> AttitudeCommand:
    """Level attitude at hover thrust (an open-loop command, e.g. for tests)."""
    zero = np.zeros(n)
    return AttitudeCommand(zero, zero.copy(), zero.copy(), np.full(n, params.hover_thrust_n))


__all__ = ["World", "Observation", "hover_command", "BarState", "GripperState", "VehicleState"]
