"""Non-linear inversion of the 2nd-order multirotor dynamics, batch-first.

Dynamics (NED, z down, thrust along the body's ``-z`` axis)::

    m a = -R e3 T + m g e3

so the force the rotors must produce is ``-f`` with ``f = m (g e3 - a)``, i.e. ``R e3 T = f``:
the body z axis (third column of ``R``, pointing *down* through the belly in hover) is
``f / |f|`` and the collective thrust is ``T = |f|``. (The thrust *force* vector, pointing up,
is ``-f``.) Roll and pitch follow from the ZYX convention of :mod:`aerodock.geometry` once the
yaw is given.

Saturation policy (vertical first, because altitude errors are what make a dock unsafe):

1. If the upward part of the required force is not positive (``f_z <= 0``: a commanded downward
   acceleration of ``g`` or more), the vehicle cannot produce it; the output is level attitude
   with zero thrust (free fall is the closest achievable acceleration).
2. Tilt: if the angle of ``f`` from the vertical exceeds ``tilt_max``, the horizontal part is
   scaled down so that the tilt equals ``tilt_max``; the vertical part is kept.
3. Thrust: if ``|f|`` exceeds ``thrust_max``, the horizontal part is shrunk further to make
   ``|f| = thrust_max`` (vertical kept); if even the vertical part alone exceeds the limit, the
   result is level attitude at ``thrust_max``.
"""

from __future__ import annotations

import numpy as np


def accel_to_attitude_thrust(
    accel_mps2: np.ndarray,
    yaw_rad: np.ndarray,
    mass_kg: np.ndarray | float,
    gravity_mps2: float,
    tilt_max_rad: float,
    thrust_max_n: np.ndarray | float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Map desired net accelerations to roll, pitch and collective thrust (inner-loop command).

    See the module docstring for the saturation policy. The output is always finite; within
    the limits it is the exact inverse of :func:`attitude_thrust_to_accel`.

    Args:
        accel_mps2: Desired acceleration, NED, gravity excluded, ``(n, 3)``.
        yaw_rad: Yaw to hold, ``(n,)``.
        mass_kg: Mass, ``(n,)`` or scalar.
        gravity_mps2: Gravitational acceleration (positive).
        tilt_max_rad: Maximum tilt of the thrust axis from vertical, in ``(0, pi/2)``.
        thrust_max_n: Maximum collective thrust, ``(n,)`` or scalar (positive).

    Returns:
        ``(roll_rad, pitch_rad, thrust_n)``, each ``(n,)``.

    Raises:
        ValueError: if ``tilt_max_rad`` is not in ``(0, pi/2)``.
    """
    if not 0.0 < tilt_max_rad < 0.5 * np.pi:
        raise ValueError(f"tilt_max_rad must be in (0, pi/2), got {tilt_max_rad}")
    accel = np.atleast_2d(np.asarray(accel_mps2, dtype=float))
    n = accel.shape[0]
    yaw = _rows(yaw_rad, n)
    mass = _rows(mass_kg, n)
    thrust_max = _rows(thrust_max_n, n)

    # f = m (g e3 - a), (n, 3), R e3 T = f; column by column (no (n, 1) broadcasts, same numbers)
    f_x = np.subtract(0.0, accel[:, 0])
    f_x *= mass
    f_y = np.subtract(0.0, accel[:, 1])
    f_y *= mass
    f_z = np.subtract(gravity_mps2, accel[:, 2])
    f_z *= mass
    h_norm = f_x * f_x
    h_norm += f_y * f_y
    np.sqrt(h_norm, out=h_norm)
    can_lift = f_z > 0.0
    f_z_pos = np.where(can_lift, f_z, 0.0)

    # Tilt limit, then thrust limit: both only shrink the horizontal part (vertical first).
    h_max = f_z_pos * np.tan(tilt_max_rad)
    h_max = np.minimum(h_max, np.sqrt(np.maximum(thrust_max**2 - f_z_pos**2, 0.0)))
    f_z_sat = np.minimum(f_z_pos, thrust_max)
    scale = np.where(h_norm > h_max, h_max / np.where(h_norm > 0.0, h_norm, 1.0), 1.0)
    f_x *= scale
    f_y *= scale
    f_x_sat = np.where(can_lift, f_x, 0.0)
    f_y_sat = np.where(can_lift, f_y, 0.0)

    thrust = f_x_sat * f_x_sat
    thrust += f_y_sat * f_y_sat
    thrust += f_z_sat * f_z_sat
    np.sqrt(thrust, out=thrust)
    safe = np.where(thrust > 0.0, thrust, 1.0)
    z_x = f_x_sat / safe
    z_y = f_y_sat / safe
    zz = f_z_sat / safe
    level = thrust <= 0.0
    if level.any():
        z_x[level] = 0.0
        z_y[level] = 0.0
        zz[level] = 1.0

    # In the yaw-aligned frame, R e3 = [cos(roll) sin(pitch), -sin(roll), cos(roll) cos(pitch)].
    # Rz(yaw)^T z_body, written out (no einsum: faster, and independent of the batch size).
    cy, sy = np.cos(yaw), np.sin(yaw)
    zx = cy * z_x + sy * z_y
    zy = -sy * z_x + cy * z_y
    roll = np.arctan2(-zy, np.hypot(zx, zz))
    pitch = np.arctan2(zx, zz)
    return roll, pitch, thrust


def _rows(value: np.ndarray | float, n: int) -> np.ndarray:
    """``value`` as floats, broadcast to (n,) unless it is a scalar or already (n,) (elementwise
    arithmetic broadcasts a scalar with the same numbers, without np.broadcast_to's cost)."""
    arr = np.asarray(value, dtype=float)
    return arr if arr.ndim == 0 or arr.shape == (n,) else np.broadcast_to(arr, (n,))


def attitude_thrust_to_accel(
    roll_rad: np.ndarray,
    pitch_rad: np.ndarray,
    yaw_rad: np.ndarray,
    thrust_n: np.ndarray,
    mass_kg: np.ndarray | float,
    gravity_mps2: float,
) -> np.ndarray:
    """Forward map: attitude and collective thrust to net acceleration ``a = g e3 - R e3 T / m``.

    Args:
        roll_rad: Roll, ``(n,)``.
        pitch_rad: Pitch, ``(n,)``.
        yaw_rad: Yaw, ``(n,)``.
        thrust_n: Collective thrust, ``(n,)``.
        mass_kg: Mass, ``(n,)`` or scalar.
        gravity_mps2: Gravitational acceleration (positive).

    Returns:
        Acceleration in NED, ``(n, 3)``.
    """
    roll, pitch, yaw, thrust, mass = (np.asarray(v, dtype=float) for v in (
        roll_rad, pitch_rad, yaw_rad, thrust_n, mass_kg))
    shape = np.broadcast_shapes(roll.shape, pitch.shape, yaw.shape, thrust.shape, mass.shape)
    # Third column of Rz(yaw) Ry(pitch) Rx(roll) (see aerodock.geometry.euler_to_rotmat).
    cr, sr, cp, sp = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch)
    cy, sy = np.cos(yaw), np.sin(yaw)
    k = np.broadcast_to(thrust / mass, shape)  # every product below has the full shape
    out = np.empty(shape + (3,))
    np.multiply(-(cy * sp * cr + sy * sr), k, out=out[..., 0])
    np.multiply(-(sy * sp * cr - cy * sr), k, out=out[..., 1])
    np.subtract(gravity_mps2, cp * cr * k, out=out[..., 2])
    return out
