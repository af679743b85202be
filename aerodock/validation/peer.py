"""The rigid-body vehicle against RotorPy: the same vehicle, the same rotor commands, open loop.

Issue 10 asks that aerodock's rigid-body quadrotor (:mod:`aerodock.world.vehicles.rigid_body`) and
an independent simulator, flying the same vehicle under the same rotor-speed commands, stay within
1 cm and 1 deg of each other over 5 s. The peer is RotorPy's ``Multirotor``
(``rotorpy.vehicles.multirotor``, its own ``solve_ivp`` integrator; install it with
``pip install --no-deps rotorpy``): nothing of RotorPy is copied here, it is called.

The command sequence is recorded from aerodock's autopilot flying an attitude manoeuvre (tilts of
several degrees on both axes, a yaw turn and thrust changes that move the vehicle tens of cm);
the recorded rotor-speed commands are then flown open loop by both simulators at 500 Hz (held over
each step), from the same hover state. Open loop, nothing corrects a difference: any mismatch of
the models (a sign, a frame, a missing term) grows with time.

Frames: aerodock's world is NED with body FRD; RotorPy's world is z-up with body FLU-like axes.
The map between them is ``F = diag(1, -1, -1)`` (a rotation by pi about x, so cross products
carry over): ``p_rp = F p``, ``R_rp = F R F``, ``w_rp = F w``, rotor positions ``F r``. A rotor's
yaw reaction torque is ``+s c_tau f`` about FRD z in aerodock (``s = +1``: counter-clockwise seen
from above), so in RotorPy ``rotor_directions = -s`` and ``k_m = c_tau k_T``.

Model terms: thrust ``k_T w^2``, yaw torque ratio, first-order motor lag, inertia and gyroscopic
torque, isotropic quadratic parasitic drag (``c_Dx = c_Dy = c_Dz``) and rotor drag (RotorPy's
H-force ``-w_i diag(k_d, k_d, k_z)`` times each rotor's local airspeed, with its moment about the
centre of mass) are in both. RotorPy's translational lift ``k_h`` and blade-flapping moment
``k_flap`` have no counterpart in aerodock and are set to zero (by design: not modelled).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from aerodock.config import Config
from aerodock.world.vehicles.point_mass import AttitudeCommand
from aerodock.world.vehicles.rigid_body import (
    RigidBodyParams,
    RigidBodyState,
    hover_rigid_state,
    rotor_speed_command,
    step_rigid_body,
)
from aerodock.world.vehicles.targets import rigid_targets

PEER_DURATION_S = 5.0
PEER_PHYSICS_HZ = 500.0
TOLERANCE_POSITION_M = 0.01
TOLERANCE_ATTITUDE_DEG = 1.0
FLIP = np.array([1.0, -1.0, -1.0])  # NED/FRD <-> RotorPy's z-up frames (rotation by pi about x)
START_ALTITUDE_M = 2.0


@dataclass(frozen=True)
class PeerRun:
    """Trajectories of one open-loop flight in aerodock's frames (world NED, body FRD)."""

    t_s: np.ndarray  # (k + 1,)
    p_m: np.ndarray  # (k + 1, 3)
    R: np.ndarray  # (k + 1, 3, 3) body to world  # noqa: N815
    rotor_speed_radps: np.ndarray  # (k + 1, 4)

    @property
    def rpy_rad(self) -> np.ndarray:
        """(k + 1, 3) ZYX Euler angles."""
        from aerodock.geometry import rotmat_to_euler

        return np.stack(rotmat_to_euler(self.R), axis=1)


@dataclass(frozen=True)
class PeerComparison:
    """aerodock and RotorPy flying the same rotor commands; their differences over time."""

    aerodock: PeerRun
    rotorpy: PeerRun
    rotor_speed_cmd_radps: np.ndarray  # (k, 4)
    aero: bool

    @property
    def position_error_m(self) -> np.ndarray:
        """(k + 1,) distance between the two positions."""
        return np.linalg.norm(self.aerodock.p_m - self.rotorpy.p_m, axis=1)

    @property
    def attitude_error_deg(self) -> np.ndarray:
        """(k + 1,) angle of the rotation between the two attitudes (geodesic distance)."""
        rel = np.matmul(self.aerodock.R.transpose(0, 2, 1), self.rotorpy.R)
        cos = (np.trace(rel, axis1=1, axis2=2) - 1.0) / 2.0
        return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))

    @property
    def travel_m(self) -> float:
        """Largest distance of aerodock's vehicle from its start."""
        return float(np.linalg.norm(self.aerodock.p_m - self.aerodock.p_m[0], axis=1).max())

    @property
    def tilt_max_deg(self) -> float:
        """Largest tilt of aerodock's vehicle (angle of body z from the vertical)."""
        return float(np.degrees(np.arccos(np.clip(self.aerodock.R[:, 2, 2], -1.0, 1.0))).max())

    def summary(self) -> dict[str, Any]:
        """The figures the README quotes."""
        return {
            "duration_s": float(self.aerodock.t_s[-1]),
            "physics_hz": PEER_PHYSICS_HZ,
            "aero": self.aero,
            "max_position_error_m": float(self.position_error_m.max()),
            "max_attitude_error_deg": float(self.attitude_error_deg.max()),
            "travel_m": self.travel_m,
            "tilt_max_deg": self.tilt_max_deg,
        }


def rigid_params(cfg: Config, aero: bool = True) -> RigidBodyParams:
    """aerodock's vehicle of ``cfg``; ``aero=False`` zeroes rotor and parasitic drag."""
    params = RigidBodyParams.from_config(cfg)
    if aero:
        return params
    from dataclasses import replace

    return replace(params, rotor_drag_coeff=0.0, rotor_drag_z_coeff=0.0,
                   parasitic_drag_coeff=0.0)


def manoeuvre_command(t_s: float, params: RigidBodyParams) -> AttitudeCommand:
    """The outer-loop command of the recorded manoeuvre at time ``t_s`` (one vehicle).

    Roll and pitch swing up to 8 deg on different periods, a 1 s yaw turn at 0.6 rad/s, and the
    collective varies by +-12 % of hover: the vehicle travels tens of cm in every direction.
    """
    deg = np.pi / 180.0
    roll = 6.0 * deg * np.sin(2.0 * np.pi * t_s / 2.5) * min(t_s / 0.5, 1.0)
    pitch = -8.0 * deg * np.sin(2.0 * np.pi * t_s / 4.0) * min(t_s / 0.5, 1.0)
    yaw_rate = 0.6 if 1.5 <= t_s < 2.5 else 0.0
    thrust = params.hover_thrust_n * (1.0 + 0.12 * np.sin(2.0 * np.pi * t_s / 3.0))
    one = np.ones(1)
    return AttitudeCommand(roll * one, pitch * one, yaw_rate * one, thrust * one)


def start_state(params: RigidBodyParams) -> RigidBodyState:
    """One vehicle hovering level at rest, ``START_ALTITUDE_M`` up, facing north."""
    return hover_rigid_state(params, np.array([[0.0, 0.0, -START_ALTITUDE_M]]), 0.0, np.ones(1))


def record_rotor_commands(params: RigidBodyParams, duration_s: float = PEER_DURATION_S,
                          physics_hz: float = PEER_PHYSICS_HZ) -> np.ndarray:
    """(k, 4) rotor-speed commands of aerodock's autopilot flying :func:`manoeuvre_command`
    (no gyro noise, no external load), one per physics step, rad/s."""
    dt = 1.0 / physics_hz
    steps = int(round(duration_s * physics_hz))
    state = start_state(params)
    zero = np.zeros((1, 3))
    cmds = np.empty((steps, 4))
    for k in range(steps):
        targets = rigid_targets(manoeuvre_command(k * dt, params), state, params, 1)
        speed, integral = rotor_speed_command(targets, state, params, state.w, dt)
        cmds[k] = speed[0]
        state, _ = step_rigid_body(state, speed, zero, None, params, dt)
        yaw_sp = state.yaw_setpoint + targets.yaw_rate_radps * dt
        from dataclasses import replace

        state = replace(state, autopilot_state=integral, yaw_setpoint=yaw_sp)
    return cmds


def fly_aerodock(params: RigidBodyParams, rotor_speed_cmd: np.ndarray,
                 physics_hz: float = PEER_PHYSICS_HZ) -> PeerRun:
    """aerodock's :func:`~aerodock.world.vehicles.rigid_body.step_rigid_body` flying
    ``rotor_speed_cmd`` (k, 4) open loop from :func:`start_state`."""
    dt = 1.0 / physics_hz
    state = start_state(params)
    zero = np.zeros((1, 3))
    steps = rotor_speed_cmd.shape[0]
    p, rot, speed = (np.empty((steps + 1, 3)), np.empty((steps + 1, 3, 3)),
                     np.empty((steps + 1, 4)))
    p[0], rot[0], speed[0] = state.p[0], state.R[0], state.rotor_speed[0]
    for k in range(steps):
        state, _ = step_rigid_body(state, rotor_speed_cmd[k:k + 1], zero, None, params, dt)
        p[k + 1], rot[k + 1], speed[k + 1] = state.p[0], state.R[0], state.rotor_speed[0]
    return PeerRun(np.arange(steps + 1) * dt, p, rot, speed)


def rotorpy_quad_params(params: RigidBodyParams) -> dict[str, Any]:
    """aerodock's vehicle as RotorPy's ``quad_params`` (keys of ``rotorpy.vehicles.multirotor``).

    Frames and signs as in the module docstring; RotorPy's drag coefficients are per rotor and
    per rad/s like aerodock's, so they carry over unchanged.
    """
    j = params.inertia_kgm2
    offsets = params.rotor_offsets_m * FLIP
    speed_max = float(np.sqrt(params.rotor_thrust_max_n / params.thrust_coeff))
    c_d = params.parasitic_drag_coeff
    return {
        "mass": params.mass_kg,
        "Ixx": float(j[0]), "Iyy": float(j[1]), "Izz": float(j[2]),
        "Ixy": 0.0, "Ixz": 0.0, "Iyz": 0.0,
        "num_rotors": 4,
        "rotor_radius": params.rotor_radius_m,
        "rotor_pos": {f"r{i + 1}": offsets[i].copy() for i in range(4)},
        "rotor_directions": -params.rotor_spin,
        "rI": np.zeros(3),
        "c_Dx": c_d, "c_Dy": c_d, "c_Dz": c_d,
        "k_eta": params.thrust_coeff,
        "k_m": params.torque_ratio_m * params.thrust_coeff,
        "k_d": params.rotor_drag_coeff,
        "k_z": params.rotor_drag_z_coeff,
        "k_h": 0.0,  # translational lift: not modelled in aerodock
        "k_flap": 0.0,  # blade flapping moment: not modelled in aerodock
        "tau_m": params.motor_tau_s,
        "rotor_speed_min": 0.0,
        "rotor_speed_max": speed_max,
        "motor_noise_std": 0.0,
    }


def fly_rotorpy(params: RigidBodyParams, rotor_speed_cmd: np.ndarray, aero: bool = True,
                physics_hz: float = PEER_PHYSICS_HZ,
                integrator_kwargs: dict[str, Any] | None = None) -> PeerRun:
    """RotorPy's ``Multirotor`` flying ``rotor_speed_cmd`` (k, 4) open loop from the same start
    (its own ``solve_ivp`` integration of every step); returned in aerodock's frames.

    Raises ImportError if RotorPy is not installed.
    """
    from rotorpy.vehicles.multirotor import Multirotor
    from scipy.spatial.transform import Rotation

    if params.gravity_mps2 != 9.81:
        raise ValueError(f"RotorPy's gravity is 9.81 m/s^2; aerodock's is {params.gravity_mps2}")
    dt = 1.0 / physics_hz
    start = start_state(params)
    rot0 = FLIP[:, None] * start.R[0] * FLIP[None, :]
    state = {"x": start.p[0] * FLIP, "v": start.v[0] * FLIP,
             "q": Rotation.from_matrix(rot0).as_quat(), "w": start.w[0] * FLIP,
             "wind": np.zeros(3), "rotor_speeds": start.rotor_speed[0].copy()}
    vehicle = Multirotor(rotorpy_quad_params(params),
                         initial_state={k: np.array(v) for k, v in state.items()},
                         control_abstraction="cmd_motor_speeds", aero=aero,
                         integrator_kwargs=integrator_kwargs)
    steps = rotor_speed_cmd.shape[0]
    p, rot, speed = (np.empty((steps + 1, 3)), np.empty((steps + 1, 3, 3)),
                     np.empty((steps + 1, 4)))

    def record(k: int, s: dict[str, np.ndarray]) -> None:
        p[k] = s["x"] * FLIP
        rot[k] = FLIP[:, None] * Rotation.from_quat(s["q"]).as_matrix() * FLIP[None, :]
        speed[k] = s["rotor_speeds"]

    record(0, state)
    for k in range(steps):
        state = vehicle.step(state, {"cmd_motor_speeds": rotor_speed_cmd[k]}, dt)
        record(k + 1, state)
    return PeerRun(np.arange(steps + 1) * dt, p, rot, speed)


def compare_with_rotorpy(cfg: Config, aero: bool = True, duration_s: float = PEER_DURATION_S,
                         integrator_kwargs: dict[str, Any] | None = None) -> PeerComparison:
    """Record the manoeuvre's rotor commands with aerodock's autopilot, fly them open loop in
    both simulators; ``aero=False`` turns rotor and parasitic drag off in both."""
    params = rigid_params(cfg, aero)
    cmds = record_rotor_commands(params, duration_s)
    return PeerComparison(fly_aerodock(params, cmds),
                          fly_rotorpy(params, cmds, aero, integrator_kwargs=integrator_kwargs),
                          cmds, aero)
