"""The position controller's arithmetic, compiled: the LQR command, the inversion map to roll,
pitch and thrust with its saturation, and the forward map back to the acceleration commanded.

The one implementation of :func:`aerodock.control.lqr.lqr_command`,
:func:`aerodock.control.inversion.accel_to_attitude_thrust` and
:func:`~aerodock.control.inversion.attitude_thrust_to_accel` (which call these kernels), and of
the command of :meth:`aerodock.control.controller.PositionController.step`
(:func:`position_command`, which the controller's compiled step,
:func:`aerodock.control.controller_kernel.control_tick`, calls). Each trial's numbers are computed
operation by operation in the order the NumPy code did (the same numbers, to the bit:
``tools/same_numbers.py``): the LQR sum over the seven states from ``0.0`` in order, the
products and sums of the maps as written below, NumPy's own ``arctan2`` loop
(:func:`aerodock.jit.np_arctan2`), and NumPy's propagation of NaN through ``minimum`` and
``maximum`` (:func:`_nan_min`, :func:`_nan_max`).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence

import numpy as np

from aerodock.jit import njit, np_arctan2

N_STATE, N_INPUT, YAW_INDEX = 7, 4, 6
TWO_PI = 2.0 * np.pi


# -- the kernels' inputs, shaped in Python ---------------------------------------------------------
_F64, _BOOL = np.dtype(np.float64), np.dtype(np.bool_)


def rows3(value: np.ndarray | Sequence[float], n: int | None = None) -> np.ndarray:
    """``value`` as contiguous, writable float rows (n, 3) (broadcast to ``n`` rows when given;
    an array that already is one is returned as it is, checked first: the hot loop's common
    case). Writable, so that every caller's rows are the same type to the compiled kernels (a
    read-only array would be another compiled variant of each kernel it reaches): a read-only
    input is copied."""
    if (type(value) is np.ndarray and value.dtype is _F64 and value.ndim == 2
            and value.shape[1] == 3 and (n is None or value.shape[0] == n)
            and value.flags.carray):
        return value
    arr = np.atleast_2d(np.asarray(value, dtype=float))
    if n is not None and arr.shape[0] != n:
        arr = np.broadcast_to(arr, (n, 3))
    return _writable(arr)


def rows1(value: np.ndarray | float, n: int) -> np.ndarray:
    """``value`` as contiguous, writable float rows (n,) (a scalar: every trial's)."""
    if type(value) is np.ndarray and value.dtype is _F64 and value.shape == (n,) and (
            value.flags.carray):
        return value
    arr = np.asarray(value, dtype=float)
    if arr.shape != (n,):
        arr = np.broadcast_to(arr, (n,))
    return _writable(arr)


def mask_rows(value: np.ndarray, n: int) -> np.ndarray:
    """``value`` as contiguous, writable bool rows (n,)."""
    if type(value) is np.ndarray and value.dtype is _BOOL and value.shape == (n,) and (
            value.flags.carray):
        return value
    arr = np.asarray(value, dtype=np.bool_)
    if arr.shape != (n,):
        arr = np.broadcast_to(arr, (n,))
    return _writable(arr)


def _writable(arr: np.ndarray) -> np.ndarray:
    """``arr`` C-contiguous, aligned and writable (a copy unless it already is)."""
    return arr if arr.flags.carray else np.array(arr, order="C", copy=True)


def per_trial(value: np.ndarray | float, n: int) -> np.ndarray:
    """A per-trial constant as the kernels read it: (n,), or (1,) when one serves every trial."""
    arr = np.asarray(value, dtype=float)
    return np.ascontiguousarray(arr if arr.shape == (n,) else arr.reshape(-1)[:1])


@functools.lru_cache(maxsize=16)
def tilt_tangent(tilt_max_rad: float) -> float:
    """``tan`` of the tilt limit (``np.tan``'s number), checked to be in ``(0, pi/2)``.

    Raises:
        ValueError: the limit is outside ``(0, pi/2)``.
    """
    if not 0.0 < tilt_max_rad < 0.5 * np.pi:
        raise ValueError(f"tilt_max_rad must be in (0, pi/2), got {tilt_max_rad}")
    return float(np.tan(tilt_max_rad))


@njit
def _nan_min(a: float, b: float) -> float:
    """``np.minimum(a, b)``: NaN if either is."""
    if a != a or b != b:
        return a + b
    return a if a <= b else b


@njit
def _nan_max(a: float, b: float) -> float:
    """``np.maximum(a, b)``: NaN if either is."""
    if a != a or b != b:
        return a + b
    return a if a >= b else b


@njit
def wrap_angle(angle: float) -> float:
    """:func:`aerodock.geometry.wrap_angle` of one angle: ``(a + pi) % 2 pi - pi``."""
    return (angle + np.pi) % TWO_PI - np.pi


@njit
def lqr_rows(gains: np.ndarray, which: np.ndarray, pos: np.ndarray, vel: np.ndarray,
             yaw: np.ndarray, ref_pos: np.ndarray, ref_vel: np.ndarray, ref_accel: np.ndarray,
             ref_yaw: np.ndarray, ref_yaw_rate: np.ndarray, accel: np.ndarray,
             yaw_rate: np.ndarray) -> None:
    """``u = -K (x - x_ref) + [a_ref, psi_dot_ref]`` per trial into ``accel`` (n, 3) and
    ``yaw_rate`` (n,), trial ``i`` with the gain ``gains[which[i]]`` (of (m, 4, 7))."""
    err = np.empty(N_STATE)
    for i in range(pos.shape[0]):
        k = gains[which[i]]
        for c in range(3):
            err[c] = pos[i, c] - ref_pos[i, c]
            err[3 + c] = vel[i, c] - ref_vel[i, c]
        err[YAW_INDEX] = wrap_angle(yaw[i] - ref_yaw[i])
        for r in range(N_INPUT):
            u = 0.0
            for j in range(N_STATE):
                u = u + k[r, j] * err[j]
            u = -u
            if r < 3:
                accel[i, r] = u + ref_accel[i, r]
            else:
                yaw_rate[i] = u + ref_yaw_rate[i]


@njit
def inverse_rows(loops: np.ndarray, accel: np.ndarray, cos_yaw: np.ndarray,
                 sin_yaw: np.ndarray, mass: np.ndarray, gravity: float, tan_tilt: float,
                 thrust_max: np.ndarray, roll: np.ndarray, pitch: np.ndarray,
                 thrust: np.ndarray) -> None:
    """The inversion map with its saturation (:mod:`aerodock.control.inversion`) per trial:
    ``accel`` (n, 3), the yaw's cosine and sine (n,), ``mass`` and ``thrust_max`` (n,) or (1,)
    (one for every trial), into ``roll``, ``pitch``, ``thrust`` (n,)."""
    n = accel.shape[0]
    y_roll, x_roll, zx_rot, zz_out = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    for i in range(n):
        m = mass[i if mass.shape[0] > 1 else 0]
        t_max = thrust_max[i if thrust_max.shape[0] > 1 else 0]
        # f = m (g e3 - a): its horizontal part and its upward part
        fx = (0.0 - accel[i, 0]) * m
        fy = (0.0 - accel[i, 1]) * m
        fz = (gravity - accel[i, 2]) * m
        h_norm = math.sqrt(fx * fx + fy * fy)
        can_lift = fz > 0.0
        fz_pos = fz if can_lift else 0.0
        h_max = fz_pos * tan_tilt
        h_max = _nan_min(h_max, math.sqrt(_nan_max(t_max * t_max - fz_pos * fz_pos, 0.0)))
        fz_sat = _nan_min(fz_pos, t_max)
        scale = h_max / (h_norm if h_norm > 0.0 else 1.0) if h_norm > h_max else 1.0
        hx, hy = fx * scale, fy * scale
        if not can_lift:
            hx, hy = 0.0, 0.0
        total = hx * hx + hy * hy
        total += fz_sat * fz_sat
        total = math.sqrt(total)
        safe = total if total > 0.0 else 1.0
        zx, zy, zz = hx / safe, hy / safe, fz_sat / safe
        if total <= 0.0:  # a level command
            zx, zy, zz = 0.0, 0.0, 1.0
        # Rz(yaw)^T z_body: (cy zx + sy zy, cy zy - sy zx)
        c, s = cos_yaw[i], sin_yaw[i]
        rx = c * zx + s * zy
        ry = c * zy - s * zx
        y_roll[i] = -ry
        x_roll[i] = math.hypot(rx, zz)
        zx_rot[i], zz_out[i] = rx, zz
        thrust[i] = total
    np_arctan2(loops, y_roll, x_roll, roll)
    np_arctan2(loops, zx_rot, zz_out, pitch)


@njit
def body_z_axis(cr: float, sr: float, cp: float, sp: float, cy: float,
                sy: float) -> tuple[float, float, float]:
    """The third column of ``Rz(yaw) Ry(pitch) Rx(roll)`` from the angles' cosines and sines,
    each entry as :func:`aerodock.geometry.rpy_to_rotmat` computes it."""
    return cy * sp * cr + sy * sr, sy * sp * cr - cy * sr, cp * cr


@njit
def forward_rows(roll: np.ndarray, pitch: np.ndarray, cos_yaw: np.ndarray, sin_yaw: np.ndarray,
                 k: np.ndarray, gravity: float, out: np.ndarray) -> None:
    """``a = g e3 - R e3 k`` (``k = T / m``) per element of the flat rows into ``out`` (n, 3),
    ``R e3`` the third column of ``Rz(yaw) Ry(pitch) Rx(roll)``."""
    for i in range(roll.shape[0]):
        zx, zy, zz = body_z_axis(math.cos(roll[i]), math.sin(roll[i]), math.cos(pitch[i]),
                                 math.sin(pitch[i]), cos_yaw[i], sin_yaw[i])
        out[i, 0] = -zx * k[i]
        out[i, 1] = -zy * k[i]
        out[i, 2] = gravity - zz * k[i]


@njit
def position_command(loops: np.ndarray, gains: np.ndarray, which: np.ndarray,
                     pos: np.ndarray, vel: np.ndarray, yaw: np.ndarray,
                     ref_pos: np.ndarray, ref_vel: np.ndarray, ref_accel: np.ndarray,
                     ref_yaw: np.ndarray, ref_yaw_rate: np.ndarray, bias: np.ndarray,
                     ff: np.ndarray, has_ff: bool, mass: np.ndarray, gravity: float,
                     tan_tilt: float, thrust_max: np.ndarray, yaw_rate_max: float,
                     desired: np.ndarray, roll: np.ndarray, pitch: np.ndarray,
                     thrust: np.ndarray, applied: np.ndarray, yaw_rate: np.ndarray,
                     saturated: np.ndarray) -> None:
    """One command of :meth:`aerodock.control.controller.PositionController.step` for every
    trial: the LQR command (:func:`lqr_rows`), less the observers' ``bias`` and the
    feed-forward ``ff`` (when ``has_ff``) into ``desired``; the inversion map to ``roll``,
    ``pitch``, ``thrust``; the acceleration it commands, ``applied``; the yaw rate within
    ``yaw_rate_max``; and whether a limit cut the desired acceleration (``saturated``, by more
    than 1e-6 m/s² on an axis)."""
    n = pos.shape[0]
    lqr_rows(gains, which, pos, vel, yaw, ref_pos, ref_vel, ref_accel, ref_yaw, ref_yaw_rate,
             desired, yaw_rate)
    cos_yaw, sin_yaw = np.empty(n), np.empty(n)
    for i in range(n):
        for c in range(3):
            d = desired[i, c] - bias[i, c]
            if has_ff:
                d -= ff[i, c]
            desired[i, c] = d
        cos_yaw[i], sin_yaw[i] = math.cos(yaw[i]), math.sin(yaw[i])
    inverse_rows(loops, desired, cos_yaw, sin_yaw, mass, gravity, tan_tilt, thrust_max, roll,
                 pitch, thrust)
    k = np.empty(n)
    for i in range(n):
        k[i] = thrust[i] / mass[i if mass.shape[0] > 1 else 0]
    forward_rows(roll, pitch, cos_yaw, sin_yaw, k, gravity, applied)
    for i in range(n):
        yaw_rate[i] = _nan_min(_nan_max(yaw_rate[i], -yaw_rate_max), yaw_rate_max)
        worst = abs(applied[i, 0] - desired[i, 0])
        worst = _nan_max(worst, abs(applied[i, 1] - desired[i, 1]))
        worst = _nan_max(worst, abs(applied[i, 2] - desired[i, 2]))
        saturated[i] = worst > 1e-6
