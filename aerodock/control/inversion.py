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

import functools

import numpy as np

from aerodock.frozen import freeze


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
    roll_pitch, thrust = _inverse(accel, _cos_sin(_rows(yaw_rad, n), n), _rows(mass_kg, n),
                                  gravity_mps2, tilt_max_rad, _rows(thrust_max_n, n))
    return roll_pitch[0], roll_pitch[1], thrust


def command_and_applied(accel_mps2: np.ndarray, yaw_rad: np.ndarray, mass_kg: float,
                        gravity_mps2: float, tilt_max_rad: float, thrust_max_n: float,
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`accel_to_attitude_thrust` and, of its result, :func:`attitude_thrust_to_accel`
    (the acceleration actually commanded), for (n, 3) accelerations and (n,) yaws: ``(roll,
    pitch, thrust, applied)``, the same numbers as the two calls (the yaw's cosine and sine
    computed once)."""
    if not 0.0 < tilt_max_rad < 0.5 * np.pi:
        raise ValueError(f"tilt_max_rad must be in (0, pi/2), got {tilt_max_rad}")
    accel = np.asarray(accel_mps2, dtype=float)
    n = accel.shape[0]
    cos_sin = _cos_sin(_rows(yaw_rad, n), n)
    mass = _rows(mass_kg, n)
    roll_pitch, thrust = _inverse(accel, cos_sin, mass, gravity_mps2, tilt_max_rad,
                                  _rows(thrust_max_n, n))
    applied = _forward(roll_pitch, cos_sin, thrust / mass, gravity_mps2)
    return roll_pitch[0], roll_pitch[1], thrust, applied


def _cos_sin(yaw: np.ndarray, n: int) -> np.ndarray:
    """(2, n) the yaws' cosines and sines (a scalar yaw: every trial's)."""
    out = np.empty((2, n))
    np.cos(yaw, out=out[0])
    np.sin(yaw, out=out[1])
    return out


def _inverse(accel: np.ndarray, cos_sin: np.ndarray, mass: np.ndarray, gravity_mps2: float,
             tilt_max_rad: float, thrust_max: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`accel_to_attitude_thrust` on (n, 3) accelerations, the yaw's cosine and sine
    (2, n) and (n,) or 0-d mass and thrust limit: (roll and pitch (2, n), thrust (n,))."""
    n = accel.shape[0]
    # f = m (g e3 - a), R e3 T = f; component-major (3, n): its rows are f_x, f_y, f_z.
    force = np.subtract(_down(gravity_mps2), accel.T, out=np.empty((3, n)))
    force *= mass
    horizontal, f_z = force[:2], force[2]
    sq = horizontal * horizontal
    h_norm = np.add(sq[0], sq[1], out=sq[0])
    np.sqrt(h_norm, out=h_norm)
    can_lift = f_z > 0.0
    f_z_pos = np.where(can_lift, f_z, 0.0)

    # Tilt limit, then thrust limit: both only shrink the horizontal part (vertical first).
    h_max = f_z_pos * _tan(tilt_max_rad)
    h_max = np.minimum(h_max, np.sqrt(np.maximum(thrust_max**2 - f_z_pos**2, 0.0)))
    f_z_sat = np.minimum(f_z_pos, thrust_max)
    scale = np.where(h_norm > h_max, h_max / np.where(h_norm > 0.0, h_norm, 1.0), 1.0)
    horizontal *= scale
    h_sat = np.where(can_lift, horizontal, 0.0)  # (f_x, f_y) saturated

    sq = h_sat * h_sat
    thrust = np.add(sq[0], sq[1], out=sq[0])
    thrust += f_z_sat * f_z_sat
    np.sqrt(thrust, out=thrust)
    safe = np.where(thrust > 0.0, thrust, 1.0)
    z_xy = h_sat / safe
    zz = f_z_sat / safe
    if np.fmin.reduce(thrust) <= 0.0:  # a level command somewhere (fmin: NaN aside)
        level = thrust <= 0.0
        z_xy[:, level] = 0.0
        zz[level] = 1.0

    # In the yaw-aligned frame, R e3 = [cos(roll) sin(pitch), -sin(roll), cos(roll) cos(pitch)].
    # Rz(yaw)^T z_body, written out (no einsum: faster, and independent of the batch size).
    # The four products (cy, sy) x (z_x, z_y) at once: zx = cy z_x + sy z_y and
    # zy = -sy z_x + cy z_y = cy z_y - sy z_x (the same addition, x + (-y) being x - y).
    prod = np.multiply(cos_sin[:, None, :], z_xy)
    zx = np.add(prod[0, 0], prod[1, 1])
    zy = np.subtract(prod[0, 1], prod[1, 0])
    roll_pitch = np.empty((2, n))
    np.arctan2(np.negative(zy, out=zy), np.hypot(zx, zz), out=roll_pitch[0])
    np.arctan2(zx, zz, out=roll_pitch[1])
    return roll_pitch, thrust


def _forward(roll_pitch: np.ndarray, cos_sin: np.ndarray, k: np.ndarray,
             gravity_mps2: float) -> np.ndarray:
    """:func:`attitude_thrust_to_accel` on roll and pitch (2, ...), the yaw's cosine and sine
    (2, ...) and ``k = T / m``, all of the full shape: (..., 3)."""
    # Third column of Rz(yaw) Ry(pitch) Rx(roll) (see aerodock.geometry.euler_to_rotmat):
    # -(cy sp cr + sy sr) k, -(sy sp cr - cy sr) k (the two rows at once), g - cp cr k.
    (cr, cp), (sr, sp) = np.cos(roll_pitch), np.sin(roll_pitch)
    horizontal = np.multiply(cos_sin, sp)
    horizontal *= cr
    cross = np.multiply(cos_sin[::-1], sr)
    np.add(horizontal[0, ...], cross[0, ...], out=horizontal[0, ...])  # (..., 0-d views too)
    np.subtract(horizontal[1, ...], cross[1, ...], out=horizontal[1, ...])
    np.negative(horizontal, out=horizontal)
    horizontal *= k
    out = np.empty(k.shape + (3,))
    out[..., 0], out[..., 1] = horizontal
    np.subtract(gravity_mps2, cp * cr * k, out=out[..., 2])
    return out


@functools.lru_cache(maxsize=16)
def _down(gravity_mps2: float) -> np.ndarray:
    """(3, 1) ``g e3`` as a read-only column."""
    out = np.array([[0.0], [0.0], [gravity_mps2]])
    freeze(out)
    return out


@functools.lru_cache(maxsize=16)
def _tan(angle_rad: float) -> float:
    """``np.tan`` of a limit (cached: the same few angles every call)."""
    return np.tan(angle_rad)


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
    roll_pitch = np.empty((2,) + shape)
    roll_pitch[0], roll_pitch[1] = roll, pitch
    cos_sin = np.empty((2,) + shape)
    cos_sin[0], cos_sin[1] = np.cos(yaw), np.sin(yaw)
    k = np.broadcast_to(thrust / mass, shape)  # every product below has the full shape
    return _forward(roll_pitch, cos_sin, k, gravity_mps2)
