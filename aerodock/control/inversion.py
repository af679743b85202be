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

from aerodock.control import command_kernel
from aerodock.control.command_kernel import per_trial, rows1, rows3, tilt_tangent
from aerodock.jit import NUMPY_LOOPS


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
    tan_tilt = tilt_tangent(tilt_max_rad)
    accel = rows3(accel_mps2)
    n = accel.shape[0]
    cos_yaw, sin_yaw = _cos_sin(rows1(yaw_rad, n))
    roll, pitch, thrust = np.empty(n), np.empty(n), np.empty(n)
    command_kernel.inverse_rows(NUMPY_LOOPS, accel, cos_yaw, sin_yaw, per_trial(mass_kg, n),
                                float(gravity_mps2), tan_tilt, per_trial(thrust_max_n, n), roll,
                                pitch, thrust)
    return roll, pitch, thrust


def command_and_applied(accel_mps2: np.ndarray, yaw_rad: np.ndarray, mass_kg: float,
                        gravity_mps2: float, tilt_max_rad: float, thrust_max_n: float,
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`accel_to_attitude_thrust` and, of its result, :func:`attitude_thrust_to_accel`
    (the acceleration actually commanded), for (n, 3) accelerations and (n,) yaws: ``(roll,
    pitch, thrust, applied)``, the same numbers as the two calls (the yaw's cosine and sine
    computed once)."""
    tan_tilt = tilt_tangent(tilt_max_rad)
    accel = rows3(accel_mps2)
    n = accel.shape[0]
    cos_yaw, sin_yaw = _cos_sin(rows1(yaw_rad, n))
    mass = per_trial(mass_kg, n)
    roll, pitch, thrust = np.empty(n), np.empty(n), np.empty(n)
    command_kernel.inverse_rows(NUMPY_LOOPS, accel, cos_yaw, sin_yaw, mass, float(gravity_mps2),
                                tan_tilt, per_trial(thrust_max_n, n), roll, pitch, thrust)
    applied = np.empty((n, 3))
    command_kernel.forward_rows(roll, pitch, cos_yaw, sin_yaw, thrust / mass, float(gravity_mps2),
                                applied)
    return roll, pitch, thrust, applied


def _cos_sin(yaw: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The yaws' cosines and sines, each (n,)."""
    return np.cos(yaw), np.sin(yaw)


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
    flat = [np.ascontiguousarray(np.broadcast_to(v, shape)).reshape(-1)
            for v in (roll, pitch, yaw)]
    k = np.ascontiguousarray(np.broadcast_to(thrust / mass, shape)).reshape(-1)
    out = np.empty((k.size, 3))
    command_kernel.forward_rows(flat[0], flat[1], np.cos(flat[2]), np.sin(flat[2]), k,
                                float(gravity_mps2), out)
    return out.reshape(shape + (3,))
