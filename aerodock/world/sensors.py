"""What the controllers and the logs see of the world: motion capture, the follower's
accelerometer, its torque observations. Each reads the batch state; none changes the physics."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from aerodock.geometry import rotmat_to_rpy, rpy_to_rotmat
from aerodock.rng import TrialRNG, standard_normal_t
from aerodock.world.params import WorldParams
from aerodock.world.sensor_kernels import mocap_noise_kernel
from aerodock.world.state import WorldState
from aerodock.world.torque_sensing import TorqueLog, TorqueReading


@dataclass(frozen=True)
class Observation:
    """What motion capture gives a controller: batch-first position, velocity and attitude."""

    p: np.ndarray  # (n, 3) m
    v: np.ndarray  # (n, 3) m/s
    rpy: np.ndarray  # (n, 3) rad: roll, pitch, yaw

    @property
    def yaw_rad(self) -> np.ndarray:
        """(n,) yaw."""
        return self.rpy[:, 2]

    @cached_property
    def R(self) -> np.ndarray:  # noqa: N802
        """(n, 3, 3) body-to-world rotation (built once per observation: the active trigger, the
        predictor's bodies and the recorder each read it)."""
        return rpy_to_rotmat(self.rpy)


def motion_capture(state: WorldState, params: WorldParams) -> tuple[Observation, Observation]:
    """(leader, follower) as the controllers see them: position and velocity from motion
    capture, ``latency_steps`` late and noisy; the attitude the flight computer's (its estimate
    now with the filtered IMU chain; the ideal chain's: the true attitude, as late, plus
    ``imu.attitude_noise_rad`` with rigid bodies). Random draws, per trial: attitude (ideal
    chain, rigid body), position, velocity; the leader's, then the follower's."""
    latency = params.latency_steps
    lp, lv, lr, fp, fv, fr = state.history[(state.step_index - latency) % (latency + 1)]
    n, rng = state.n, state.rng
    pos_sd, vel_sd = params.mocap.pos_noise_m, params.mocap.vel_noise_mps
    att_sd = params.imu.attitude_noise_rad if params.rigid else 0.0
    if state.imu is not None:  # the estimates' angles, the leaders' rows then the followers'
        both = rotmat_to_rpy(state.imu.attitude)
        lr, fr, att_sd = both[:n], both[n:], 0.0
    lr = rotmat_to_rpy(lr) if lr.ndim == 3 else lr
    fr = rotmat_to_rpy(fr) if fr.ndim == 3 else fr
    k = 9 if att_sd > 0 else 6
    out = np.empty((6, n, 3))
    mocap_noise_kernel(lp, lv, lr, _draws(rng, n, k), fp, fv, fr, _draws(rng, n, k),
                       pos_sd, vel_sd, att_sd, out)
    return Observation(p=out[0], v=out[1], rpy=out[2]), Observation(p=out[3], v=out[4], rpy=out[5])


def _draws(rng: np.random.Generator | TrialRNG, n: int, k: int) -> np.ndarray:
    """(k, n) one vehicle's motion-capture draws, component-major: with a trial's own stream,
    its next ``k``; from a plain ``Generator``, ``k // 3`` draws of ``(n, 3)`` (the angles',
    the position's, the velocity's; the numbers and order they were always drawn in)."""
    if isinstance(rng, TrialRNG) and rng.n == n:
        return standard_normal_t(rng, n, k)
    draws = np.empty((k, n))
    for row in range(0, k, 3):
        draws[row:row + 3] = rng.standard_normal((n, 3)).T
    return draws


def accelerometer(state: WorldState, params: WorldParams) -> np.ndarray:
    """(n, 3) the follower's accelerometer, world NED.

    With the filtered IMU chain: its latest filtered, delayed sample of the specific force,
    turned to the world with the flight computer's attitude estimate, plus gravity. With the
    ideal chain, averaged since the last read: the mean kinematic acceleration over the window
    plus what the IMU adds: white noise (``vehicle.accel_noise_mps2`` per physics sample) and,
    with rigid bodies, motor vibration
    (``imu.accel_vibration_mps2`` per sample at hover rotor speed, growing with the square of
    the rotor speed) and the residual bias (constant in the body frame), both averaged over the
    window's samples as the flight computer's filter does. A second read before the world has
    moved returns the same reading (the controller and the recorder read one accelerometer).
    """
    window = state.accel_window
    if window.reading is not None and state.step_index == window.step_index:
        return window.reading.copy()
    if state.imu is not None:  # the chain's latest sample, to the world on the estimate
        n, ims = state.n, state.imu
        force = ims.accel_t[:, n:].T
        reading = np.matmul(ims.attitude[n:], force[:, :, None])[:, :, 0]
        reading[:, 2] += params.vehicle.gravity_mps2
        window.reading, window.step_index = reading, state.step_index
        return reading.copy()
    fol, n = state.follower, state.n
    dt = max(state.t_s - window.t_s, 1e-9)
    samples = max(state.step_index - window.step_index, 1)
    accel = (fol.v - window.v_mps) / dt
    window.v_mps = fol.v.copy()
    window.t_s = state.t_s
    window.step_index = state.step_index
    sd = np.full(n, params.vehicle.accel_noise_mps2 ** 2)
    if params.rigid:
        load = fol.thrust_n / params.vehicle.hover_thrust_n
        sd = sd + (params.imu.accel_vibration_mps2 * load) ** 2
        accel = accel + np.matmul(fol.R, state.accel_bias_body_mps2[:, :, None])[:, :, 0]
    sd = np.sqrt(sd / samples)
    window.reading = accel + sd[:, None] * state.rng.standard_normal((n, 3))
    return window.reading.copy()


def torque_observations(state: WorldState, params: WorldParams) -> TorqueReading:
    """The follower's torque observations (body FRD) over the control period since the last
    read: the kinematic torque ``J dw/dt + w x J w`` from its gyro, the torque its rotors explain
    from their measured speeds, its mean gyro reading, and the true wake torque over the same
    steps (see :mod:`aerodock.world.torque_sensing`).

    The first read starts the log (and returns zeros): until then the world computes none of
    it. A second read before the world has moved returns the same reading. No random numbers
    are drawn (the gyro noise is the autopilot's).

    Raises:
        ValueError: point-mass vehicles (they have no rotors or body rates).
    """
    if not params.rigid:
        raise ValueError("torque observations need vehicle.model = 'rigid-body'")
    if state.torque_log is None:
        state.torque_log = TorqueLog(params.follower_fleet.params, state.n, params.dt_s)
        state.steps_at_last_torque = state.step_index
        state.torque_reading = state.torque_log.read()
    elif state.step_index != state.steps_at_last_torque or state.torque_reading is None:
        state.steps_at_last_torque = state.step_index
        state.torque_reading = state.torque_log.read()
    return state.torque_reading
