"""The autopilots' attitude targets of a batch of vehicles, compiled (:func:`attitude_targets`):
the command clipped to the tilt and thrust limits and the target rotation at the yaw setpoint, with
NumPy's numbers to the bit (its cos and sin loops, its ``maximum``/``minimum`` ties and NaNs), so
that a control period's targets are one call instead of about 25 NumPy calls.
"""

from __future__ import annotations

import math

import numpy as np

from aerodock.jit import _unary, njit


@njit
def _np_maximum(a: float, b: float) -> float:
    """``np.maximum(a, b)`` on float64 to the bit: NaN in ``a`` propagates, ties (``-0.0`` and
    ``0.0`` too) give ``b`` (:func:`_max` keeps ``a`` on ties: its callers never meet a signed
    zero tie, the attitude targets' command may: a hover command is ``-0.0`` or ``0.0``)."""
    return a if (a > b or a != a) else b


@njit
def _np_minimum(a: float, b: float) -> float:
    """``np.minimum(a, b)`` on float64 to the bit: NaN in ``a`` propagates, ties give ``b``."""
    return a if (a < b or a != a) else b


@njit
def _row(a: np.ndarray, b: np.ndarray, i: int) -> float:
    """Row ``i`` of ``a`` then ``b`` joined (``np.concatenate((a, b))[i]``)."""
    na = a.shape[0]
    return a[i] if i < na else b[i - na]


@njit
def attitude_targets(trig: np.ndarray, roll_a: np.ndarray, roll_b: np.ndarray,
                     pitch_a: np.ndarray, pitch_b: np.ndarray, yaw_rate_a: np.ndarray,
                     yaw_rate_b: np.ndarray, thrust_a: np.ndarray, thrust_b: np.ndarray,
                     yaw_setpoint: np.ndarray, tilt_max: float,
                     thrust_max: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The autopilots' attitude targets of m vehicles, the commands of two batches ``_a`` and
    ``_b`` joined (the leaders' then the followers'; ``_b`` empty for one batch): (``R_des``
    transposed in memory (m, 3, 3): element ``[i, b, a]`` is row ``a``, column ``b`` of vehicle
    ``i``'s target, as the autopilot reads it; the yaw rates (m,); the collective thrust clipped
    to [0, ``thrust_max``] (m,)).

    The roll and pitch commands clipped to +-``tilt_max`` (``np.minimum(np.maximum(x, -tilt),
    tilt)``), the yaw at the setpoint, the rotation ``Rz(yaw) Ry(pitch) Rx(roll)`` from the
    angles' cosines and sines entry by entry as :func:`aerodock.geometry.rpy_to_rotmat` builds
    it, and the thrust as ``np.clip`` clips it: NumPy's numbers to the bit, with NumPy's own cos
    and sin loops (``trig``, :data:`aerodock.world.trig_loops.TRIG_LOOPS`) over the (m, 3)
    angles as one row, as ``np.cos(rpy)`` runs them (the C library's functions where ``trig``
    is zeros). One difference, on purpose: where a product's two factors are NaNs of opposite
    signs (a command holding NaNs), the NaN it gives may carry the other sign than NumPy's (LLVM
    may swap a product's operands, and x86 keeps the first one's NaN); nothing reads a NaN's
    sign."""
    m = roll_a.shape[0] + roll_b.shape[0]
    rpy = np.empty(3 * m)  # the (m, 3) angles, row-major
    for i in range(m):
        rpy[3 * i] = _np_minimum(_np_maximum(_row(roll_a, roll_b, i), -tilt_max), tilt_max)
        rpy[3 * i + 1] = _np_minimum(_np_maximum(_row(pitch_a, pitch_b, i), -tilt_max),
                                     tilt_max)
        rpy[3 * i + 2] = yaw_setpoint[i]
    cos, sin = np.empty(3 * m), np.empty(3 * m)
    if trig[0] != 0 and trig[1] != 0:
        _unary(trig[0], rpy, cos)
        _unary(trig[1], rpy, sin)
    else:
        for j in range(3 * m):
            cos[j], sin[j] = math.cos(rpy[j]), math.sin(rpy[j])
    r_t = np.empty((m, 3, 3))
    for i in range(m):
        cr, sr, cp, sp = cos[3 * i], sin[3 * i], cos[3 * i + 1], sin[3 * i + 1]
        cy, sy = cos[3 * i + 2], sin[3 * i + 2]
        cysp = cy * sp
        sysp = sy * sp
        r_t[i, 0, 0] = cy * cp
        r_t[i, 1, 0] = cysp * sr - sy * cr
        r_t[i, 2, 0] = cysp * cr + sy * sr
        r_t[i, 0, 1] = sy * cp
        r_t[i, 1, 1] = sysp * sr + cy * cr
        r_t[i, 2, 1] = sysp * cr - cy * sr
        r_t[i, 0, 2] = -sp
        r_t[i, 1, 2] = cp * sr
        r_t[i, 2, 2] = cp * cr
    yaw_rate, clipped = np.empty(m), np.empty(m)
    for i in range(m):  # np.clip: a NaN and a -0.0 pass as they are
        yaw_rate[i] = _row(yaw_rate_a, yaw_rate_b, i)
        t = _row(thrust_a, thrust_b, i)
        t = 0.0 if t < 0.0 else t
        clipped[i] = thrust_max if t > thrust_max else t
    return r_t, yaw_rate, clipped
