"""Rigid-body quadrotor: attitude and body-rate dynamics, four rotors with motor lag, rotor drag.

The vehicle DESIGN.md asks for, batch-first and pure (one call advances N vehicles)::

    m dv/dt = m g e3 + R (F_rotor_drag - T e3) - c_D |v| v + F_ext            (world NED)
    J dw/dt = tau_rotors + tau_ext - w x J w                                 (body FRD)
    dR/dt   = R [w]x
    d omega_i/dt = (omega_cmd_i - omega_i) / tau_motor,   f_i = k_T omega_i^2 (x thrust gain)

with ``T = sum f_i``, rotor torques ``tau = sum r_i x (-f_i e3) + s_i c_tau f_i e3`` (X layout,
spin directions as PX4's quad X), rotor drag as RotorPy models it (the H-force of blades in
edgewise flow and the induced-inflow force along the axis): on rotor ``i``, with its local
airspeed ``u_i = v_b + w x r_i`` (body frame), ``H_i = -omega_i diag(k_d, k_d, k_z) u_i`` acting
at the rotor hub, so ``F_rotor_drag = sum H_i`` with the moment ``sum r_i x H_i`` (the rotors'
damping of roll, pitch and yaw rates), and quadratic parasitic drag. External forces (downwash,
cable, contact) arrive as a world force and a body torque about the centre of mass, so
off-centre loads (the wake on each rotor disk, the cable anchor below the leader) tilt the
vehicle.

The autopilot (:mod:`aerodock.world.vehicles.autopilot`) runs inside the step at the physics rate,
on the gyro's noisy rates: it is part of the vehicle, as on the aircraft. Integration: angular
velocity and velocity by explicit Euler on the current derivatives, position and attitude on the
mean of old and new rates (trapezoid; attitude by the exact Rodrigues exponential, so ``R`` stays
orthonormal), motor speeds by the exact first-order step.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from aerodock.config import Config
from aerodock.config.schema import AutopilotSection, VehicleSection
from aerodock.downwash.base import frozen_record
from aerodock.frozen import freeze, is_frozen
from aerodock.geometry import rotmat_to_rpy
from aerodock.jit import any_layout, njit
from aerodock.world.vehicles import rigid_kernel
from aerodock.world.vehicles.autopilot import AutopilotGains, autopilot_constants
from aerodock.world.vehicles.body import VehicleBody, nominal_body
from aerodock.world.vehicles.stacks import stack_constants, state_columns
from aerodock.world.vehicles.targets import RigidTargets


@dataclass(frozen=True)
class RigidBodyParams:
    """Constants of one rigid-body quadrotor type (``[vehicle]`` and ``[autopilot]``)."""

    mass_kg: float
    inertia_kgm2: np.ndarray  # (3,) principal moments, body FRD
    rotor_offsets_m: np.ndarray  # (4, 3) rotor-disk centres, body FRD
    rotor_spin: np.ndarray  # (4,) +1 counter-clockwise seen from above, -1 clockwise
    rotor_radius_m: float
    thrust_coeff: float  # k_T, N per (rad/s)^2
    torque_ratio_m: float  # c_tau: yaw reaction torque per N of thrust
    motor_tau_s: float
    rotor_drag_coeff: float  # k_d, N per (m/s) per (rad/s), in-plane
    rotor_drag_z_coeff: float  # k_z, the same along the rotor axis
    parasitic_drag_coeff: float  # c_D, N per (m/s)^2
    rotor_thrust_max_n: float
    tilt_max_rad: float
    gravity_mps2: float
    gains: AutopilotGains
    mixer_inv: np.ndarray  # (4, 4): [T, tau_x, tau_y, tau_z] -> rotor thrusts
    rotor_torque_map: np.ndarray  # (4, 3): rotor thrusts -> body torque
    rotor_drag_sums: np.ndarray  # (4, 7): rotor speeds -> sums of omega_i [1, -y, x, y, x^2, y^2,
    # xy] (the rotor drag's, _DRAG_SUM_COLUMNS)
    stack_constants: np.ndarray | None = None  # the flight stack's loops in SI (stacks.py);
    # None: the generic autopilot
    autopilot_state_columns: int = 3  # numbers of autopilot state per vehicle

    @classmethod
    def from_config(cls, cfg: Config, vehicle: VehicleSection | None = None,
                    autopilot: AutopilotSection | None = None) -> RigidBodyParams:
        """Bind ``[vehicle]`` (or the given vehicle section, e.g. ``cfg.leader``),
        ``[autopilot]`` (or the given one, e.g. ``cfg.leader_autopilot``) and ``[sim]`` of
        ``cfg``."""
        v = cfg.vehicle if vehicle is None else vehicle
        a = cfg.autopilot if autopilot is None else autopilot
        g = cfg.sim.gravity_mps2
        n_rotors = int(v.n_rotors)
        if n_rotors != 4:
            raise ValueError(f"the rigid-body vehicle is a quadrotor: vehicle.n_rotors must be 4, "
                             f"got {n_rotors} (use vehicle.model = 'point-mass')")
        arm = v.diagonal_m / 2.0
        angles = np.deg2rad([45.0, 135.0, 225.0, 315.0])  # FR, RR, RL, FL (x fwd, y right)
        offsets = np.stack([arm * np.cos(angles), arm * np.sin(angles), np.zeros(4)], axis=1)
        spin = np.array([1.0, -1.0, 1.0, -1.0])
        # tau = r x (-f e3) = (-y f, x f, 0); yaw reaction s c_tau f.
        torque_map = np.stack([-offsets[:, 1], offsets[:, 0], spin * v.rotor_torque_ratio_m],
                              axis=1)
        x, y = offsets[:, 0], offsets[:, 1]  # the rotor disks lie in the body x-y plane
        columns = {"1": np.ones(4), "x": x, "y": y, "-y": -y, "xx": x * x, "yy": y * y,
                   "xy": x * y}
        drag_sums = np.stack([columns[c] for c in _DRAG_SUM_COLUMNS], axis=1)
        mixer = np.vstack([np.ones(4), torque_map.T])
        gains = AutopilotGains(
            attitude_p=np.array(a.attitude_p, dtype=float),
            rate_p=np.array(a.rate_p, dtype=float), rate_i=np.array(a.rate_i, dtype=float),
            rate_integral_max_radps2=float(a.rate_integral_max_radps2),
            rate_max_radps=np.deg2rad(np.asarray(a.rate_max_dps, dtype=float)),
        )
        inertia = np.array(v.inertia_kgm2, dtype=float)
        mixer_inv = np.linalg.inv(mixer).T.copy()
        thrust_max = v.thrust_max_g * v.mass_kg * g / 4.0
        # Constants, read-only: the autopilot's gain columns and the downwash field's geometry
        # are cached by these arrays (autopilot_constants, RoundJetField.wrench).
        freeze(gains.attitude_p, gains.rate_p, gains.rate_i, gains.rate_max_radps, inertia,
               offsets, spin, torque_map, drag_sums, mixer_inv)
        return cls(
            mass_kg=v.mass_kg, inertia_kgm2=inertia,
            rotor_offsets_m=offsets, rotor_spin=spin, rotor_radius_m=v.rotor_radius_m,
            thrust_coeff=v.rotor_thrust_coeff, torque_ratio_m=v.rotor_torque_ratio_m,
            motor_tau_s=v.motor_tau_s, rotor_drag_coeff=v.rotor_drag_coeff,
            rotor_drag_z_coeff=v.rotor_drag_z_coeff,
            parasitic_drag_coeff=v.parasitic_drag_coeff,
            rotor_thrust_max_n=thrust_max,
            tilt_max_rad=np.deg2rad(v.tilt_max_deg), gravity_mps2=g, gains=gains,
            mixer_inv=mixer_inv, rotor_torque_map=torque_map,
            rotor_drag_sums=drag_sums,
            stack_constants=stack_constants(a, arm, thrust_max, v.rotor_torque_ratio_m),
            autopilot_state_columns=state_columns(a),
        )

    @property
    def hover_thrust_n(self) -> float:
        """Thrust that balances gravity, N."""
        return self.mass_kg * self.gravity_mps2

    @property
    def thrust_max_n(self) -> float:
        """Collective thrust with every rotor at its maximum, N."""
        return 4.0 * self.rotor_thrust_max_n


@dataclass(frozen=True)
class RigidBodyState:
    """Batch of N rigid-body vehicles with their autopilots' state."""

    p: np.ndarray  # (n, 3) m, world NED
    v: np.ndarray  # (n, 3) m/s
    R: np.ndarray  # (n, 3, 3) body to world
    w: np.ndarray  # (n, 3) rad/s, body rates
    rotor_speed: np.ndarray  # (n, 4) rad/s
    autopilot_state: np.ndarray  # (n, k): the generic autopilot's rate integral (k = 3, rad),
    # or a flight stack's loops' state (stack_kernel.STATE_COLUMNS)
    yaw_setpoint: np.ndarray  # (n,) rad, the autopilot's yaw target (integrated yaw rate)
    thrust_gain: np.ndarray  # (n,) multiplicative thrust error (mis-estimated k_T), ~1
    thrust_n: np.ndarray  # (n,) actual collective thrust, N (from the rotor speeds)
    body: VehicleBody  # the true mass, inertia, torque coefficient and motor lag of each vehicle

    @property
    def n(self) -> int:
        """Batch size."""
        return int(self.p.shape[0])

    @property
    def rpy(self) -> np.ndarray:
        """(n, 3) ZYX Euler angles, rad."""
        return rotmat_to_rpy(self.R)


def rotor_thrusts_n(rotor_speed: np.ndarray, thrust_gain: np.ndarray,
                    params: RigidBodyParams) -> np.ndarray:
    """(n, 4) actual thrust of each rotor, N, from rotor speeds (n, 4) and thrust gains (n,)."""
    f = rotor_speed * rotor_speed
    f *= (params.thrust_coeff * thrust_gain)[:, None]
    return f


def hover_rigid_state(params: RigidBodyParams, p_m: np.ndarray, yaw_rad: np.ndarray | float,
                      thrust_gain: np.ndarray, body: VehicleBody | None = None) -> RigidBodyState:
    """Vehicles at rest at ``p_m`` (n, 3), level, rotors at the speed that balances gravity
    (each vehicle's true weight; ``body`` default: every vehicle as nominal)."""
    n = p_m.shape[0]
    if body is None:
        body = nominal_body(params.mass_kg, params.inertia_kgm2, params.motor_tau_s, n)
    weight = body.mass_kg * params.gravity_mps2
    yaw = np.broadcast_to(np.asarray(yaw_rad, dtype=float), (n,)).copy()
    c, s = np.cos(yaw), np.sin(yaw)
    rot = np.zeros((n, 3, 3))
    rot[:, 0, 0], rot[:, 0, 1], rot[:, 1, 0], rot[:, 1, 1], rot[:, 2, 2] = c, -s, s, c, 1.0
    omega = np.sqrt(weight / 4.0 / (params.thrust_coeff * thrust_gain))
    gain = np.array(thrust_gain, dtype=float)
    freeze(gain)  # constant: the step's k_T is cached by it (_thrust_coeffs)
    return RigidBodyState(
        p=np.array(p_m, dtype=float), v=np.zeros((n, 3)), R=rot, w=np.zeros((n, 3)),
        rotor_speed=np.repeat(omega[:, None], 4, axis=1),
        autopilot_state=np.zeros((n, params.autopilot_state_columns)),
        yaw_setpoint=yaw, thrust_gain=gain,
        thrust_n=weight, body=body,
    )


_NO_ROWS = np.zeros((1, 4))  # the kernels' placeholder for an absent (n, k) input
freeze(_NO_ROWS)


def kernel_constants(params: RigidBodyParams) -> tuple[np.ndarray, ...]:
    """The vehicle's constant matrices as the kernels take them (flat, row-major): the
    autopilot's loop constants, the mixer, the torque map and the rotor drag's sums (kept on
    ``params``)."""
    hit = params.__dict__.get("_kernel_constants")
    if hit is None:
        hit = (rigid_kernel.flat(autopilot_constants(params.gains, params.inertia_kgm2)),
               rigid_kernel.flat(params.mixer_inv),
               rigid_kernel.flat(params.rotor_torque_map),
               rigid_kernel.flat(params.rotor_drag_sums))
        params.__dict__["_kernel_constants"] = hit
    return hit


def rotor_speed_command(targets: RigidTargets, state: RigidBodyState, params: RigidBodyParams,
                        gyro_radps: np.ndarray, dt_s: float,
                        attitude: np.ndarray | None = None,
                        gyro_noise_radps: np.ndarray | None = None,
                        ) -> tuple[np.ndarray, np.ndarray]:
    """The autopilot: (commanded rotor speeds (n, 4) rad/s, new autopilot state), on the
    gyro's rates (``gyro_radps`` plus ``gyro_noise_radps``) and its attitude estimate
    (``attitude``; None: the true attitude). Compiled: :func:`rigid_kernel.autopilot`."""
    n = state.R.shape[0]
    cmd, integral = np.empty((n, 4)), np.empty((n, params.autopilot_state_columns))
    ff = targets.torque_ff_nm
    consts, mixer, _, _ = kernel_constants(params)
    rigid_kernel.autopilot_batch(
        state.R if attitude is None else attitude, targets.R_des, targets.yaw_rate_radps,
        targets.thrust_n, _NO_ROWS if ff is None else ff, ff is not None, gyro_radps,
        _NO_ROWS if gyro_noise_radps is None else gyro_noise_radps,
        gyro_noise_radps is not None, state.autopilot_state, consts,
        params.stack_constants is not None, _stack(params), mixer, params.rotor_thrust_max_n,
        params.thrust_coeff, dt_s, cmd, integral)
    return cmd, integral


def body_wrench(rotor_speed: np.ndarray, thrust_gain: np.ndarray, v_body_mps: np.ndarray,
                w_radps: np.ndarray, params: RigidBodyParams) -> tuple[np.ndarray, np.ndarray]:
    """The rotors' force and torque on N vehicles, body FRD: ((n, 3) N, (n, 3) N m).

    Thrust ``-f_i e3`` and yaw reaction at each rotor, and rotor drag at each hub:
    ``H_i = -omega_i diag(k_d, k_d, k_z) (v_b + w x r_i)`` (RotorPy's H-force and induced-inflow
    terms, per rotor on its local airspeed). With the hubs in the body x-y plane the sums over
    rotors reduce to the weighted sums ``S = sum omega_i [1, x_i, y_i, x_i^2, y_i^2, x_i y_i]``.
    Compiled: :func:`rigid_kernel.rotor_wrench`.

    Args:
        rotor_speed: (n, 4) rotor speeds, rad/s.
        thrust_gain: (n,) multiplicative thrust error.
        v_body_mps: (n, 3) velocity relative to the air, body frame.
        w_radps: (n, 3) body rates.
        params: vehicle constants.
    """
    omega = np.asarray(rotor_speed, dtype=float)
    n = omega.shape[0]
    force, torque = np.empty((n, 3)), np.empty((n, 3))
    _, _, torque_map, drag_sums = kernel_constants(params)
    rigid_kernel.wrench_batch(omega, params.thrust_coeff * np.asarray(thrust_gain, dtype=float),
                              np.ones(n), np.asarray(v_body_mps, dtype=float),
                              np.asarray(w_radps, dtype=float), torque_map, drag_sums,
                              params.rotor_drag_coeff, params.rotor_drag_z_coeff, force, torque)
    return force, torque


# The rotor drag's weighted sums S = sum_i omega_i c_i (columns c of ``rotor_drag_sums``).
_DRAG_SUM_COLUMNS = ("1", "-y", "x", "y", "xx", "yy", "xy")


def _thrust_coeffs(body: VehicleBody, thrust_coeff: float,
                   thrust_gain: np.ndarray) -> np.ndarray:
    """(n,) each vehicle's true k_T, ``thrust_coeff * thrust_gain``, read-only: kept on
    ``body`` (states carry both the body and the gain over unchanged, so one product serves
    every step) while ``thrust_gain`` is the same read-only array."""
    hit = body.__dict__.get("_thrust_coeffs")  # not a field: numbers derived from it
    if (hit is not None and hit[0] is thrust_gain and hit[1] == thrust_coeff
            and is_frozen(thrust_gain)):
        return hit[2]
    coeffs = thrust_coeff * thrust_gain
    freeze(coeffs)
    body.__dict__["_thrust_coeffs"] = (thrust_gain, thrust_coeff, coeffs)
    return coeffs


def _body_constants(body: VehicleBody, dt_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Per-step constants of ``body``'s vehicles: the motors' first-order step factor
    ``1 - exp(-dt / tau)`` (NumPy's exp: (n,), or (1,) when every vehicle's motors are alike)
    and the inertia (n, 3), C-ordered; read-only, kept on ``body`` for the last ``dt_s`` while
    its arrays are read-only (a :class:`VehicleBody` makes them so)."""
    tau, inertia = body.motor_tau_s, body.inertia_kgm2
    hit = body.__dict__.get("_step_constants")  # not a field: numbers derived from it
    if hit is not None and hit[0] == dt_s and is_frozen(tau) and is_frozen(inertia):
        return hit[1]
    alpha = (np.array([1.0 - np.exp(-dt_s / float(tau[0]))]) if np.all(tau == tau[0])
             else 1.0 - np.exp(-dt_s / tau))
    rows = np.ascontiguousarray(inertia, dtype=float)
    freeze(alpha, rows)
    body.__dict__["_step_constants"] = (dt_s, (alpha, rows))
    return alpha, rows


def step_rigid_body(state: RigidBodyState, rotor_speed_cmd: np.ndarray, ext_force_n: np.ndarray,
                    ext_torque_nm: np.ndarray | None, params: RigidBodyParams,
                    dt_s: float) -> tuple[RigidBodyState, np.ndarray]:
    """Advance N vehicles by ``dt_s`` under rotor-speed commands; returns (state, accel (n, 3)).

    Args:
        state: current state (its autopilot fields are carried over unchanged).
        rotor_speed_cmd: (n, 4) commanded rotor speeds, rad/s.
        ext_force_n: (n, 3) external force at the centre of mass, world NED, N.
        ext_torque_nm: (n, 3) external torque about the centre of mass, body FRD, N m (or None).
        params: vehicle constants.
        dt_s: physics step.
    """
    p, v, rot, w, omega, thrust, accel, _, _ = _step_arrays(state, rotor_speed_cmd,
                                                            ext_force_n, ext_torque_nm, params,
                                                            dt_s)
    return RigidBodyState(p, v, rot, w, omega, state.autopilot_state, state.yaw_setpoint,
                          state.thrust_gain, thrust, state.body), accel


def _step_arrays(state: RigidBodyState, rotor_speed_cmd: np.ndarray | None,
                 ext_force_n: np.ndarray, ext_torque_nm: np.ndarray | None,
                 params: RigidBodyParams, dt_s: float, targets: RigidTargets | None = None,
                 gyro: np.ndarray | None = None, gyro_noise: np.ndarray | None = None,
                 attitude: np.ndarray | None = None) -> tuple[np.ndarray, ...]:
    """:func:`step_rigid_body`'s new (p, v, R, w, rotor speeds, thrust, accel, rate integral,
    yaw setpoint) from the compiled :func:`rigid_kernel.step_vehicles`: under the rotor speed
    commands ``rotor_speed_cmd``, or (None) flown by the autopilot to ``targets`` on ``gyro``
    (plus ``gyro_noise``) and ``attitude`` (None: the true attitude), the world's step, through
    :func:`flown_step` with the constants packed (:func:`_packed_constants`)."""
    n = state.p.shape[0]
    out = (np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3, 3)), np.empty((n, 3)),
           np.empty((n, 4)), np.empty(n), np.empty((n, 3)),
           np.empty((n, params.autopilot_state_columns)), np.empty(n))
    if targets is not None:  # the world's step: its constants packed once they are kept
        arguments, packed = _packed_constants(state.body, params, dt_s, state.thrust_gain)
        ff = targets.torque_ff_nm
        if packed is not None:
            flown_step(
                packed, state.p, state.v, state.R, state.w, state.rotor_speed,
                _NO_ATTITUDE if attitude is None else attitude, attitude is not None,
                targets.R_des, targets.yaw_rate_radps, targets.thrust_n,
                _NO_ROWS if ff is None else ff, ff is not None, state.w if gyro is None else gyro,
                _NO_ROWS if gyro_noise is None else gyro_noise, gyro_noise is not None,
                state.autopilot_state, state.yaw_setpoint, np.asarray(ext_force_n, dtype=float),
                _NO_ROWS if ext_torque_nm is None else np.asarray(ext_torque_nm, dtype=float),
                ext_torque_nm is not None, *out)
            return out
        (kc, torque_gain, mass_rows, inertia, alpha, consts, has_stack, stack, mixer,
         thrust_max, thrust_coeff, torque_map, drag_sums, drag, drag_z, parasitic,
         gravity) = arguments
        rigid_kernel.step_vehicles(
            state.p, state.v, state.R, state.w, state.rotor_speed, kc, torque_gain, mass_rows,
            inertia, alpha, True, _NO_ROWS, _NO_ATTITUDE if attitude is None else attitude,
            attitude is not None, targets.R_des, targets.yaw_rate_radps, targets.thrust_n,
            _NO_ROWS if ff is None else ff, ff is not None, state.w if gyro is None else gyro,
            _NO_ROWS if gyro_noise is None else gyro_noise, gyro_noise is not None,
            state.autopilot_state, state.yaw_setpoint, consts, has_stack, stack, mixer,
            thrust_max, thrust_coeff, np.asarray(ext_force_n, dtype=float),
            _NO_ROWS if ext_torque_nm is None else np.asarray(ext_torque_nm, dtype=float),
            ext_torque_nm is not None, torque_map, drag_sums, drag, drag_z, parasitic, gravity,
            dt_s, *out)
        return out
    (kc, torque_gain, mass_rows, inertia, alpha, consts, has_stack, stack, mixer, thrust_max,
     thrust_coeff, torque_map, drag_sums, drag, drag_z, parasitic, gravity) = _step_constants(
        state.body, params, dt_s, state.thrust_gain)
    rigid_kernel.step_vehicles(
        state.p, state.v, state.R, state.w, state.rotor_speed, kc, torque_gain, mass_rows,
        inertia, alpha, False, np.asarray(rotor_speed_cmd, dtype=float),
        _NO_ATTITUDE if attitude is None else attitude, attitude is not None, _NO_ATTITUDE,
        _NO_VALUES, _NO_VALUES, _NO_ROWS, False, state.w if gyro is None else gyro,
        _NO_ROWS if gyro_noise is None else gyro_noise, gyro_noise is not None,
        state.autopilot_state, state.yaw_setpoint, consts, has_stack, stack, mixer, thrust_max,
        thrust_coeff, np.asarray(ext_force_n, dtype=float),
        _NO_ROWS if ext_torque_nm is None else np.asarray(ext_torque_nm, dtype=float),
        ext_torque_nm is not None, torque_map, drag_sums, drag, drag_z, parasitic, gravity, dt_s,
        *out)
    return out


def _step_constants(body: VehicleBody, params: RigidBodyParams, dt_s: float,
                    thrust_gain: np.ndarray) -> tuple:
    """:func:`rigid_kernel.step_vehicles`'s arguments that stay the same from step to step for
    one body, vehicle type, ``dt_s`` and thrust gain: (k_T per vehicle, torque gains, mass
    rows, inertia, the motors' step factor, the autopilot's constants, whether a flight stack
    flies, its constants, the mixer, the rotor thrust limit, k_T, the torque map, the rotor
    drag's sums, the three drag coefficients, gravity). Kept on ``body`` for the last
    ``params``, ``dt_s`` and ``thrust_gain`` while the arrays the numbers among them are
    computed from are read-only (the checks of :func:`_body_constants` and
    :func:`_thrust_coeffs`, which compute them); the rest are references to ``body``'s and
    ``params``' own read-only fields."""
    hit = body.__dict__.get("_step_arguments")  # not a field: numbers derived from it
    if (hit is not None and hit[0] is params and hit[1] == dt_s and hit[2] is thrust_gain
            and is_frozen(thrust_gain) and is_frozen(body.motor_tau_s)
            and is_frozen(body.inertia_kgm2)):
        return hit[3]
    alpha, inertia = _body_constants(body, dt_s)
    consts, mixer, torque_map, drag_sums = kernel_constants(params)
    arguments = (_thrust_coeffs(body, params.thrust_coeff, thrust_gain), body.torque_gain,
                 body.mass_rows_kg, inertia, alpha, consts, params.stack_constants is not None,
                 _stack(params), mixer, params.rotor_thrust_max_n, params.thrust_coeff,
                 torque_map, drag_sums, params.rotor_drag_coeff, params.rotor_drag_z_coeff,
                 params.parasitic_drag_coeff, params.gravity_mps2)
    body.__dict__["_step_arguments"] = (params, dt_s, thrust_gain, arguments)
    return arguments


def _packed_constants(body: VehicleBody, params: RigidBodyParams, dt_s: float,
                      thrust_gain: np.ndarray, eager: bool = False,
                      ) -> tuple[tuple, np.ndarray | None]:
    """(:func:`_step_constants`' tuple, the same numbers and ``dt_s`` in one flat read-only
    array as :func:`flown_step` reads them, or None). The array is built the second time the
    same tuple serves (a body and gains that stay, as in the world's step: one array to pass
    instead of eleven arrays and eight numbers, at a batch of 1 the compiled call's cost is
    mostly its arguments'); a tuple used once (a body split off for one step, a pair's half)
    is not packed. The array, kept beside the tuple and under its checks: a header of
    :data:`_PACK_HEADER` numbers (the lengths of the motors' step factor, the autopilot's
    constants, the flight stack's constants, the mixer, the torque map and the drag sums;
    whether a flight stack flies; the rotor thrust limit, k_T, the three drag coefficients,
    gravity, ``dt_s``), then k_T per vehicle, the torque gains, the mass rows and the inertia
    (row-major), the step factor, the autopilot's, the stack's, the mixer's, the torque map's
    and the drag sums' numbers (copied, not computed). Not packed unless the body's torque gains
    and mass rows and the flight stack's constants are read-only (the tuple reads them live; a
    copy would not see a write). ``eager``: packed at the first use."""
    arguments = _step_constants(body, params, dt_s, thrust_gain)
    if not (is_frozen(body.torque_gain) and is_frozen(body.mass_rows_kg)
            and (params.stack_constants is None or is_frozen(params.stack_constants))):
        return arguments, None  # the tuple refers to them live; a copy could go stale
    hit = body.__dict__.get("_packed_arguments")  # not a field: numbers derived from it
    if (hit is None or hit[0] is not arguments) and not eager:
        body.__dict__["_packed_arguments"] = (arguments, None)  # packed if used again
        return arguments, None
    if hit is not None and hit[0] is arguments and hit[1] is not None:
        return hit
    (kc, torque_gain, mass_rows, inertia, alpha, consts, has_stack, stack, mixer, thrust_max,
     thrust_coeff, torque_map, drag_sums, drag, drag_z, parasitic, gravity) = arguments
    header = [alpha.size, consts.size, stack.size, mixer.size, torque_map.size,
              drag_sums.size, float(has_stack), thrust_max, thrust_coeff, drag, drag_z,
              parasitic, gravity, dt_s]
    packed = np.concatenate([np.array(header, dtype=float)] + [
        np.asarray(a, dtype=float).ravel() for a in (kc, torque_gain, mass_rows, inertia, alpha,
                                                     consts, stack, mixer, torque_map,
                                                     drag_sums)])
    freeze(packed)
    hit = body.__dict__["_packed_arguments"] = (arguments, packed)
    return hit


_PACK_HEADER = 14


def packed_step_constants(body: VehicleBody, params: RigidBodyParams, dt_s: float,
                          thrust_gain: np.ndarray) -> np.ndarray | None:
    """The flat constants :func:`flown_step` reads for ``body``'s vehicles, packed now if they
    were not yet (:func:`_packed_constants`; None: they cannot be)."""
    return _packed_constants(body, params, dt_s, thrust_gain, eager=True)[1]


@njit
def flown_rows(packed: np.ndarray, lo: int, hi: int, p: np.ndarray, v: np.ndarray,
               rot: np.ndarray, w: np.ndarray, omega: np.ndarray, att: np.ndarray,
               use_att: bool, r_des: np.ndarray, yaw_rate: np.ndarray, thrust_cmd: np.ndarray,
               torque_ff: np.ndarray, has_ff: bool, gyro: np.ndarray, gyro_noise: np.ndarray,
               noisy: bool, integral: np.ndarray, yaw_sp: np.ndarray, ext_force: np.ndarray,
               ext_torque: np.ndarray, has_ext_torque: bool, p_new: np.ndarray,
               v_new: np.ndarray, rot_new: np.ndarray, w_new: np.ndarray,
               omega_new: np.ndarray, thrust_new: np.ndarray, accel: np.ndarray,
               integral_new: np.ndarray, yaw_sp_new: np.ndarray) -> None:
    """:func:`rigid_kernel.step_vehicles` flown by the autopilots on the rows ``lo..hi`` of the
    batch, its constants read from :func:`_packed_constants`' array (views of it, the same
    numbers). Every array is whole, as the step holds it; each vehicle's step is its own, so
    rows stepped apart give the numbers of the batch stepped at once (the compiled period's
    blocks of trials)."""
    n = p.shape[0]
    n_alpha, n_consts, n_stack = int(packed[0]), int(packed[1]), int(packed[2])
    n_mixer, n_map, n_drag = int(packed[3]), int(packed[4]), int(packed[5])
    o = _PACK_HEADER
    kc = packed[o:o + n]
    o += n
    torque_gain = packed[o:o + n]
    o += n
    mass_rows = packed[o:o + 3 * n].reshape((n, 3))
    o += 3 * n
    inertia = packed[o:o + 3 * n].reshape((n, 3))
    o += 3 * n
    alpha = packed[o:o + n_alpha]
    o += n_alpha
    consts = packed[o:o + n_consts]
    o += n_consts
    stack = packed[o:o + n_stack]
    o += n_stack
    mixer = packed[o:o + n_mixer]
    o += n_mixer
    torque_map = packed[o:o + n_map]
    o += n_map
    drag_sums = packed[o:o + n_drag]
    if n_alpha > 1:  # the motors' step factor per vehicle (else one for all)
        alpha = alpha[lo:hi]
    # the placeholders of absent inputs (an empty gyro noise, a (1, 4) feed-forward) are not
    # read: their slices are as good as they
    rigid_kernel.step_vehicles_body(
        p[lo:hi], v[lo:hi], rot[lo:hi], w[lo:hi], omega[lo:hi], kc[lo:hi], torque_gain[lo:hi],
        mass_rows[lo:hi], inertia[lo:hi], alpha, True, omega[:0], att[lo:hi], use_att,
        r_des[lo:hi], yaw_rate[lo:hi], thrust_cmd[lo:hi], torque_ff[lo:hi], has_ff, gyro[lo:hi],
        gyro_noise[lo:hi], noisy, integral[lo:hi], yaw_sp[lo:hi], consts, packed[6] != 0.0,
        stack, mixer, packed[7], packed[8], ext_force[lo:hi], ext_torque[lo:hi],
        has_ext_torque, torque_map, drag_sums, packed[9], packed[10], packed[11], packed[12],
        packed[13], p_new[lo:hi], v_new[lo:hi], rot_new[lo:hi], w_new[lo:hi],
        omega_new[lo:hi], thrust_new[lo:hi], accel[lo:hi], integral_new[lo:hi],
        yaw_sp_new[lo:hi])


@any_layout("p_new", "v_new", "rot_new", "w_new", "omega_new", "thrust_new", "accel",
            "integral_new", "yaw_sp_new", contiguous=("packed",))
@njit
def flown_step(packed: np.ndarray, p: np.ndarray, v: np.ndarray, rot: np.ndarray,
                w: np.ndarray, omega: np.ndarray, att: np.ndarray, use_att: bool,
                r_des: np.ndarray, yaw_rate: np.ndarray, thrust_cmd: np.ndarray,
                torque_ff: np.ndarray, has_ff: bool, gyro: np.ndarray, gyro_noise: np.ndarray,
                noisy: bool, integral: np.ndarray, yaw_sp: np.ndarray, ext_force: np.ndarray,
                ext_torque: np.ndarray, has_ext_torque: bool, p_new: np.ndarray,
                v_new: np.ndarray, rot_new: np.ndarray, w_new: np.ndarray,
                omega_new: np.ndarray, thrust_new: np.ndarray, accel: np.ndarray,
                integral_new: np.ndarray, yaw_sp_new: np.ndarray) -> None:
    """:func:`flown_rows` on every row, for a call from Python: any array layout (sealed to one
    general signature, :func:`aerodock.jit.any_layout`); compiled callers call
    :func:`flown_rows` itself, which no seal stops from compiling for their types."""
    flown_rows(packed, 0, p.shape[0], p, v, rot, w, omega, att, use_att, r_des, yaw_rate,
               thrust_cmd, torque_ff, has_ff, gyro, gyro_noise, noisy, integral, yaw_sp,
               ext_force, ext_torque, has_ext_torque, p_new, v_new, rot_new, w_new, omega_new,
               thrust_new, accel, integral_new, yaw_sp_new)


_NO_ATTITUDE = np.zeros((0, 3, 3))
_NO_VALUES = np.zeros(0)
freeze(_NO_ATTITUDE, _NO_VALUES)


def _stack(params: RigidBodyParams) -> np.ndarray:
    """The flight stack's constants as the kernel takes them (an empty array: none)."""
    return _NO_VALUES if params.stack_constants is None else params.stack_constants


def step_with_autopilot(
    state: RigidBodyState,
    targets: RigidTargets,
    ext_force_n: np.ndarray,
    ext_torque_nm: np.ndarray | None,
    params: RigidBodyParams,
    dt_s: float,
    gyro_noise_radps: np.ndarray | None = None,
    sensed: tuple[np.ndarray, np.ndarray] | None = None,
) -> tuple[RigidBodyState, np.ndarray]:
    """One physics step of N vehicles flown by their autopilots: the autopilot reads the gyro
    (true rates plus ``gyro_noise_radps``; or, given ``sensed = (rates (n, 3), attitude
    (n, 3, 3))``, what the flight computer's IMU chain and estimator give), commands the rotors,
    then :func:`step_rigid_body`. Returns (state, acceleration (n, 3))."""
    attitude = noise = None
    if sensed is not None:
        gyro, attitude = sensed
    else:
        gyro, noise = state.w, gyro_noise_radps
    p, v, rot, w, omega, thrust, accel, integral, yaw_sp = _step_arrays(
        state, None, ext_force_n, ext_torque_nm, params, dt_s, targets, gyro, noise, attitude)
    return frozen_record(RigidBodyState, p=p, v=v, R=rot, w=w, rotor_speed=omega,
                         autopilot_state=integral, yaw_setpoint=yaw_sp,
                         thrust_gain=state.thrust_gain, thrust_n=thrust,
                         body=state.body), accel


def _rotate(rot: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """``R exp([phi]x)`` for (n, 3, 3) ``R`` and (n, 3) body rotation vectors (Rodrigues)."""
    return _rotate_t(rot, np.ascontiguousarray(np.asarray(phi, dtype=float).T))


def _rotate_t(rot: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """:func:`_rotate` with component-major rotation vectors ``phi`` (3, n); compiled
    (:func:`rigid_kernel.rotate_batch`)."""
    out = np.empty((rot.shape[0], 3, 3))
    rigid_kernel.rotate_batch(rot, phi, out)
    return out
