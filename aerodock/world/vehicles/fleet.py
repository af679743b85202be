"""The vehicles of the world as one batch, for either vehicle model (``[vehicle] model``).

The world steps the leaders and the followers of N trials as one batch of 2N vehicles (leaders
first). A :class:`Fleet` hides which model flies them:

- ``rigid-body`` (default, :mod:`aerodock.world.vehicles.rigid_body`): attitude and body rates with
  inertia, four rotors with motor lag and saturation, rotor drag, the onboard autopilot on a noisy
  gyro; external loads are a force and a torque, so off-centre forces tilt the vehicle.
- ``point-mass`` (:mod:`aerodock.world.vehicles.point_mass`): a point mass behind first-order
  attitude and thrust lags, as the paper's controller models the vehicle. Several times cheaper,
  and the idealised world of earlier releases: torques are ignored.

Every state exposes ``p``, ``v``, ``R``, ``rpy``, ``thrust_n`` and ``thrust_gain`` (batch-first).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, fields, replace
from typing import Any

import numpy as np

from aerodock.config import Config
from aerodock.config.schema import AutopilotSection, VehicleSection
from aerodock.frozen import freeze
from aerodock.world.vehicles import rigid_kernel
from aerodock.world.vehicles.body import VehicleBody, body_rows, concat_bodies, nominal_body
from aerodock.world.vehicles.point_mass import (
    AttitudeCommand,
    CommandTargets,
    VehicleParams,
    VehicleState,
    command_targets,
    hover_state,
    step_vehicle_targets,
)
from aerodock.world.vehicles.rigid_body import (
    RigidBodyParams,
    RigidBodyState,
    hover_rigid_state,
    step_with_autopilot,
)
from aerodock.world.vehicles.targets import joined_torque, rigid_targets


@functools.cache
def _field_names(cls: type) -> tuple[str, ...]:
    return tuple(f.name for f in fields(cls))


def _concat(cls: type, a: Any, b: Any) -> Any:
    return _frozen(cls(*[concat_bodies(getattr(a, name), getattr(b, name)) if name == "body"
                         else np.concatenate([getattr(a, name), getattr(b, name)])
                         for name in _field_names(cls)]))


def _rows(cls: type, state: Any, sl: slice | np.ndarray) -> Any:
    return _frozen(cls(*[body_rows(state.body, sl) if name == "body" else getattr(state, name)[sl]
                         for name in _field_names(cls)]))


def _frozen(state: Any) -> Any:
    """``state`` with the arrays the steps keep numbers for made read-only, as the steps make
    them: the thrust gains (a rigid body's k_T) and a point mass's angles (its R)."""
    freeze(state.thrust_gain)
    if isinstance(state, VehicleState):
        freeze(state.rpy)
    return state


def _join_commands(lead: AttitudeCommand, fol: AttitudeCommand, n: int) -> AttitudeCommand:
    def both(name: str) -> np.ndarray:  # np.concatenate of the two, each broadcast to (n,)
        a, b = getattr(lead, name), getattr(fol, name)
        if (type(a) is np.ndarray and type(b) is np.ndarray and a.shape == b.shape == (n,)
                and a.dtype == b.dtype == np.float64):  # the controllers' commands: one call
            return np.concatenate((a, b))
        a, b = np.asarray(a), np.asarray(b)
        out = np.empty(2 * n, dtype=np.result_type(a, b))
        out[:n] = a
        out[n:] = b
        return out

    return AttitudeCommand(both("roll_rad"), both("pitch_rad"), both("yaw_rate_radps"),
                           both("thrust_n"), joined_torque(lead, fol, n))


def _broadcast_command(cmd: AttitudeCommand, n: int) -> AttitudeCommand:
    """``cmd`` with every field an (n,) array (a scalar command is every vehicle's)."""
    def rows(name: str) -> np.ndarray:
        return np.array(np.broadcast_to(np.asarray(getattr(cmd, name), dtype=float), (n,)))

    torque = None if cmd.torque_ff_nm is None else np.broadcast_to(cmd.torque_ff_nm, (n, 3))
    return AttitudeCommand(rows("roll_rad"), rows("pitch_rad"), rows("yaw_rate_radps"),
                           rows("thrust_n"), torque)


@dataclass(frozen=True)
class PointMassFleet:
    """Point-mass vehicles (:func:`aerodock.world.vehicles.point_mass.step_vehicle_targets`)."""

    params: VehicleParams
    state_type: type = VehicleState
    has_torque: bool = False

    def hover(self, p_m: np.ndarray, yaw_rad: np.ndarray | float, gain: np.ndarray,
              body: VehicleBody | None = None) -> VehicleState:
        """Vehicles at rest at ``p_m`` (n, 3) with thrust gains ``gain`` (n,) and true
        constants ``body`` (default nominal)."""
        state = hover_state(self.params, p_m, yaw_rad, body=body)
        gain = np.array(gain, dtype=float)
        freeze(gain)
        return replace(state, thrust_cmd_state_n=state.thrust_cmd_state_n / gain,
                       thrust_gain=gain)

    def targets(self, lead: AttitudeCommand, fol: AttitudeCommand, state: VehicleState,
                n: int, dt_s: float) -> CommandTargets:
        """Both halves' commands clipped to the limits, held over a control period."""
        return command_targets(_join_commands(lead, fol, n), self.params, dt_s, 2 * n)

    def nominal_body(self, n: int) -> VehicleBody:
        """``n`` vehicles exactly as nominal (a point mass: only its mass matters)."""
        return nominal_body(self.params.mass_kg, np.zeros(3), 0.0, n)

    def half_targets(self, cmd: AttitudeCommand, state: VehicleState, n: int,
                     dt_s: float) -> CommandTargets:
        """One batch of ``n`` vehicles' commands clipped to the limits (a pair's half)."""
        return command_targets(_broadcast_command(cmd, n), self.params, dt_s, n)

    def step(self, state: VehicleState, targets: CommandTargets, force_n: np.ndarray,
             torque_nm: np.ndarray | None, dt_s: float,
             gyro_noise_radps: np.ndarray | None,
             sensed: tuple[np.ndarray, np.ndarray] | None = None,
             ) -> tuple[VehicleState, np.ndarray]:
        """One physics step (torques and what an IMU senses do not apply to a point mass)."""
        return step_vehicle_targets(state, targets, force_n, self.params, dt_s, state.R)

    def hovering(self, state: VehicleState, old: VehicleState, rows: slice) -> VehicleState:
        """``state`` with ``rows`` held as in ``old`` at hover thrust (a leader on a stand)."""
        state.p[rows] = old.p[rows]
        state.v[rows] = old.v[rows]
        np.divide(old.body.mass_kg[rows] * self.params.gravity_mps2, old.thrust_gain[rows],
                  out=state.thrust_cmd_state_n[rows])
        rpy = state.rpy.copy()  # the angles are read-only (VehicleState.R is kept for them)
        rpy[rows] = old.rpy[rows]
        freeze(rpy)
        return replace(state, rpy=rpy)


@dataclass(frozen=True)
class RigidBodyFleet:
    """Rigid-body vehicles with their autopilots (:mod:`aerodock.world.vehicles.rigid_body`)."""

    params: RigidBodyParams
    state_type: type = RigidBodyState
    has_torque: bool = True

    def hover(self, p_m: np.ndarray, yaw_rad: np.ndarray | float, gain: np.ndarray,
              body: VehicleBody | None = None) -> RigidBodyState:
        """Vehicles at rest at ``p_m`` (n, 3) with thrust gains ``gain`` (n,) and true
        constants ``body`` (default nominal)."""
        return hover_rigid_state(self.params, np.array(p_m, dtype=float), yaw_rad, gain, body)

    def targets(self, lead: AttitudeCommand, fol: AttitudeCommand, state: RigidBodyState,
                n: int, dt_s: float) -> Any:
        """The autopilots' attitude targets for both halves, held over a control period (the
        two commands joined in the same compiled call)."""
        return rigid_targets(lead, state, self.params, 2 * n, follower_cmd=fol)

    def nominal_body(self, n: int) -> VehicleBody:
        """``n`` vehicles exactly as nominal."""
        p = self.params
        return nominal_body(p.mass_kg, p.inertia_kgm2, p.motor_tau_s, n)

    def half_targets(self, cmd: AttitudeCommand, state: RigidBodyState, n: int,
                     dt_s: float) -> Any:
        """One batch of ``n`` vehicles' attitude targets (a pair's half)."""
        return rigid_targets(_broadcast_command(cmd, n), state, self.params, n)

    def step(self, state: RigidBodyState, targets: Any, force_n: np.ndarray,
             torque_nm: np.ndarray | None, dt_s: float, gyro_noise_radps: np.ndarray | None,
             sensed: tuple[np.ndarray, np.ndarray] | None = None,
             ) -> tuple[RigidBodyState, np.ndarray]:
        """One physics step: autopilot on the gyro (or the sensed rates and attitude), rotors,
        rigid-body dynamics."""
        return step_with_autopilot(state, targets, force_n, torque_nm, self.params, dt_s,
                                   gyro_noise_radps, sensed)

    def hovering(self, state: RigidBodyState, old: RigidBodyState,
                 rows: slice) -> RigidBodyState:
        """``state`` with ``rows`` (a slice of step 1) held as in ``old`` (a leader on a rigid
        stand; compiled: :func:`rigid_kernel.hold_rows`, which the world's compiled control
        period calls too)."""
        start, stop, step = rows.indices(state.p.shape[0])
        if step != 1:
            raise ValueError(f"hovering holds a slice of step 1, got {rows}")
        rigid_kernel.hold_rows(start, stop, old.p, old.v, old.R, old.w, old.rotor_speed,
                               old.autopilot_state, old.thrust_n, state.p, state.v, state.R,
                               state.w, state.rotor_speed, state.autopilot_state,
                               state.thrust_n)
        return state


@dataclass(frozen=True)
class PairFleet:
    """Leaders and followers of different types (a heterogeneous pair): each half of the 2n
    batch is flown by its own fleet (its own nominal parameters, autopilot and mixer); the halves
    are joined again after every step."""

    leader: PointMassFleet | RigidBodyFleet
    follower: PointMassFleet | RigidBodyFleet

    @property
    def state_type(self) -> type:
        """The state class of both halves."""
        return self.follower.state_type

    @property
    def has_torque(self) -> bool:
        """Rigid bodies (both halves are one model)."""
        return self.follower.has_torque

    def targets(self, lead: AttitudeCommand, fol: AttitudeCommand, state: Any, n: int,
                dt_s: float) -> tuple[Any, Any]:
        """Each half's targets from its own fleet."""
        lead_state, fol_state = split_state(self, state, n)
        return (self.leader.half_targets(lead, lead_state, n, dt_s),
                self.follower.half_targets(fol, fol_state, n, dt_s))

    def step(self, state: Any, targets: tuple[Any, Any], force_n: np.ndarray,
             torque_nm: np.ndarray | None, dt_s: float, gyro_noise_radps: np.ndarray | None,
             sensed: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[Any, np.ndarray]:
        """One physics step of each half, joined."""
        n = force_n.shape[0] // 2
        halves = split_state(self, state, n)
        out = []
        for i, (fleet, half) in enumerate(zip((self.leader, self.follower), halves)):
            rows = slice(None, n) if i == 0 else slice(n, None)
            out.append(fleet.step(half, targets[i], force_n[rows],
                                  None if torque_nm is None else torque_nm[rows], dt_s,
                                  None if gyro_noise_radps is None else gyro_noise_radps[rows],
                                  None if sensed is None else (sensed[0][rows], sensed[1][rows])))
        accel = np.concatenate([out[0][1], out[1][1]])
        return concat_states(self, out[0][0], out[1][0]), accel

    def hovering(self, state: Any, old: Any, rows: slice) -> Any:
        """``state`` with the leader rows held as in ``old`` (a leader on a stand)."""
        return self.leader.hovering(state, old, rows)


Fleet = PointMassFleet | RigidBodyFleet | PairFleet


def same_state_width(leader: Any, follower: Any) -> tuple[Any, Any]:
    """Two rigid-body fleets whose autopilots keep the same number of state columns (a pair's
    halves are joined after every step): the narrower one widened (its extra columns are
    carried unread). Other fleets unchanged."""
    if not (isinstance(leader, RigidBodyFleet) and isinstance(follower, RigidBodyFleet)):
        return leader, follower
    width = max(leader.params.autopilot_state_columns, follower.params.autopilot_state_columns)
    return tuple(fleet if fleet.params.autopilot_state_columns == width else replace(
        fleet, params=replace(fleet.params, autopilot_state_columns=width))
        for fleet in (leader, follower))


def build_fleet(cfg: Config, vehicle: VehicleSection | None = None,
                autopilot: AutopilotSection | None = None) -> PointMassFleet | RigidBodyFleet:
    """The fleet of ``cfg``'s ``[vehicle] model`` for the vehicle section ``vehicle`` and the
    autopilot section ``autopilot`` (default ``[vehicle]`` and ``[autopilot]``, the
    follower's; ``cfg.leader`` and ``cfg.leader_autopilot`` for the leader's)."""
    if cfg.vehicle.model == "point-mass":
        return PointMassFleet(VehicleParams.from_config(cfg, vehicle))
    return RigidBodyFleet(RigidBodyParams.from_config(cfg, vehicle, autopilot))


def concat_states(fleet: Fleet, lead: Any, fol: Any) -> Any:
    """One batch of 2n vehicles from the leaders' and followers' states (leaders first)."""
    return _concat(fleet.state_type, lead, fol)


def state_rows(fleet: Fleet, both: Any, rows: np.ndarray) -> Any:
    """The vehicles at ``rows`` (an index array) of a batch: copies."""
    return _rows(fleet.state_type, both, rows)


def split_state(fleet: Fleet, both: Any, n: int) -> tuple[Any, Any]:
    """(leaders, followers) halves of a batch of 2n vehicles (views, not copies)."""
    return _rows(fleet.state_type, both, slice(None, n)), _rows(fleet.state_type, both,
                                                                slice(n, None))
