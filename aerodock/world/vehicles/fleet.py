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
    rigid_targets,
    step_with_autopilot,
)


@functools.cache
def _field_names(cls: type) -> tuple[str, ...]:
    return tuple(f.name for f in fields(cls))


def _concat(cls: type, a: Any, b: Any) -> Any:
    return cls(*[np.concatenate([getattr(a, name), getattr(b, name)])
                 for name in _field_names(cls)])


def _rows(cls: type, state: Any, sl: slice) -> Any:
    return cls(*[getattr(state, name)[sl] for name in _field_names(cls)])


def _join_commands(lead: AttitudeCommand, fol: AttitudeCommand, n: int) -> AttitudeCommand:
    def both(name: str) -> np.ndarray:  # np.concatenate of the two, each broadcast to (n,)
        a, b = np.asarray(getattr(lead, name)), np.asarray(getattr(fol, name))
        out = np.empty(2 * n, dtype=np.result_type(a, b))
        out[:n] = a
        out[n:] = b
        return out

    torque = None
    if lead.torque_ff_nm is not None or fol.torque_ff_nm is not None:
        torque = np.zeros((2 * n, 3))
        for rows, cmd in ((slice(None, n), lead), (slice(n, None), fol)):
            if cmd.torque_ff_nm is not None:
                torque[rows] = cmd.torque_ff_nm
    return AttitudeCommand(both("roll_rad"), both("pitch_rad"), both("yaw_rate_radps"),
                           both("thrust_n"), torque)


@dataclass(frozen=True)
class PointMassFleet:
    """Point-mass vehicles (:func:`aerodock.world.vehicles.point_mass.step_vehicle_targets`)."""

    params: VehicleParams
    state_type: type = VehicleState
    has_torque: bool = False

    def hover(self, p_m: np.ndarray, yaw_rad: np.ndarray | float,
              gain: np.ndarray) -> VehicleState:
        """Vehicles at rest at ``p_m`` (n, 3) with thrust gains ``gain`` (n,)."""
        state = hover_state(self.params, p_m, yaw_rad)
        return replace(state, thrust_cmd_state_n=state.thrust_cmd_state_n / gain,
                       thrust_gain=np.asarray(gain, dtype=float).copy())

    def targets(self, lead: AttitudeCommand, fol: AttitudeCommand, state: VehicleState,
                n: int, dt_s: float) -> CommandTargets:
        """Both halves' commands clipped to the limits, held over a control period."""
        return command_targets(_join_commands(lead, fol, n), self.params, dt_s, 2 * n)

    def step(self, state: VehicleState, targets: CommandTargets, force_n: np.ndarray,
             torque_nm: np.ndarray | None, dt_s: float,
             gyro_noise_radps: np.ndarray | None) -> tuple[VehicleState, np.ndarray]:
        """One physics step (torques and gyro noise do not apply to a point mass)."""
        return step_vehicle_targets(state, targets, force_n, self.params, dt_s, state.R)

    def hovering(self, state: VehicleState, old: VehicleState, rows: slice) -> VehicleState:
        """``state`` with ``rows`` held as in ``old`` at hover thrust (a leader on a stand)."""
        state.p[rows] = old.p[rows]
        state.v[rows] = old.v[rows]
        state.rpy[rows] = old.rpy[rows]
        np.divide(self.params.hover_thrust_n, old.thrust_gain[rows],
                  out=state.thrust_cmd_state_n[rows])
        return state


@dataclass(frozen=True)
class RigidBodyFleet:
    """Rigid-body vehicles with their autopilots (:mod:`aerodock.world.vehicles.rigid_body`)."""

    params: RigidBodyParams
    state_type: type = RigidBodyState
    has_torque: bool = True

    def hover(self, p_m: np.ndarray, yaw_rad: np.ndarray | float,
              gain: np.ndarray) -> RigidBodyState:
        """Vehicles at rest at ``p_m`` (n, 3) with thrust gains ``gain`` (n,)."""
        return hover_rigid_state(self.params, np.array(p_m, dtype=float), yaw_rad, gain)

    def targets(self, lead: AttitudeCommand, fol: AttitudeCommand, state: RigidBodyState,
                n: int, dt_s: float) -> Any:
        """The autopilots' attitude targets for both halves, held over a control period."""
        return rigid_targets(_join_commands(lead, fol, n), state, self.params, 2 * n)

    def step(self, state: RigidBodyState, targets: Any, force_n: np.ndarray,
             torque_nm: np.ndarray | None, dt_s: float,
             gyro_noise_radps: np.ndarray | None) -> tuple[RigidBodyState, np.ndarray]:
        """One physics step: autopilot on the gyro, rotors, rigid-body dynamics."""
        return step_with_autopilot(state, targets, force_n, torque_nm, self.params, dt_s,
                                   gyro_noise_radps)

    def hovering(self, state: RigidBodyState, old: RigidBodyState,
                 rows: slice) -> RigidBodyState:
        """``state`` with ``rows`` held as in ``old`` (a leader on a rigid stand)."""
        for name in ("p", "v", "R", "w", "rotor_speed", "rate_integral", "thrust_n"):
            getattr(state, name)[rows] = getattr(old, name)[rows]
        return state


Fleet = PointMassFleet | RigidBodyFleet


def build_fleet(cfg: Config) -> Fleet:
    """The fleet of ``cfg``'s ``[vehicle] model``."""
    if cfg.vehicle.model == "point-mass":
        return PointMassFleet(VehicleParams.from_config(cfg))
    return RigidBodyFleet(RigidBodyParams.from_config(cfg))


def concat_states(fleet: Fleet, lead: Any, fol: Any) -> Any:
    """One batch of 2n vehicles from the leaders' and followers' states (leaders first)."""
    return _concat(fleet.state_type, lead, fol)


def split_state(fleet: Fleet, both: Any, n: int) -> tuple[Any, Any]:
    """(leaders, followers) halves of a batch of 2n vehicles (views, not copies)."""
    return _rows(fleet.state_type, both, slice(None, n)), _rows(fleet.state_type, both,
                                                                slice(n, None))
