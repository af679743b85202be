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

import math
from dataclasses import dataclass

import numpy as np

from aerodock.borrowed import borrowed, keep_alive, scratch_row, scratch_size
from aerodock.jit import NUMPY_LOOPS, dot3_vecmat, njit, np_arctan2
from aerodock.world.vehicles.rigid_kernel import exp_so3, load3x3, mat3_mul, store3x3


@dataclass(frozen=True)
class AttitudeEstimatorParams:
    """The complementary filter's gains (``[imu]``)."""

    accel_gain_radps: float  # k_p: how fast the tilt follows the accelerometer, 1/s
    heading_gain_radps: float  # k_yaw: how fast the heading follows the external source, 1/s


def estimate_step(rot_hat: np.ndarray, gyro_t: np.ndarray, accel_t: np.ndarray,
                  accel_comp_world: np.ndarray, yaw_ext_rad: np.ndarray,
                  params: AttitudeEstimatorParams, dt_s: float) -> np.ndarray:
    """One sample's new estimate (compiled: :func:`estimate_into`).

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
    out = np.empty((rot_hat.shape[0], 3, 3))
    estimate_into(NUMPY_LOOPS, rot_hat, gyro_t, accel_t, accel_comp_world, yaw_ext_rad,
                  params.accel_gain_radps, params.heading_gain_radps, dt_s, out)
    return out


@njit
def estimate_into(loops: np.ndarray, rot_hat: np.ndarray, gyro_t: np.ndarray,
                  accel_t: np.ndarray, comp: np.ndarray, yaw_ext: np.ndarray, k_p: float,
                  k_yaw: float, dt: float, out: np.ndarray) -> None:
    """:func:`estimate_step` into ``out``: per vehicle, gravity as measured
    ``g_b = -(f - R^T a_comp) / |.|`` (the norm floored at 1e-6), the error
    ``g_b x (R^T e3)`` plus the heading's about the world's down axis, and the exact rotation
    by ``(w_gyro + k_p e + k_yaw yaw_err R^T e3) dt``."""
    m = rot_hat.shape[0]
    owner = np.zeros(scratch_size(2 * m, 2))  # both rows below are views of it
    (work,) = borrowed((owner,))
    yaw_err, at = scratch_row(work, 0, m)
    if k_yaw != 0.0:
        yaw_hat, _ = scratch_row(work, at, m)
        np_arctan2(loops, rot_hat[:, 1, 0], rot_hat[:, 0, 0], yaw_hat)
        for i in range(m):
            e = yaw_ext[i] - yaw_hat[i]
            e += math.pi
            e %= 2 * math.pi
            yaw_err[i] = e - math.pi
    for i in range(m):
        r = rot_hat[i]
        c0, c1, c2 = comp[i, 0], comp[i, 1], comp[i, 2]
        m0 = dot3_vecmat(c0, c1, c2, r[0, 0], r[1, 0], r[2, 0]) - accel_t[0, i]
        m1 = dot3_vecmat(c0, c1, c2, r[0, 1], r[1, 1], r[2, 1]) - accel_t[1, i]
        m2 = dot3_vecmat(c0, c1, c2, r[0, 2], r[1, 2], r[2, 2]) - accel_t[2, i]
        norm = m0 * m0 + m1 * m1
        norm += m2 * m2
        norm = math.sqrt(norm)
        norm = norm if (norm >= 1e-6 or norm != norm) else 1e-6
        m0 /= norm
        m1 /= norm
        m2 /= norm
        e0, e1, e2 = r[2, 0], r[2, 1], r[2, 2]  # R_hat^T e3: the estimate's down axis
        w0 = gyro_t[0, i] + k_p * (m1 * e2 - m2 * e1)
        w1 = gyro_t[1, i] + k_p * (m2 * e0 - m0 * e2)
        w2 = gyro_t[2, i] + k_p * (m0 * e1 - m1 * e0)
        if k_yaw != 0.0:
            y = k_yaw * yaw_err[i]
            w0 += y * e0
            w1 += y * e1
            w2 += y * e2
        store3x3(out, i, mat3_mul(load3x3(rot_hat, i), exp_so3(w0 * dt, w1 * dt, w2 * dt)))
    keep_alive(owner)
