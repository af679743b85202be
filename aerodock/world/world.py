"""The simulated world: two quadrotors, the downwash wake, the hanging bar and the gripper.

Batch-first and fixed-step: one :meth:`World.step` advances N independent trials by one physics
step (``1 / sim.physics_rate_hz``); controllers run outside, every ``physics/control`` steps, and
see the world only through :meth:`World.observe` (motion capture with noise and latency) and
:meth:`World.observed_accel` (the follower's IMU: bias, vibration, noise). A flight log may also
read :meth:`World.observed_torque` (the follower's gyro and rotor-speed torques, rigid-body model;
see :mod:`aerodock.world.torque_sensing`). All randomness comes from the ``numpy.random.Generator``
given to the constructor: same config and seed, same numbers.

The physics pipeline of one step (the downwash is one stage of it, as in crazyflow):

1. forces and torques: the wake's wrench on the follower's rotor disks
   (:func:`aerodock.downwash.wrench.follower_wrench`), its drag on the bar, gripper contact, the
   cables' pull at the leader's anchor, an injected rotor fault;
2. vehicles: :class:`aerodock.world.vehicles.fleet.Fleet` (rigid bodies under their autopilots on a
noisy gyro,
   or point masses; the leader fixed on a stand if configured);
3. bar: :func:`aerodock.world.platform.step_bar` (with a captured follower hanging from it);
4. the ground (z = 0), then the gripper: :func:`aerodock.world.gripper.step_gripper` (sensor at its
own
   rate, latencies, gate).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from aerodock.config import Config
from aerodock.downwash import BodyState, DownwashField, build_field
from aerodock.downwash.mean import mean_acceleration_fn
from aerodock.downwash.wrench import bar_wake_force_n, follower_wrench
from aerodock.geometry import rotmat_to_euler
from aerodock.rng import TrialRNG, standard_normal_t
from aerodock.world.gripper import (
    _CAPTURED,
    GateState,
    GripperParams,
    GripperState,
    bar_in_gripper,
    calibrated_gripper,
    step_gripper,
)
from aerodock.world.platform import BarState, PlatformParams, anchor_point, hanging_bar, step_bar
from aerodock.world.torque_sensing import TorqueLog, TorqueReading
from aerodock.world.vehicles.fleet import Fleet, build_fleet, concat_states, split_state
from aerodock.world.vehicles.point_mass import (
    AttitudeCommand,
    VehicleParams,
    VehicleState,
    rpy_to_rotmat,
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
        cfg: configuration (``[vehicle] model`` chooses rigid-body or point-mass vehicles).
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
        self.fleet: Fleet = build_fleet(cfg)
        self.rigid = self.fleet.has_torque
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
        self._mass_rows = np.repeat(self._mass_col, 3, axis=1)  # (n, 3): a flat loop, same numbers
        self._bar_mass = np.full(n, self.platform.bar_mass_kg)
        self._no_close = np.zeros(n, dtype=bool)
        self._zero_n = np.zeros(n)
        self._mean_fn: Any = None  # built on first use (estimating a mean copies the field)
        self._gravity = np.array([0.0, 0.0, self.vehicle.gravity_mps2])
        imu = cfg.imu
        self._gyro_sd = imu.gyro_noise_radps if self.rigid else 0.0
        # Motion capture's noise (position, velocity) and the attitude estimate's (rigid body).
        self._mocap_sd = (cfg.mocap.pos_noise_m, cfg.mocap.vel_noise_mps,
                          imu.attitude_noise_rad if self.rigid else 0.0)
        self._rotor_offsets = (self.fleet.params.rotor_offsets_m if self.rigid
                               else np.zeros((1, 3)))
        # Both vehicles as one batch of 2n (leaders first); ``leader``/``follower`` are its
        # halves, split off when first asked for (the hot loop works on the batch itself).
        self._batch: Any = None
        self._lead: Any = None
        self._fol: Any = None
        self.t_s = 0.0
        self.step_index = 0

    # -- set-up ------------------------------------------------------------------------------
    def reset(self, leader_p_m: np.ndarray, follower_p_m: np.ndarray,
              leader_yaw_rad: np.ndarray | float = 0.0,
              follower_yaw_rad: np.ndarray | float = 0.0) -> None:
        """Both vehicles at rest at the given positions (n, 3), the bar hanging still."""
        n = self.n
        rng = self.rng
        sd = self.vehicle.thrust_gain_sd
        ones = np.ones(n)
        lead_gain = ones if self.leader_fixed or sd <= 0 else 1.0 + sd * rng.standard_normal(n)
        fol_gain = ones if sd <= 0 else 1.0 + sd * rng.standard_normal(n)
        self.leader = self.fleet.hover(np.broadcast_to(leader_p_m, (n, 3)), leader_yaw_rad,
                                       lead_gain)
        self.follower = self.fleet.hover(np.broadcast_to(follower_p_m, (n, 3)),
                                         follower_yaw_rad, fol_gain)
        self.leader_accel = np.zeros((n, 3))
        self.follower_accel = np.zeros((n, 3))
        anchor = anchor_point(self.leader.p, self.leader.R, self.platform)
        self.bar = hanging_bar(anchor, self.leader.v, self.leader.rpy[:, 2], self.platform)
        self.cable_force_n = np.tile([0.0, 0.0, self.platform.bar_mass_kg
                                      * self.vehicle.gravity_mps2], (n, 1))
        self.gripper = calibrated_gripper(n, self.gripper_params, rng)
        self.field.reset(n, rng)
        # The follower's accelerometer: a constant residual bias per trial (body frame).
        self._accel_bias_body = (self.cfg.imu.accel_bias_sd_mps2 * rng.standard_normal((n, 3))
                                 if self.rigid else np.zeros((n, 3)))
        self.t_s = 0.0
        self.step_index = 0
        # Ring buffer of the last latency_steps + 1 true states (the arrays themselves: states
        # are never modified in place, every step makes new ones).
        first = self._snapshot()
        self._history = [first] * (self._latency_steps + 1)
        self._v_at_last_accel = self.follower.v.copy()
        self._t_at_last_accel = 0.0
        self._steps_at_last_accel = 0
        self._accel_reading: np.ndarray | None = None
        self.last_downwash_mps2 = np.zeros((n, 3))
        self.contact_seen = np.zeros(n, dtype=bool)
        self.ground_contact = np.zeros(n, dtype=bool)
        self._rotor_loss: np.ndarray | None = None
        self._torque_log: TorqueLog | None = None  # kept once someone reads the torques
        self._torque_reading: TorqueReading | None = None
        self._steps_at_last_torque = 0

    def set_rotor_loss(self, loss: np.ndarray) -> None:
        """Injected fault: the follower's rotors lose these fractions (n, 4) of their thrust
        (rigid-body model; the autopilot is not told, it can only react)."""
        if not self.rigid:
            raise ValueError("rotor thrust loss needs vehicle.model = 'rigid-body'")
        loss = np.asarray(loss, dtype=float)
        self._rotor_loss = loss if loss.any() else None

    def set_velocities(self, leader_v_mps: np.ndarray | None = None,
                       bar_v_mps: np.ndarray | None = None) -> None:
        """Start the leader (and the bar) moving: (n, 3) or (3,) velocities, NED."""
        n = self.n
        if leader_v_mps is not None:
            self.leader = replace(self.leader, v=np.array(np.broadcast_to(leader_v_mps, (n, 3))))
        if bar_v_mps is not None:
            self.bar = replace(self.bar, v=np.array(np.broadcast_to(bar_v_mps, (n, 3))))

    def disarm_gate(self, mask: np.ndarray) -> None:
        """Stop the gates of the trials in ``mask`` (n,) from closing (an aborted approach).

        A gate still open never closes (a trigger waiting out the software latency is
        cancelled); one already closing finishes.
        """
        g = self.gripper
        idle = mask & (g.gate == GateState.OPEN)
        if idle.any():
            self.gripper = replace(g, servo_start_s=np.where(idle, np.inf, g.servo_start_s))

    # -- views ---------------------------------------------------------------------------------
    def body_states(self) -> tuple[BodyState, BodyState]:
        """True (leader, follower) states as the downwash field sees them."""
        lead = BodyState(self.leader.p, self.leader.v, self.leader.R, self.leader.thrust_n,
                         self._mass)
        fol = BodyState(self.follower.p, self.follower.v, self.follower.R,
                        self.follower.thrust_n, self._mass)
        return lead, fol

    def true_mean_field_mps2(self) -> np.ndarray:
        """(n, 3) the field's mean (turbulence-free) acceleration on the follower: its own
        ``mean_acceleration``, or the estimate of :mod:`aerodock.downwash.mean` for a field
        without one (evaluation only: no controller or label reads it)."""
        if self._mean_fn is None:
            self._mean_fn = mean_acceleration_fn(self.field, dt_s=self.dt_s)
        return self._mean_fn(*self.body_states())

    def observe(self) -> tuple[Observation, Observation]:
        """Motion-capture measurements of (leader, follower), delayed and noisy.

        Positions and velocities from motion capture; the attitude is the flight computer's
        estimate (true attitude plus ``imu.attitude_noise_rad`` with the rigid-body model).
        """
        k = (self.step_index - self._latency_steps) % (self._latency_steps + 1)
        lp, lv, lr, fp, fv, fr = self._history[k]
        n, rng = self.n, self.rng
        pos_sd, vel_sd, att_sd = self._mocap_sd
        # Per trial the draws come as attitude (rigid body), position, velocity: one block.
        per_trial = isinstance(rng, TrialRNG) and rng.n == n

        def noisy(p, v, rot):
            rpy = np.stack(rotmat_to_euler(rot), axis=1) if rot.ndim == 3 else rot.copy()
            if per_trial:
                draw = standard_normal_t(rng, n, 9 if att_sd > 0 else 6)
                if att_sd > 0:
                    rpy += att_sd * draw[:3].T
                    draw = draw[3:]
                noise_p, noise_v = draw[:3].T, draw[3:].T
            else:
                if att_sd > 0:
                    rpy += att_sd * rng.standard_normal((n, 3))
                noise_p = rng.standard_normal((n, 3))
                noise_v = rng.standard_normal((n, 3))
            return Observation(
                p=np.add(p, pos_sd * noise_p, out=np.empty((n, 3))),
                v=np.add(v, vel_sd * noise_v, out=np.empty((n, 3))),
                rpy=rpy,
            )

        return noisy(lp, lv, lr), noisy(fp, fv, fr)

    def observed_accel(self) -> np.ndarray:
        """(n, 3) the follower's accelerometer, world NED, averaged since the last call.

        The mean kinematic acceleration over the window plus what the IMU adds: white noise
        (``vehicle.accel_noise_mps2`` per physics sample) and, with the rigid-body model, motor
        vibration (``imu.accel_vibration_mps2`` per sample at hover rotor speed, growing with the
        square of the rotor speed) and the residual bias (constant in the body frame), both
        averaged over the window's samples as the flight computer's filter does.

        A second call before the world has moved returns the same reading (the controller and
        the recorder read one accelerometer).
        """
        if self._accel_reading is not None and self.step_index == self._steps_at_last_accel:
            return self._accel_reading.copy()
        dt = max(self.t_s - self._t_at_last_accel, 1e-9)
        samples = max(self.step_index - self._steps_at_last_accel, 1)
        accel = (self.follower.v - self._v_at_last_accel) / dt
        self._v_at_last_accel = self.follower.v.copy()
        self._t_at_last_accel = self.t_s
        self._steps_at_last_accel = self.step_index
        sd = np.full(self.n, self.vehicle.accel_noise_mps2 ** 2)
        if self.rigid:
            load = self.follower.thrust_n / self.vehicle.hover_thrust_n
            sd = sd + (self.cfg.imu.accel_vibration_mps2 * load) ** 2
            accel = accel + np.matmul(self.follower.R, self._accel_bias_body[:, :, None])[:, :, 0]
        sd = np.sqrt(sd / samples)
        self._accel_reading = accel + sd[:, None] * self.rng.standard_normal((self.n, 3))
        return self._accel_reading.copy()

    def observed_torque(self) -> TorqueReading:
        """The follower's torque observations (body FRD) over the control period since the last
        call: the kinematic torque ``J dw/dt + w x J w`` from its gyro, the torque its rotors
        explain from their measured speeds, its mean gyro reading, and the simulator's true wake
        torque over the same steps (see :mod:`aerodock.world.torque_sensing`).

        The first call starts the log (and returns zeros): until then the world computes none
        of it. Like :meth:`observed_accel`, a second call before the world has moved returns
        the same reading. No random numbers are drawn (the gyro noise is the autopilot's).

        Raises:
            ValueError: point-mass vehicles (they have no rotors or body rates).
        """
        if not self.rigid:
            raise ValueError("torque observations need vehicle.model = 'rigid-body'")
        if self._torque_log is None:
            self._torque_log = TorqueLog(self.fleet.params, self.n, self.dt_s)
            self._steps_at_last_torque = self.step_index
            self._torque_reading = self._torque_log.read()
        elif self.step_index != self._steps_at_last_torque or self._torque_reading is None:
            self._steps_at_last_torque = self.step_index
            self._torque_reading = self._torque_log.read()
        return self._torque_reading

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
        targets = self._targets(leader_cmd, follower_cmd)  # prepared once per period
        for _ in range(self.substeps):
            self._step(targets, close_command)

    def _targets(self, leader_cmd: AttitudeCommand, follower_cmd: AttitudeCommand) -> Any:
        """Both vehicles' commands as one batch (a fixed leader's rows are unused)."""
        lead = follower_cmd if self.leader_fixed else leader_cmd
        return self.fleet.targets(lead, follower_cmd, self._both(), self.n, self.dt_s)

    @property
    def leader(self) -> Any:
        """The leaders' state (n trials): a view of the batch's first half."""
        if self._lead is None:
            self._split()
        return self._lead

    @leader.setter
    def leader(self, value: Any) -> None:
        if self._lead is None:
            self._split()
        self._lead, self._batch = value, None

    @property
    def follower(self) -> Any:
        """The followers' state (n trials): a view of the batch's second half."""
        if self._fol is None:
            self._split()
        return self._fol

    @follower.setter
    def follower(self, value: Any) -> None:
        if self._fol is None:
            self._split()
        self._fol, self._batch = value, None

    def _split(self) -> None:
        if self._batch is not None:
            self._lead, self._fol = split_state(self.fleet, self._batch, self.n)

    def _both(self) -> Any:
        """Leader and follower as one batch of 2n vehicles (rebuilt if either was replaced)."""
        if self._batch is None:
            self._batch = concat_states(self.fleet, self.leader, self.follower)
        return self._batch

    def _publish(self, both: Any) -> None:
        """Make ``both`` the current vehicles: ``self.leader``/``self.follower`` are its halves."""
        self._batch, self._lead, self._fol = both, None, None

    def _snapshot(self) -> tuple[np.ndarray, ...]:
        both, n = self._both(), self.n
        p, v = both.p, both.v
        att = both.R if self.rigid else both.rpy  # a rotation; angles are computed when observed
        return p[:n], v[:n], att[:n], p[n:], v[n:], att[n:]

    def _draw_gyro_noise(self) -> np.ndarray | None:
        if not self._gyro_sd:
            return None
        n = self.n
        draw = standard_normal_t(self.rng, n, 6)  # per trial: leader's then follower's gyro
        noise = np.empty((3, 2 * n))  # component-major: both halves are contiguous rows
        np.multiply(draw[:3], self._gyro_sd, out=noise[:, :n])
        np.multiply(draw[3:], self._gyro_sd, out=noise[:, n:])
        return noise.T

    def _lose_thrust(self, rotor_speed: np.ndarray, thrust_gain: np.ndarray,
                     fol_R: np.ndarray, force: np.ndarray,  # noqa: N803
                     torque: np.ndarray) -> None:
        """Add the thrust the followers' faulty rotors (speeds (n, 4), thrust gains (n,)) do
        not give, as a force and torque (in place)."""
        params = self.fleet.params
        lost = rotor_speed * rotor_speed
        lost *= (params.thrust_coeff * thrust_gain)[:, None]
        lost *= self._rotor_loss
        force += fol_R[:, :, 2] * lost.sum(axis=1)[:, None]  # less thrust along body -z
        for i in range(lost.shape[1]):
            torque -= lost[:, i:i + 1] * params.rotor_torque_map[i]

    def _step(self, targets: Any, close_command: np.ndarray | None) -> None:
        dt = self.dt_s
        n = self.n
        both = self._both()  # the halves are views of the batch's rows
        bar, gp, mass = self.bar, self.gripper_params, self._mass
        rot, pos, vel = both.R, both.p, both.v
        lead_R, fol_R = rot[:n], rot[n:]
        lead_p, lead_v, fol_p, fol_v = pos[:n], vel[:n], pos[n:], vel[n:]
        thrust = both.thrust_n
        captured = self.gripper.gate == _CAPTURED
        any_captured = bool(captured.any())
        lead_body = BodyState(lead_p, lead_v, lead_R, thrust[:n], mass)
        fol_body = BodyState(fol_p, fol_v, fol_R, thrust[n:], mass)
        # 1. Forces: the wake on the follower's rotors, on the bar; contact; cables.
        if self.rigid:  # sampled where it acts: each rotor disk (force and torque)
            wake_force, wake_torque = follower_wrench(self.field, lead_body, fol_body,
                                                      self._rotor_offsets, dt)
        else:  # a point mass feels the force at its centre
            wake_force = self.field.acceleration(lead_body, fol_body, dt) * self._mass_rows
            wake_torque = None
        self.last_downwash_mps2 = wake_force / self._mass_rows
        bar_axis = np.empty((3, n))  # (cos yaw, sin yaw, 0) per bar, component-major
        cos_yaw = np.cos(bar.yaw_rad, out=bar_axis[0])
        sin_yaw = np.sin(bar.yaw_rad, out=bar_axis[1])
        bar_axis[2] = 0.0
        bar_force = bar_wake_force_n(self.field, lead_body, bar.p, bar.v,
                                     self.platform.bar_area_m2, dt, bar_axis.T)
        contact, inside, up = bar_in_gripper(
            fol_p, fol_R, fol_v, bar.p, bar.v, bar.yaw_rad, gp, cos_sin=(cos_yaw, sin_yaw),
        )
        if any_captured:
            contact = np.where(captured, 0.0, contact)
        push = up * contact[:, None]
        # Any bar contact during this control period (the recorder flags those labels).
        self.contact_seen |= contact > 0
        ext = np.empty((2 * n, 3))
        ext[:n] = self.cable_force_n  # the leader is pulled by last step's cable force
        follower_force = np.add(wake_force, 0.0, out=ext[n:])
        follower_force -= push
        bar_force = push if bar_force is None else bar_force + push
        torque = None
        if self.rigid:
            torque_t = np.zeros((3, 2 * n))  # component-major: the vehicles work on its rows
            # The cables pull at the anchor, below the leader's centre of mass (body +z).
            cable_body = np.matmul(self.cable_force_n[:, None, :], lead_R)[:, 0]
            d = self.platform.anchor_below_leader_m
            np.multiply(-d, cable_body[:, 1], out=torque_t[0, :n])
            np.multiply(d, cable_body[:, 0], out=torque_t[1, :n])
            if wake_torque is not None:
                torque_t[:, n:] = wake_torque.T
            torque = torque_t.T
            if self._rotor_loss is not None:
                self._lose_thrust(both.rotor_speed[n:], both.thrust_gain[n:], fol_R,
                                  follower_force, torque[n:])

        # 2. Vehicles (autopilots inside); then the bar hangs from the leader's new anchor.
        gyro_noise = self._draw_gyro_noise()
        if self._torque_log is not None:  # only when a flight log reads the torques
            self._torque_log.add_step(both.w[n:], None if gyro_noise is None else gyro_noise[n:],
                                      both.rotor_speed[n:], fol_v, fol_R, wake_torque)
        new, accel = self.fleet.step(both, targets, ext, torque, dt, gyro_noise)
        if self.leader_fixed:  # on its stand: no motion, hover thrust
            new = self.fleet.hovering(new, both, slice(None, n))
            accel[:n] = 0.0
        lead_accel, fol_accel = accel[:n], accel[n:]
        # A captured follower hangs from the bar: its forces go to the hanging mass.
        if any_captured:
            hang_mass = np.where(captured, self.platform.bar_mass_kg + mass,
                                 self.platform.bar_mass_kg)
            fol_own = (fol_accel - self._gravity) * self._mass_rows
            bar_force = bar_force + np.where(captured[:, None], fol_own, 0.0)
        else:
            hang_mass = self._bar_mass
        anchor_offset = lead_R[:, :, 2] * self.platform.anchor_below_leader_m  # anchor_point()
        self.bar, self.cable_force_n = step_bar(
            bar, lead_p + anchor_offset, lead_v, lead_accel, new.p[:n] + anchor_offset,
            both.rpy[:n, 2] if not self.rigid else _yaw(lead_R), bar_force, hang_mass,
            self.platform, dt,
        )
        if any_captured:
            offset = gp.mount_height_m + gp.bar_radius_m
            up_new = -new.R[n:, :, 2]
            p_hang = self.bar.p - up_new * offset
            cap = captured[:, None]
            np.copyto(new.p[n:], p_hang, where=cap)
            np.copyto(new.v[n:], self.bar.v, where=cap)
            np.copyto(fol_accel, (new.v[n:] - fol_v) / dt, where=cap)
        # The ground (z = 0, NED): a vehicle that reaches it stops there (and is flagged).
        below = new.p[:, 2] > 0.0
        if below.any():
            new.p[:, 2] = np.minimum(new.p[:, 2], 0.0)
            new.v[:, 2] = np.where(below, np.minimum(new.v[:, 2], 0.0), new.v[:, 2])
            self.ground_contact |= below[n:] | below[:n]
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


def _yaw(rot: np.ndarray) -> np.ndarray:
    """(n,) yaw of (n, 3, 3) rotations (ZYX)."""
    return np.arctan2(rot[:, 1, 0], rot[:, 0, 0])


def hover_command(params: VehicleParams, n: int) -> AttitudeCommand:
    """Level attitude at hover thrust (an open-loop command, e.g. for tests)."""
    zero = np.zeros(n)
    return AttitudeCommand(zero, zero.copy(), zero.copy(), np.full(n, params.hover_thrust_n))


__all__ = ["World", "Observation", "hover_command", "BarState", "GripperState", "VehicleState"]
