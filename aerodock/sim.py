"""The simulated world: two quadrotors, the downwash wake, the hanging bar and the gripper.

Batch-first and fixed-step: one :meth:`World.step` advances N independent trials by one physics
step (``1 / sim.physics_rate_hz``); controllers run outside, every ``physics/control`` steps, and
see the world only through :meth:`World.observe` (motion capture with noise and latency) and
:meth:`World.observed_accel` (an accelerometer-like measurement). All randomness comes from the
``numpy.random.Generator`` given to the constructor: same config and seed, same numbers.

The physics pipeline of one step (the downwash is one stage of it, as in crazyflow):

1. forces: downwash on the follower, wake drag on the bar, gripper contact, cable tension;
2. vehicles: :func:`aerodock.vehicle.step_vehicle` (leader fixed on a stand if configured);
3. bar: :func:`aerodock.platform.step_bar` (with a captured follower hanging from it);
4. gripper: :func:`aerodock.gripper.step_gripper` (sensor at its own rate, latencies, gate).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from aerodock.config import Config
from aerodock.downwash import BodyState, DownwashField, build_field
from aerodock.geometry import euler_to_rotmat
from aerodock.gripper import (
    GateState,
    GripperParams,
    GripperState,
    bar_in_gripper,
    calibrated_gripper,
    step_gripper,
)
from aerodock.platform import BarState, PlatformParams, anchor_point, hanging_bar, step_bar
from aerodock.rng import TrialRNG
from aerodock.vehicle import (
    AttitudeCommand,
    VehicleParams,
    VehicleState,
    hover_state,
    step_vehicle,
)


@dataclass(frozen=True)
class Observation:
    """What motion capture gives a controller: batch-first position, velocity and yaw."""

    p: np.ndarray  # (n, 3) m
    v: np.ndarray  # (n, 3) m/s
    rpy: np.ndarray  # (n, 3) rad: roll, pitch, yaw

    @property
    def yaw_rad(self) -> np.ndarray:
        """(n,) yaw."""
        return self.rpy[:, 2]

    @property
    def R(self) -> np.ndarray:  # noqa: N802
        """(n, 3, 3) body-to-world rotation."""
        return euler_to_rotmat(self.rpy[:, 0], self.rpy[:, 1], self.rpy[:, 2])


class World:
    """N trials of the two-vehicle docking world.

    Args:
        cfg: configuration.
        n: number of trials.
        rng: the only source of randomness; a :class:`aerodock.rng.TrialRNG` makes every trial's
            numbers independent of the batch size.
        field: downwash field (default: the configured one).
        leader_fixed: hold the leader on a rigid stand at hover thrust (cable-length study).
    """

    def __init__(self, cfg: Config, n: int, rng: np.random.Generator | TrialRNG,
                 field: DownwashField | None = None, leader_fixed: bool = False):
        if n < 1:
            raise ValueError(f"number of trials must be >= 1, got {n}")
        self.cfg = cfg
        self.n = n
        self.rng = rng
        self.vehicle = VehicleParams.from_config(cfg)
        self.platform = PlatformParams.from_config(cfg)
        self.gripper_params = GripperParams.from_config(cfg)
        self.field = field if field is not None else build_field(cfg)
        self.leader_fixed = leader_fixed
        self.dt_s = 1.0 / cfg.sim.physics_rate_hz
        self.substeps = int(round(cfg.sim.physics_rate_hz / cfg.sim.control_rate_hz))
        self.dt_control_s = self.substeps * self.dt_s
        self._latency_steps = int(round(cfg.mocap.latency_s / self.dt_s))
        self._mass = np.full(n, self.vehicle.mass_kg)
        self.t_s = 0.0
        self.step_index = 0

    # -- set-up ------------------------------------------------------------------------------
    def reset(self, leader_p_m: np.ndarray, follower_p_m: np.ndarray,
              leader_yaw_rad: np.ndarray | float = 0.0,
              follower_yaw_rad: np.ndarray | float = 0.0) -> None:
        """Both vehicles at rest at the given positions (n, 3), the bar hanging still."""
        n = self.n
        rng = self.rng
        self.leader = hover_state(self.vehicle, np.broadcast_to(leader_p_m, (n, 3)),
                                  leader_yaw_rad, None if self.leader_fixed else rng)
        self.follower = hover_state(self.vehicle, np.broadcast_to(follower_p_m, (n, 3)),
                                    follower_yaw_rad, rng)
        self.leader_accel = np.zeros((n, 3))
        self.follower_accel = np.zeros((n, 3))
        anchor = anchor_point(self.leader.p, self.leader.R, self.platform)
        self.bar = hanging_bar(anchor, self.leader.v, self.leader.rpy[:, 2], self.platform)
        self.cable_force_n = np.tile([0.0, 0.0, self.platform.bar_mass_kg
                                      * self.vehicle.gravity_mps2], (n, 1))
        self.gripper = calibrated_gripper(n, self.gripper_params, rng)
        self.field.reset(n, rng)
        self.t_s = 0.0
        self.step_index = 0
        size = self._latency_steps + 1
        self._history = {
            "lp": np.repeat(self.leader.p[None], size, 0),
            "lv": np.repeat(self.leader.v[None], size, 0),
            "ly": np.repeat(self.leader.rpy[None], size, 0),
            "fp": np.repeat(self.follower.p[None], size, 0),
            "fv": np.repeat(self.follower.v[None], size, 0),
            "fy": np.repeat(self.follower.rpy[None], size, 0),
        }
        self._v_at_last_accel = self.follower.v.copy()
        self._t_at_last_accel = 0.0
        self.last_downwash_mps2 = np.zeros((n, 3))

    # -- views ---------------------------------------------------------------------------------
    def body_states(self) -> tuple[BodyState, BodyState]:
        """True (leader, follower) states as the downwash field sees them."""
        lead = BodyState(self.leader.p, self.leader.v, self.leader.R, self.leader.thrust_n,
                         self._mass)
        fol = BodyState(self.follower.p, self.follower.v, self.follower.R,
                        self.follower.thrust_n, self._mass)
        return lead, fol

    def true_mean_field_mps2(self) -> np.ndarray:
        """(n, 3) the field's mean (turbulence-free) acceleration on the follower, if it has one."""
        mean = getattr(self.field, "mean_acceleration", None)
        if mean is None:
            return np.full((self.n, 3), np.nan)
        return mean(*self.body_states())

    def observe(self) -> tuple[Observation, Observation]:
        """Motion-capture measurements of (leader, follower), delayed and noisy."""
        cfg = self.cfg.mocap
        k = (self.step_index - self._latency_steps) % (self._latency_steps + 1)
        h = self._history
        n = self.n

        def noisy(p, v, rpy):
            return Observation(
                p=p + cfg.pos_noise_m * self.rng.standard_normal((n, 3)),
                v=v + cfg.vel_noise_mps * self.rng.standard_normal((n, 3)),
                rpy=rpy.copy(),
            )

        return noisy(h["lp"][k], h["lv"][k], h["ly"][k]), noisy(h["fp"][k], h["fv"][k], h["fy"][k])

    def observed_accel(self) -> np.ndarray:
        """(n, 3) the follower's mean kinematic acceleration since the last call, with noise."""
        dt = max(self.t_s - self._t_at_last_accel, 1e-9)
        accel = (self.follower.v - self._v_at_last_accel) / dt
        self._v_at_last_accel = self.follower.v.copy()
        self._t_at_last_accel = self.t_s
        noise = self.vehicle.accel_noise_mps2 * self.rng.standard_normal((self.n, 3))
        return accel + noise

    @property
    def captured(self) -> np.ndarray:
        """(n,) bool: the gripper holds the bar."""
        return self.gripper.gate == GateState.CAPTURED

    # -- dynamics ------------------------------------------------------------------------------
    def step(self, leader_cmd: AttitudeCommand, follower_cmd: AttitudeCommand,
             close_command: np.ndarray | None = None) -> None:
        """Advance every trial by one physics step."""
        dt = self.dt_s
        n = self.n
        lead_R = self.leader.R
        fol_R = self.follower.R
        captured = self.gripper.gate == GateState.CAPTURED
        lead_body = BodyState(self.leader.p, self.leader.v, lead_R, self.leader.thrust_n,
                              self._mass)
        fol_body = BodyState(self.follower.p, self.follower.v, fol_R, self.follower.thrust_n,
                             self._mass)
        downwash = self.field.acceleration(lead_body, fol_body, dt)
        self.last_downwash_mps2 = downwash
        bar_force = np.zeros((n, 3))
        bar_drag = getattr(self.field, "bar_force_n", None)
        if bar_drag is not None:
            bar_force += bar_drag(lead_body, self.bar.p, self.bar.v, self.platform.bar_area_m2)
        contact, inside, up = bar_in_gripper(
            self.follower.p, fol_R, self.follower.v, self.bar.p, self.bar.v, self.bar.yaw_rad,
            self.gripper_params,
        )
        contact = np.where(captured, 0.0, contact)
        follower_force = downwash * self._mass[:, None] - up * contact[:, None]
        bar_force += up * contact[:, None]

        # Leader first, pulled by last step's cable force; then the bar hangs from its new anchor.
        if self.leader_fixed:
            hover = np.full(n, self.vehicle.hover_thrust_n)
            new_leader = replace(self.leader, thrust_cmd_state_n=hover / self.leader.thrust_gain)
            lead_accel = np.zeros((n, 3))
        else:
            new_leader, lead_accel = step_vehicle(self.leader, leader_cmd, self.cable_force_n,
                                                  self.vehicle, dt, lead_R)
        new_follower, fol_accel = step_vehicle(self.follower, follower_cmd, follower_force,
                                               self.vehicle, dt, fol_R)
        # A captured follower hangs from the bar: its forces go to the hanging mass.
        hang_mass = np.where(captured, self.platform.bar_mass_kg + self._mass,
                             self.platform.bar_mass_kg)
        if np.any(captured):
            fol_own = (fol_accel - np.array([0.0, 0.0, self.vehicle.gravity_mps2])) * self._mass[
                :, None
            ]
            bar_force = bar_force + np.where(captured[:, None], fol_own, 0.0)
        self.bar, self.cable_force_n = step_bar(
            self.bar, anchor_point(self.leader.p, lead_R, self.platform), self.leader.v,
            lead_accel, anchor_point(new_leader.p, lead_R, self.platform),
            self.leader.rpy[:, 2], bar_force, hang_mass, self.platform, dt,
        )
        if np.any(captured):
            offset = self.gripper_params.mount_height_m + self.gripper_params.bar_radius_m
            up_new = -new_follower.R[:, :, 2]
            p_hang = self.bar.p - up_new * offset
            new_follower = replace(
                new_follower,
                p=np.where(captured[:, None], p_hang, new_follower.p),
                v=np.where(captured[:, None], self.bar.v, new_follower.v),
            )
            fol_accel = np.where(captured[:, None], (new_follower.v - self.follower.v) / dt,
                                 fol_accel)
        self.leader, self.follower = new_leader, new_follower
        self.leader_accel, self.follower_accel = lead_accel, fol_accel
        self.t_s = (self.step_index + 1) * dt
        self.step_index += 1
        sample = int(self.t_s * self.gripper_params.sensor_rate_hz + 1e-9) != int(
            (self.t_s - dt) * self.gripper_params.sensor_rate_hz + 1e-9
        )
        close = np.zeros(n, dtype=bool) if close_command is None else close_command
        self.gripper = step_gripper(self.gripper, self.t_s, contact, inside, sample, close,
                                    self.gripper_params, self.rng)
        k = self.step_index % (self._latency_steps + 1)
        h = self._history
        h["lp"][k], h["lv"][k], h["ly"][k] = self.leader.p, self.leader.v, self.leader.rpy
        h["fp"][k], h["fv"][k], h["fy"][k] = self.follower.p, self.follower.v, self.follower.rpy

    def advance(self, leader_cmd: AttitudeCommand, follower_cmd: AttitudeCommand,
                close_command: np.ndarray | None = None) -> None:
        """One control period: ``substeps`` physics steps with zero-order-hold commands."""
        for _ in range(self.substeps):
            self.step(leader_cmd, follower_cmd, close_command)


def hover_command(params: VehicleParams, n: int) -> AttitudeCommand:
    """Level attitude at hover thrust (an open-loop command, e.g. for tests)."""
    zero = np.zeros(n)
    return AttitudeCommand(zero, zero.copy(), zero.copy(), np.full(n, params.hover_thrust_n))


__all__ = ["World", "Observation", "hover_command", "BarState", "GripperState", "VehicleState"]
