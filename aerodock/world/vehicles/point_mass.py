"""Quadrotor parameters and dynamics: a pure, batch-first step function.

Model (NED): ``m a = m g e3 - R e3 T - c_d v + F_ext``; an inner attitude/thrust loop (the
autopilot) tracks commanded roll, pitch, yaw rate and collective thrust through first-order lags,
with tilt and thrust limits. ``T`` is the commanded thrust times a per-trial gain error (a constant
bias that exists with or without a leader, like a mis-estimated hover throttle).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from aerodock.config import Config
from aerodock.config.schema import VehicleSection
from aerodock.frozen import freeze, is_frozen
from aerodock.geometry import rpy_to_rotmat
from aerodock.world.vehicles.body import VehicleBody, nominal_body


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
    def from_config(cls, cfg: Config, vehicle: VehicleSection | None = None) -> VehicleParams:
        """Bind the ``[vehicle]`` (or the given vehicle section, e.g. ``cfg.leader``) and
        ``[sim]`` values of ``cfg``."""
        v = cfg.vehicle if vehicle is None else vehicle
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
    """Batch of N vehicles: position, velocity (NED), ZYX Euler angles, actual thrust.

    The step makes ``rpy`` and ``thrust_gain`` read-only (:attr:`R` is kept per state for its
    read-only angles); ``p``, ``v`` and ``thrust_cmd_state_n`` are written in place by the
    constraints that act on a step's result (the ground, a leader's stand).
    """

    p: np.ndarray  # (n, 3) m
    v: np.ndarray  # (n, 3) m/s
    rpy: np.ndarray  # (n, 3) rad: roll, pitch, yaw
    thrust_cmd_state_n: np.ndarray  # (n,) thrust the inner loop currently produces (before gain)
    thrust_gain: np.ndarray  # (n,) multiplicative thrust error, ~1
    body: VehicleBody  # each vehicle's true mass (the point mass has no inertia or rotors)

    @property
    def n(self) -> int:
        """Batch size."""
        return int(self.p.shape[0])

    @property
    def R(self) -> np.ndarray:  # noqa: N802 - the rotation matrix is R by convention
        """(n, 3, 3) body-to-world rotation, read-only (kept on the state while its angles are
        the same read-only array: a step reads the same state's twice)."""
        rpy = self.rpy
        hit = self.__dict__.get("_rotation")  # not a field: numbers derived from one
        if hit is not None and hit[0] is rpy and is_frozen(rpy):
            return hit[1]
        rot = rpy_to_rotmat(rpy)
        freeze(rot)
        self.__dict__["_rotation"] = (rpy, rot)
        return rot

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
    # (n, 3) body torque, N m, added to the rate loop's torque before the mixer (a feed-forward,
    # e.g. minus the wake's predicted torque); None: none. Rigid-body vehicles only.
    torque_ff_nm: np.ndarray | None = None


def hover_state(params: VehicleParams, p_m: np.ndarray, yaw_rad: np.ndarray | float = 0.0,
                rng: np.random.Generator | None = None,
                body: VehicleBody | None = None) -> VehicleState:
    """Vehicles at rest at ``p_m`` (n, 3), thrust at hover; thrust gain errors from ``rng``;
    ``body``: each vehicle's true mass (default: nominal)."""
    n = p_m.shape[0]
    if body is None:
        body = nominal_body(params.mass_kg, np.zeros(3), 0.0, n)
    rpy = np.zeros((n, 3))
    rpy[:, 2] = yaw_rad
    gain = np.ones(n)
    if rng is not None and params.thrust_gain_sd > 0:
        gain = 1.0 + params.thrust_gain_sd * rng.standard_normal(n)
    freeze(rpy, gain)
    return VehicleState(
        p=np.array(p_m, dtype=float), v=np.zeros((n, 3)), rpy=rpy,
        thrust_cmd_state_n=body.mass_kg * params.gravity_mps2 / gain, thrust_gain=gain,
        body=body,
    )


def thrust_axis(rpy: np.ndarray) -> np.ndarray:
    """(n, 3) body z axis in the world, ``R[:, :, 2]`` of :func:`rpy_to_rotmat` bit for bit."""
    c = np.cos(rpy)
    s = np.sin(rpy)
    cr, cp, cy = c[:, 0], c[:, 1], c[:, 2]
    sr, sp, sy = s[:, 0], s[:, 1], s[:, 2]
    axis = np.empty_like(rpy)
    np.add(cy * sp * cr, sy * sr, out=axis[:, 0])
    np.subtract(sy * sp * cr, cy * sr, out=axis[:, 1])
    np.multiply(cp, cr, out=axis[:, 2])
    return axis


@dataclass(frozen=True)
class CommandTargets:
    """An :class:`AttitudeCommand` clipped to the limits, ready for the inner loop.

    Prepared once per control period by :func:`command_targets` (the command is held for all the
    physics steps of the period).
    """

    roll_pitch_rad: np.ndarray  # (n, 2) clipped roll and pitch
    yaw_step_rad: np.ndarray  # (n,) yaw rate times the physics step
    thrust_n: np.ndarray  # (n,) clipped thrust


def command_targets(cmd: AttitudeCommand, params: VehicleParams, dt_s: float,
                    n: int) -> CommandTargets:
    """Clip the commands of ``n`` vehicles to the tilt and thrust limits (:func:`step_vehicle`)."""
    tilt = params.tilt_max_rad
    rp = np.empty((n, 2))
    np.clip(cmd.roll_rad, -tilt, tilt, out=rp[:, 0])
    np.clip(cmd.pitch_rad, -tilt, tilt, out=rp[:, 1])
    return CommandTargets(rp, cmd.yaw_rate_radps * dt_s,
                          np.clip(cmd.thrust_n, 0.0, params.thrust_max_n))


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
    targets = command_targets(cmd, params, dt_s, state.n)
    return step_vehicle_targets(state, targets, ext_force_n, params, dt_s, R)


def step_vehicle_targets(
    state: VehicleState,
    targets: CommandTargets,
    ext_force_n: np.ndarray,
    params: VehicleParams,
    dt_s: float,
    R: np.ndarray | None = None,  # noqa: N803
) -> tuple[VehicleState, np.ndarray]:
    """:func:`step_vehicle` with the command already clipped (:func:`command_targets`)."""
    body = state.body
    m = body.mass_kg
    # m a = m g e3 - R e3 T - c_d v + F_ext, evaluated as in the formula, left to right.
    accel = np.negative(thrust_axis(state.rpy) if R is None else R[:, :, 2])
    accel *= (state.thrust_cmd_state_n * state.thrust_gain / m)[:, None]
    accel -= (params.drag_coeff_kgps / body.mass_rows_kg) * state.v
    accel += ext_force_n / body.mass_rows_kg
    accel[:, 2] += params.gravity_mps2
    v = accel * dt_s
    v += state.v
    p = v * dt_s
    p += state.p
    # Inner loop: first-order lags towards the limited commands.
    alpha_att = dt_s / (params.tau_attitude_s + dt_s)
    alpha_thr = dt_s / (params.tau_thrust_s + dt_s)
    old = state.rpy
    rpy = np.empty_like(old)
    rp = old[:, :2]
    step = targets.roll_pitch_rad - rp
    step *= alpha_att
    np.add(rp, step, out=rpy[:, :2])
    yaw = old[:, 2] + targets.yaw_step_rad
    yaw += np.pi
    yaw %= 2 * np.pi
    np.subtract(yaw, np.pi, out=rpy[:, 2])
    freeze(rpy)  # the state's R is kept for these angles (VehicleState.R)
    tcs = state.thrust_cmd_state_n
    thrust_state = targets.thrust_n - tcs
    thrust_state *= alpha_thr
    thrust_state += tcs
    return VehicleState(p, v, rpy, thrust_state, state.thrust_gain, state.body), accel
