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

from dataclasses import dataclass

import numpy as np

from aerodock.config import Config
from aerodock.downwash import BodyState, DownwashField, build_field
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
    CommandTargets,
    VehicleParams,
    VehicleState,
    command_targets,
    hover_state,
    rpy_to_rotmat,
    step_vehicle_targets,
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
        return rpy_to_rotmat(self.rpy)


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
        # Constant arrays of the hot loop (never modified in place).
        self._mass_col = self._mass[:, None]
        self._bar_mass = np.full(n, self.platform.bar_mass_kg)
        self._no_close = np.zeros(n, dtype=bool)
        self._gravity = np.array([0.0, 0.0, self.vehicle.gravity_mps2])
        self._both_state: tuple[VehicleState, VehicleState, VehicleState] | None = None
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
        # Ring buffer of the last latency_steps + 1 true states (the arrays themselves: states
        # are never modified in place, every step makes new ones).
        first = self._snapshot()
        self._history = [first] * (self._latency_steps + 1)
        self._v_at_last_accel = self.follower.v.copy()
        self._t_at_last_accel = 0.0
        self.last_downwash_mps2 = np.zeros((n, 3))
        self.contact_seen = np.zeros(n, dtype=bool)

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
        lp, lv, ly, fp, fv, fy = self._history[k]
        n = self.n

        def noisy(p, v, rpy):
            return Observation(
                p=p + cfg.pos_noise_m * self.rng.standard_normal((n, 3)),
                v=v + cfg.vel_noise_mps * self.rng.standard_normal((n, 3)),
                rpy=rpy.copy(),
            )

        return noisy(lp, lv, ly), noisy(fp, fv, fy)

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
    # Both vehicles are stepped as one batch of 2n rows (leaders first): every operation is
    # row-wise, so the numbers are those of two separate calls, at half the per-call overhead.
    # ``self.leader`` and ``self.follower`` are views of that batch; a caller may still replace
    # either (the batch is then rebuilt from them).

    def step(self, leader_cmd: AttitudeCommand, follower_cmd: AttitudeCommand,
             close_command: np.ndarray | None = None) -> None:
        """Advance every trial by one physics step."""
        self._step(self._targets(leader_cmd, follower_cmd), close_command)

    def advance(self, leader_cmd: AttitudeCommand, follower_cmd: AttitudeCommand,
                close_command: np.ndarray | None = None) -> None:
        """One control period: ``substeps`` physics steps with zero-order-hold commands."""
        targets = self._targets(leader_cmd, follower_cmd)  # clipped once per period
        for _ in range(self.substeps):
            self._step(targets, close_command)

    def _targets(self, leader_cmd: AttitudeCommand,
                 follower_cmd: AttitudeCommand) -> CommandTargets:
        """Both vehicles' clipped commands as one batch (a fixed leader's rows are unused)."""
        dt, n = self.dt_s, self.n
        fol = command_targets(follower_cmd, self.vehicle, dt, n)
        lead = fol if self.leader_fixed else command_targets(leader_cmd, self.vehicle, dt, n)
        return CommandTargets(
            np.concatenate([lead.roll_pitch_rad, fol.roll_pitch_rad]),
            np.concatenate([np.broadcast_to(lead.yaw_step_rad, (n,)),
                            np.broadcast_to(fol.yaw_step_rad, (n,))]),
            np.concatenate([np.broadcast_to(lead.thrust_n, (n,)),
                            np.broadcast_to(fol.thrust_n, (n,))]),
        )

    def _both(self) -> VehicleState:
        """Leader and follower as one batch of 2n vehicles (rebuilt if either was replaced)."""
        both = self._both_state
        if both is None or both[0] is not self.leader or both[1] is not self.follower:
            lead, fol = self.leader, self.follower
            state = VehicleState(*(np.concatenate([getattr(lead, k), getattr(fol, k)])
                                   for k in ("p", "v", "rpy", "thrust_cmd_state_n",
                                             "thrust_gain")))
            self._both_state = both = (lead, fol, state)
        return both[2]

    def _publish(self, both: VehicleState) -> None:
        """Make ``both`` the current vehicles: ``self.leader``/``self.follower`` are its halves."""
        n = self.n
        self.leader = VehicleState(both.p[:n], both.v[:n], both.rpy[:n],
                                   both.thrust_cmd_state_n[:n], both.thrust_gain[:n])
        self.follower = VehicleState(both.p[n:], both.v[n:], both.rpy[n:],
                                     both.thrust_cmd_state_n[n:], both.thrust_gain[n:])
        self._both_state = (self.leader, self.follower, both)

    def _snapshot(self) -> tuple[np.ndarray, ...]:
        lead, fol = self.leader, self.follower
        return lead.p, lead.v, lead.rpy, fol.p, fol.v, fol.rpy

    def _step(self, targets: CommandTargets, close_command: np.ndarray | None) -> None:
        dt = self.dt_s
        n = self.n
        both = self._both()
        leader, follower = self.leader, self.follower
        bar, gp, mass = self.bar, self.gripper_params, self._mass
        rot = both.R
        lead_R, fol_R = rot[:n], rot[n:]
        thrust = both.thrust_n
        captured = self.gripper.gate == GateState.CAPTURED.value
        any_captured = bool(captured.any())
        lead_body = BodyState(leader.p, leader.v, lead_R, thrust[:n], mass)
        fol_body = BodyState(follower.p, follower.v, fol_R, thrust[n:], mass)
        downwash = self.field.acceleration(lead_body, fol_body, dt)
        self.last_downwash_mps2 = downwash
        bar_drag = getattr(self.field, "bar_force_n", None)
        bar_force = (None if bar_drag is None
                     else bar_drag(lead_body, bar.p, bar.v, self.platform.bar_area_m2))
        contact, inside, up = bar_in_gripper(
            follower.p, fol_R, follower.v, bar.p, bar.v, bar.yaw_rad, gp,
        )
        if any_captured:
            contact = np.where(captured, 0.0, contact)
        push = up * contact[:, None]
        # Any bar contact during this control period (the recorder flags those labels).
        self.contact_seen |= contact > 0
        ext = np.empty((2 * n, 3))
        ext[:n] = self.cable_force_n  # the leader is pulled by last step's cable force
        follower_force = np.multiply(downwash, self._mass_col, out=ext[n:])
        follower_force -= push
        bar_force = push if bar_force is None else bar_force + push

        # Both vehicles; then the bar hangs from the leader's new anchor.
        new, accel = step_vehicle_targets(both, targets, ext, self.vehicle, dt, rot)
        if self.leader_fixed:  # on its stand: no motion, hover thrust
            new.p[:n] = leader.p
            new.v[:n] = leader.v
            new.rpy[:n] = leader.rpy
            np.divide(self.vehicle.hover_thrust_n, leader.thrust_gain,
                      out=new.thrust_cmd_state_n[:n])
            accel[:n] = 0.0
        lead_accel, fol_accel = accel[:n], accel[n:]
        # A captured follower hangs from the bar: its forces go to the hanging mass.
        if any_captured:
            hang_mass = np.where(captured, self.platform.bar_mass_kg + mass,
                                 self.platform.bar_mass_kg)
            fol_own = (fol_accel - self._gravity) * self._mass_col
            bar_force = bar_force + np.where(captured[:, None], fol_own, 0.0)
        else:
            hang_mass = self._bar_mass
        anchor_offset = lead_R[:, :, 2] * self.platform.anchor_below_leader_m  # anchor_point()
        self.bar, self.cable_force_n = step_bar(
            bar, leader.p + anchor_offset, leader.v, lead_accel, new.p[:n] + anchor_offset,
            leader.rpy[:, 2], bar_force, hang_mass, self.platform, dt,
        )
        if any_captured:
            offset = gp.mount_height_m + gp.bar_radius_m
            up_new = -rpy_to_rotmat(new.rpy[n:])[:, :, 2]
            p_hang = self.bar.p - up_new * offset
            cap = captured[:, None]
            np.copyto(new.p[n:], p_hang, where=cap)
            np.copyto(new.v[n:], self.bar.v, where=cap)
            np.copyto(fol_accel, (new.v[n:] - follower.v) / dt, where=cap)
        self._publish(new)
        self.leader_accel, self.follower_accel = lead_accel, fol_accel
        self.t_s = (self.step_index + 1) * dt
        self.step_index += 1
        rate = gp.sensor_rate_hz
        sample = int(self.t_s * rate + 1e-9) != int((self.t_s - dt) * rate + 1e-9)
        close = self._no_close if close_command is None else close_command
        self.gripper = step_gripper(self.gripper, self.t_s, contact, inside, sample, close, gp,
                                    self.rng)
        self._history[self.step_index % (self._latency_steps + 1)] = self._snapshot()


def hover_command(params: VehicleParams, n: int) -> AttitudeCommand:
    """Level attitude at hover thrust (an open-loop command, e.g. for tests)."""
    zero = np.zeros(n)
    return AttitudeCommand(zero, zero.copy(), zero.copy(), np.full(n, params.hover_thrust_n))


__all__ = ["World", "Observation", "hover_command", "BarState", "GripperState", "VehicleState"]
