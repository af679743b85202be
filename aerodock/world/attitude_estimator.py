"""The flight computer's attitude estimate: a complementary filter on the gyro and accelerometer,
velocity-aided (as PX4's ``attitude_estimator_q`` with acceleration compensation), batch-first.

Per vehicle and IMU sample: the estimate ``R_hat`` turns with the (filtered, delayed) gyro, plus
a correction that rotates its "down" axis towards the gravity the accelerometer sees (Mahony et
al. 2008, the accelerometer as the reference direction)::

    g_b   = -(f - R_hat^T a_comp) / |.|          gravity in the body frame, as measured
    e     = g_b x (R_hat^T e3) + k_yaw * yaw error about body z (from the external heading)
    R_hat <- R_hat exp([w_gyro + k_p e] dt)

``a_comp`` is the vehicle's acceleration as its navigation knows it from the external position
source (the motion capture's velocity, differenced at its rate): without it a sustained push
(a turn, the wake's lateral force) reads as a tilt. A real flight computer's error comes from what
it is given: the gyro's noise and filter lag, the accelerometer's vibration, the external
source's delay. Rotations stay orthonormal (the exact Rodrigues step of the rigid body).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from aerodock.world.vehicles.rigid_body import _rotate_t


@dataclass(frozen=True)
class AttitudeEstimatorParams:
    """The complementary filter's gains (``[imu]``)."""

    accel_gain_radps: float  # k_p: how fast the tilt follows the accelerometer, 1/s
    heading_gain_radps: float  # k_yaw: how fast the heading follows the external source, 1/s


def estimate_step(rot_hat: np.ndarray, gyro_t: np.ndarray, accel_t: np.ndarray,
                  accel_comp_world: np.ndarray, yaw_ext_rad: np.ndarray,
                  params: AttitudeEstimatorParams, dt_s: float) -> np.ndarray:
    """One sample's new estimate.

    Args:
        rot_hat: (m, 3, 3) the current estimate, body to world.
        gyro_t: (3, m) the gyro's rates, rad/s, component-major.
        accel_t: (3, m) the accelerometer's specific force, body FRD, m/s², component-major.
        accel_comp_world: (m, 3) the vehicle's acceleration as its navigation knows it, NED.
        yaw_ext_rad: (m,) the external source's heading.
        params: the gains.
        dt_s: the sample period.

    Returns:
        (m, 3, 3) the estimate after ``dt_s``.
    """
    # Gravity in the body, as the accelerometer sees it once the known acceleration is removed:
    # f = R^T (a - g e3), so -(f - R^T a) = g R^T e3.
    comp_body = np.matmul(accel_comp_world[:, None, :], rot_hat)[:, 0]  # R_hat^T a_comp
    # Both factors of the cross product meas x est with their first two rows repeated (5, m):
    # (meas_y est_z - meas_z est_y, ...) is then two products of slices.
    m = rot_hat.shape[0]
    meas5, est5 = np.empty((5, m)), np.empty((5, m))
    meas = np.subtract(comp_body.T, accel_t, out=meas5[:3])
    sq = meas * meas
    norm = np.add(sq[0], sq[1], out=sq[0])
    norm += sq[2]
    np.sqrt(norm, out=norm)
    meas /= np.maximum(norm, 1e-6)
    meas5[3:] = meas5[:2]
    est = est5[:3]  # R_hat^T e3: the estimate's down axis in the body, (3, m)
    np.copyto(est, rot_hat[:, 2, :].T)
    est5[3:] = est5[:2]
    err = meas5[1:4] * est5[2:5]  # meas x est
    err -= meas5[2:5] * est5[1:4]
    omega = gyro_t + params.accel_gain_radps * err
    if params.heading_gain_radps:
        yaw_hat = np.arctan2(rot_hat[:, 1, 0], rot_hat[:, 0, 0])
        yaw_err = (yaw_ext_rad - yaw_hat + np.pi) % (2 * np.pi) - np.pi
        # About the world's down axis, expressed in the body: R_hat^T e3 * yaw error.
        omega += params.heading_gain_radps * yaw_err * est
    return _rotate_t(rot_hat, omega * dt_s)
