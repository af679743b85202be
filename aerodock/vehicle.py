"""Quadrotor parameters and dynamics: a pure, batch-first step function.

Model (NED): ``m a = m g e3 - R e3 T - c_d v + F_ext``; an inner attitude/thrust loop (the
autopilot) tracks commanded roll, pitch, yaw rate and collective thrust through first-order lags,
with tilt and thrust limits. ``T`` is the commanded thrust times a per-trial gain error (a constant
bias that exists with or without a leader, like a mis-estimated hover throttle).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from aerodock.config import Config
from aerodock.geometry import euler_to_rotmat


@dataclass(frozen=True)
class VehicleParams:
    """Constants of one quadrotor type (see ``[vehicle]`` in defaults.toml)."""

    mass_kg: float
    diagonal_m: float
    rotor_radius_m: float
    n_rotors: int
    drag_coeff_kgps: float
    tau_attitude_s: float
    tau_thrust_s: float
    tilt_max_rad: float
    thrust_max_n: float
    thrust_gain_sd: float
    accel_noise_mps2: float
    gravity_mps2: float

    @classmethod
    def from_config(cls, cfg: Config) -> VehicleParams:
        """Bind the ``[vehicle]`` and ``[sim]`` values of ``cfg``."""
        v = cfg.vehicle
        g = cfg.sim.gravity_mps2
        return cls(
            mass_kg=v.mass_kg, diagonal_m=v.diagonal_m, rotor_radius_m=v.rotor_radius_m,
            n_rotors=int(v.n_rotors), drag_coeff_kgps=v.drag_coeff_kgps,
            tau_attitude_s=v.tau_attitude_s, tau_thrust_s=v.tau_thrust_s,
            tilt_max_rad=np.deg2rad(v.tilt_max_deg), thrust_max_n=v.thrust_max_g * v.mass_kg * g,
            thrust_gain_sd=v.thrust_gain_sd, accel_noise_mps2=v.accel_noise_mps2,
            gravity_mps2=g,
        )

    @property
    def hover_thrust_n(self) -> float:
        """Thrust that balances gravity, N."""
        return self.mass_kg * self.gravity_mps2


@dataclass(frozen=True)
class VehicleState:
    """Batch of N vehicles: position, velocity (NED), ZYX Euler angles, actual thrust."""

    p: np.ndarray  # (n, 3) m
    v: np.ndarray  # (n, 3) m/s
    rpy: np.ndarray  # (n, 3) rad: roll, pitch, yaw
    thrust_cmd_state_n: np.ndarray  # (n,) thrust the inner loop currently produces (before gain)
    thrust_gain: np.ndarray  # (n,) multiplicative thrust error, ~1

    @property
    def n(self) -> int:
        """Batch size."""
        return int(self.p.shape[0])

    @property
    def R(self) -> np.ndarray:  # noqa: N802 - the rotation matrix is R by convention
        """(n, 3, 3) body-to-world rotation."""
        return euler_to_rotmat(self.rpy[:, 0], self.rpy[:, 1], self.rpy[:, 2])

    @property
    def thrust_n(self) -> np.ndarray:
        """(n,) actual collective thrust, N."""
        return self.thrust_cmd_state_n * self.thrust_gain


@dataclass(frozen=True)
class AttitudeCommand:
    """What the outer loop sends the autopilot, batch-first."""

    roll_rad: np.ndarray
    pitch_rad: np.ndarray
    yaw_rate_radps: np.ndarray
    thrust_n: np.ndarray


def hover_state(params: VehicleParams, p_m: np.ndarray, yaw_rad: np.ndarray | float = 0.0,
                rng: np.random.Generator | None = None) -> VehicleState:
    """Vehicles at rest at ``p_m`` (n, 3), thrust at hover; thrust gain errors drawn from ``rng``."""
    n = p_m.shape[0]
    rpy = np.zeros((n, 3))
    rpy[:, 2] = yaw_rad
    gain = np.ones(n)
    if rng is not None and params.thrust_gain_sd > 0:
        gain = 1.0 + params.thrust_gain_sd * rng.standard_normal(n)
    return VehicleState(
        p=np.array(p_m, dtype=float), v=np.zeros((n, 3)), rpy=rpy,
        thrust_cmd_state_n=np.full(n, params.hover_thrust_n) / gain, thrust_gain=gain,
    )


def step_vehicle(
    state: VehicleState,
    cmd: AttitudeCommand,
    ext_force_n: np.ndarray,
    params: VehicleParams,
    dt_s: float,
    R: np.ndarray | None = None,  # noqa: N803
) -> tuple[VehicleState, np.ndarray]:
    """Advance N vehicles by ``dt_s`` (semi-implicit Euler); returns (state, acceleration (n,3)).

    Args:
        state: current state.
        cmd: autopilot command (clipped here to the tilt and thrust limits).
        ext_force_n: (n, 3) external force (downwash, cable, contact), N, NED.
        params: vehicle constants.
        dt_s: physics step.
        R: the rotation of ``state`` if already computed (saves work in the hot loop).
    """
    if R is None:
        R = state.R
    thrust = state.thrust_n
    accel = (
        -R[:, :, 2] * (thrust / params.mass_kg)[:, None]
        - (params.drag_coeff_kgps / params.mass_kg) * state.v
        + ext_force_n / params.mass_kg
    )
    accel[:, 2] += params.gravity_mps2
    v = state.v + accel * dt_s
    p = state.p + v * dt_s
    # Inner loop: first-order lags towards the limited commands.
    tilt = params.tilt_max_rad
    alpha_att = dt_s / (params.tau_attitude_s + dt_s)
    alpha_thr = dt_s / (params.tau_thrust_s + dt_s)
    rpy = state.rpy.copy()
    rpy[:, 0] += alpha_att * (np.clip(cmd.roll_rad, -tilt, tilt) - rpy[:, 0])
    rpy[:, 1] += alpha_att * (np.clip(cmd.pitch_rad, -tilt, tilt) - rpy[:, 1])
    rpy[:, 2] = (rpy[:, 2] + cmd.yaw_rate_radps * dt_s + np.pi) % (2 * np.pi) - np.pi
    thrust_state = state.thrust_cmd_state_n + alpha_thr * (
        np.clip(cmd.thrust_n, 0.0, params.thrust_max_n) - state.thrust_cmd_state_n
    )
    return replace(state, p=p, v=v, rpy=rpy, thrust_cmd_state_n=thrust_state), accel
