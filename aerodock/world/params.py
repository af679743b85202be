"""The world's constants, bound once from the configuration into typed structs."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from aerodock.config import Config
from aerodock.world.attitude_estimator import AttitudeEstimatorParams
from aerodock.world.gripper import GripperParams
from aerodock.world.imu import Biquad, ImuChainParams
from aerodock.world.platform import PlatformParams
from aerodock.world.vehicles.body import SpreadParams
from aerodock.world.vehicles.fleet import (
    Fleet,
    PairFleet,
    PointMassFleet,
    RigidBodyFleet,
    build_fleet,
    same_state_width,
)
from aerodock.world.vehicles.point_mass import VehicleParams


@dataclass(frozen=True)
class ImuParams:
    """What the flight computers' IMUs add to the truth (``[imu]``; rigid-body vehicles)."""

    gyro_noise_radps: float  # sd per physics sample (both vehicles' autopilots)
    accel_vibration_mps2: float  # motor vibration per sample at hover rotor speed (~ speed^2)
    accel_bias_sd_mps2: float  # residual bias after calibration, per trial and axis
    attitude_noise_rad: float  # chain "ideal": sd of the attitude the controllers see
    filtered: bool  # chain "filtered": the IMU chain and the attitude estimator (imu.py)
    chain: ImuChainParams
    estimator: AttitudeEstimatorParams

    @classmethod
    def from_config(cls, cfg: Config) -> ImuParams:
        """Bind ``[imu]`` of ``cfg``."""
        imu = cfg.imu
        dt_s = cfg.timing.physics_dt_s
        chain = ImuChainParams(
            gyro_cutoff_hz=imu.gyro_cutoff_hz, accel_cutoff_hz=imu.accel_cutoff_hz,
            delay_steps=int(round(imu.latency_s / dt_s)),
            gyro_range_radps=float(np.deg2rad(imu.gyro_range_dps)),
            accel_range_mps2=imu.accel_range_g * cfg.sim.gravity_mps2)
        return cls(imu.gyro_noise_radps, imu.accel_vibration_mps2, imu.accel_bias_sd_mps2,
                   imu.attitude_noise_rad, imu.chain == "filtered", chain,
                   AttitudeEstimatorParams(imu.accel_gain_radps, imu.heading_gain_radps))


@dataclass(frozen=True)
class MocapParams:
    """Motion capture (``[mocap]``): noise on what the controllers see, and its latency."""

    pos_noise_m: float
    vel_noise_mps: float
    latency_s: float

    @classmethod
    def from_config(cls, cfg: Config) -> MocapParams:
        """Bind ``[mocap]`` of ``cfg``."""
        m = cfg.mocap
        return cls(m.pos_noise_m, m.vel_noise_mps, m.latency_s)


@dataclass(frozen=True)
class WorldParams:
    """Every constant the world step and its sensors read (nothing reads the config later).

    Attributes:
        vehicle: the follower's nominal constants (mass, gravity, limits, accelerometer noise).
        leader_vehicle: the leader's nominal constants (the follower's unless ``[leader]``
            differs).
        leader_fleet, follower_fleet: each vehicle's model with its nominal parameters.
        fleet: what steps the 2n batch: the one fleet of a homogeneous pair, or a
            :class:`~aerodock.world.vehicles.fleet.PairFleet`.
        spread, leader_spread: each vehicle type's fleet spread (the true vehicles' draws).
        platform: the bar and its cables.
        gripper: the follower's gripper (and which triggers are armed).
        imu, mocap: the sensors.
        dt_s: physics step, s; ``substeps`` of them make one control period ``dt_control_s``.
        latency_steps: motion capture's latency in physics steps.
    """

    vehicle: VehicleParams
    leader_vehicle: VehicleParams
    leader_fleet: PointMassFleet | RigidBodyFleet
    follower_fleet: PointMassFleet | RigidBodyFleet
    fleet: Fleet
    spread: SpreadParams
    leader_spread: SpreadParams
    platform: PlatformParams
    gripper: GripperParams
    imu: ImuParams
    mocap: MocapParams
    dt_s: float
    substeps: int
    dt_control_s: float
    latency_steps: int

    @classmethod
    def from_config(cls, cfg: Config) -> WorldParams:
        """Bind every world constant of ``cfg``."""
        timing = cfg.timing
        dt_s = timing.physics_dt_s
        follower = build_fleet(cfg)
        leader = (build_fleet(cfg, cfg.leader, cfg.leader_autopilot) if cfg.leader_differs
                  else follower)
        if leader is not follower:
            leader, follower = same_state_width(leader, follower)
        return cls(
            vehicle=VehicleParams.from_config(cfg),
            leader_vehicle=VehicleParams.from_config(cfg, cfg.leader), leader_fleet=leader,
            follower_fleet=follower,
            fleet=follower if leader is follower else PairFleet(leader, follower),
            spread=SpreadParams.from_section(cfg.vehicle),
            leader_spread=SpreadParams.from_section(cfg.leader),
            platform=PlatformParams.from_config(cfg), gripper=GripperParams.from_config(cfg),
            imu=ImuParams.from_config(cfg), mocap=MocapParams.from_config(cfg), dt_s=dt_s,
            substeps=timing.substeps, dt_control_s=timing.control_dt_s,
            latency_steps=int(round(cfg.mocap.latency_s / dt_s)),
        )

    @property
    def rigid(self) -> bool:
        """Rigid-body vehicles (attitude, rotors, torques) rather than point masses."""
        return self.fleet.has_torque

    @property
    def filtered_imu(self) -> bool:
        """The flight computers fly their IMU chain and attitude estimate (rigid bodies)."""
        return self.rigid and self.imu.filtered

    @property
    def gyro_filter(self) -> Biquad | None:
        """The gyro's software low-pass at the physics rate."""
        return Biquad.butterworth(self.imu.chain.gyro_cutoff_hz, self.dt_s)

    @property
    def accel_filter(self) -> Biquad | None:
        """The accelerometer's software low-pass at the physics rate."""
        return Biquad.butterworth(self.imu.chain.accel_cutoff_hz, self.dt_s)

    def with_triggers(self, passive: bool | np.ndarray, active: bool | np.ndarray) -> WorldParams:
        """The same world with these triggers armed (for every trial, or (n,) per trial)."""
        return replace(self, gripper=replace(self.gripper, passive=passive, active=active))
