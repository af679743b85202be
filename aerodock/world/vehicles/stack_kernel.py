"""The flight stacks' attitude loops, compiled: one cascade whose parts each stack's published
controller switches on (:mod:`aerodock.world.vehicles.stacks` binds the parameters, in SI).

Per axis (body roll, pitch, yaw), at the physics rate:

1. **Input shaping** (ArduCopter's ``input_quaternion`` with ``ATC_RATE_FF_ENAB``; off where
   the time constant is 0): the target roll and pitch follow the commanded ones through a
   square-root controller of gain ``1 / INPUT_TC`` whose rate changes by at most the
   acceleration limit a step; the target's rates are fed forward to the rate loop.
2. **The angle loop**: the rotation from the estimated attitude to the target,
   ``e = -vee(R_t^T R - R^T R_t) / 2`` (body, rad), through a square-root controller of gain
   ``ang_p`` and acceleration limit ``ang_accel`` (linear where the limit is 0), plus an
   integral (the Crazyflie PID's) clipped to its limit, plus the commanded yaw rate.
3. **The rate loop**: the reference rate low-passed (``FLTT``), the error to the gyro
   low-passed (``FLTE``), P and I on it (the integral of the error clipped to its limit), D on
   the error's or the gyro's derivative low-passed (``FLTD``), plus the SJC law's
   ``J_tune dw_r/dt = J_tune lambda (dq_r/dt - w)`` (the reference's feed-forward rate less
   the gyro), clipped to the output limit.
   First-order low-passes as ArduPilot's: ``y += a (x - y)``, ``a = dt / (dt + 1 / (2 pi f))``
   (1 where ``f`` is 0).

The torques go to the vehicle's mixer (:func:`aerodock.world.vehicles.rigid_kernel.mix`).

State per vehicle (:data:`STATE_COLUMNS` numbers; zeros start it, as a first call seeds the
filters): per axis the angle integral, the rate integral, the filtered reference, the filtered
error, the derivative's previous input, the filtered derivative; then
the shaper's target roll and pitch and their rates, and whether the filters are seeded.
"""

from __future__ import annotations

import math

import numpy as np

from aerodock.jit import njit

STATE_COLUMNS = 23
"""Numbers of state per vehicle (module docstring)."""
CONSTANTS = 47
"""Constants per stack: 15 rows of (roll, pitch, yaw), then the shaper's time constant (s) and
the mixer (0: the world's, attitude first when a rotor saturates; 1: each rotor clipped on its
own, as the SJC firmware's force-torque mixer). Rows: ang_p, ang_accel, ang_i, ang_ilim, rate_p,
rate_i, rate_d, rate_ilim, fltt_hz, flte_hz, fltd_hz, d_on_gyro (0/1), ref_inertia, torque_max,
shaper_accel."""

_A_INT, _R_INT, _TGT, _ERR, _PREV, _DER = 0, 3, 6, 9, 12, 15
_PHI_T, _THETA_T, _PHI_RATE, _THETA_RATE, _SEEDED = 18, 19, 20, 21, 22


@njit
def _alpha(cutoff_hz: float, dt: float) -> float:
    """ArduPilot's first-order low-pass factor (1: no filter)."""
    if cutoff_hz <= 0.0:
        return 1.0
    return dt / (dt + 1.0 / (2.0 * math.pi * cutoff_hz))


@njit
def sqrt_controller(error: float, p: float, accel: float) -> float:
    """ArduPilot's ``sqrt_controller`` (AP_Math/control.cpp): ``p e`` within ``accel / p^2``,
    beyond it ``sqrt(2 a (|e| - a / (2 p^2)))`` (the rate from which a constant deceleration
    ``accel`` stops at the target); linear where ``accel`` is 0."""
    if accel <= 0.0:
        return p * error
    if p == 0.0:
        return math.copysign(math.sqrt(2.0 * accel * abs(error)), error)
    knee = accel / (p * p)
    if abs(error) <= knee:
        return p * error
    return math.copysign(math.sqrt(2.0 * accel * (abs(error) - 0.5 * knee)), error)


_NO_STACK = np.zeros(CONSTANTS)  # the constants where no stack flies


@njit
def constants_tuple(stack_on: bool, a: np.ndarray) -> tuple:
    """The :data:`CONSTANTS` numbers of a stack as a tuple, zeros where no stack flies (``a``
    then any array, unread). Read once a call: the loops' helpers take numbers, never arrays,
    whose reference counts (a pair of atomic operations an array a call) would cost more
    than their arithmetic."""
    if stack_on:
        return _tuple47(a)
    return _tuple47(_NO_STACK)


@njit
def _tuple47(a: np.ndarray) -> tuple:
    return (a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11], a[12],
            a[13], a[14], a[15], a[16], a[17], a[18], a[19], a[20], a[21], a[22], a[23], a[24],
            a[25], a[26], a[27], a[28], a[29], a[30], a[31], a[32], a[33], a[34], a[35], a[36],
            a[37], a[38], a[39], a[40], a[41], a[42], a[43], a[44], a[45], a[46])


@njit
def stack_row(s: np.ndarray, i: int) -> tuple:
    """Vehicle ``i``'s :data:`STATE_COLUMNS` numbers of state as a tuple."""
    return (s[i, 0], s[i, 1], s[i, 2], s[i, 3], s[i, 4], s[i, 5], s[i, 6], s[i, 7], s[i, 8],
            s[i, 9], s[i, 10], s[i, 11], s[i, 12], s[i, 13], s[i, 14], s[i, 15], s[i, 16],
            s[i, 17], s[i, 18], s[i, 19], s[i, 20], s[i, 21], s[i, 22])


@njit
def store_stack_row(s: np.ndarray, i: int, row: tuple) -> None:
    """Write a state tuple (:func:`stack_torque`'s) into row ``i`` of ``s``."""
    for col in range(STATE_COLUMNS):
        s[i, col] = row[col]


@njit
def _shape_axis(target: float, rate: float, accel: float, command: float, p: float,
                dt: float) -> tuple:
    """One shaped axis: the target's new rate and the target advanced by it."""
    wanted = sqrt_controller(command - target, p, accel)
    if accel > 0.0:
        wanted = min(max(wanted, rate - accel * dt), rate + accel * dt)
    return wanted, target + wanted * dt


@njit
def _shape(phi_t: float, theta_t: float, phi_rate: float, theta_rate: float, seeded: bool,
           tc: float, accel_phi: float, accel_theta: float, rd: tuple, yaw_rate: float,
           dt: float) -> tuple:
    """The shaper's step: the target rotation (row-major), the target's body rates
    (feed-forward), from the commanded ``rd``; and the shaper's new state (target roll and
    pitch, their rates)."""
    phi_cmd = math.atan2(rd[7], rd[8])
    theta_cmd = math.asin(min(max(-rd[6], -1.0), 1.0))
    psi = math.atan2(rd[3], rd[0])
    if not seeded:
        phi_t, theta_t = phi_cmd, theta_cmd
        phi_rate = theta_rate = 0.0
    rate_phi, phi = _shape_axis(phi_t, phi_rate, accel_phi, phi_cmd, 1.0 / tc, dt)
    rate_theta, theta = _shape_axis(theta_t, theta_rate, accel_theta, theta_cmd, 1.0 / tc, dt)
    cf, sf = math.cos(phi), math.sin(phi)
    ct, st = math.cos(theta), math.sin(theta)
    cp, sp = math.cos(psi), math.sin(psi)
    rt = (cp * ct, cp * st * sf - sp * cf, cp * st * cf + sp * sf,
          sp * ct, sp * st * sf + cp * cf, sp * st * cf - cp * sf,
          -st, ct * sf, ct * cf)
    # ZYX Euler rates to body rates at the target attitude
    w0 = rate_phi - st * yaw_rate
    w1 = cf * rate_theta + sf * ct * yaw_rate
    w2 = -sf * rate_theta + cf * ct * yaw_rate
    return rt, w0, w1, w2, phi, theta, rate_phi, rate_theta


@njit
def _axis_state(row: tuple, j: int) -> tuple:
    """Axis ``j``'s six numbers of a state row: angle integral, rate integral, filtered
    reference, filtered error, the derivative's previous input, filtered derivative."""
    return (row[_A_INT + j], row[_R_INT + j], row[_TGT + j], row[_ERR + j], row[_PREV + j],
            row[_DER + j])


@njit
def _axis_constants(c: tuple, j: int) -> tuple:
    """Axis ``j``'s fourteen constants (the rows of :data:`CONSTANTS`, in their order)."""
    return (c[j], c[3 + j], c[6 + j], c[9 + j], c[12 + j], c[15 + j], c[18 + j], c[21 + j],
            c[24 + j], c[27 + j], c[30 + j], c[33 + j], c[36 + j], c[39 + j])


@njit
def _axis(state: tuple, k: tuple, e: float, gyro: float, ff: float, seeded: bool,
          dt: float) -> tuple:
    """One axis's loops (module docstring): its torque, N m, from the attitude error ``e``, the
    gyro and the feed-forward rate ``ff``, with its state (:func:`_axis_state`) and constants
    (:func:`_axis_constants`); and its new state."""
    a_int, r_int, tgt, err, prev, der = state
    (ang_p, ang_accel, ang_i, ang_ilim, rate_p, rate_i, rate_d, rate_ilim, fltt, flte, fltd,
     d_on_gyro, ref_inertia, torque_max) = k
    ref = sqrt_controller(e, ang_p, ang_accel)
    if ang_i != 0.0:
        a_int = min(max(a_int + e * dt, -ang_ilim), ang_ilim)
        ref += ang_i * a_int
    ref += ff
    if not seeded:
        tgt = ref
        err = ref - gyro
        prev = gyro if d_on_gyro != 0.0 else ref - gyro
    tgt += _alpha(fltt, dt) * (ref - tgt)
    err += _alpha(flte, dt) * ((tgt - gyro) - err)
    r_int = min(max(r_int + err * dt, -rate_ilim), rate_ilim)
    if d_on_gyro != 0.0:  # D on the measurement: the gyro's rate of change, negated
        x = gyro
        slope = -(x - prev) / dt
    else:
        x = err
        slope = (x - prev) / dt
    der = der if seeded else 0.0
    der += _alpha(fltd, dt) * (slope - der)
    t = rate_p * err + rate_i * r_int + rate_d * der
    # the SJC law's J_tune dw_r/dt: w_r = lambda (q_r - q) + dq_r/dt with the reference's
    # second derivative zero, so dw_r/dt = lambda (dq_r/dt - dq/dt), dq/dt from the gyro
    # (controller_sjc.c computes it so: Z(q) w; the identity at small angles)
    t += ref_inertia * ang_p * (ff - gyro)
    return min(max(t, -torque_max), torque_max), a_int, r_int, tgt, err, x, der


@njit
def stack_torque(row: tuple, c: tuple, att: tuple, rd: tuple, yaw_rate: float, g0: float,
                 g1: float, g2: float, dt: float) -> tuple:
    """One vehicle's attitude loops (module docstring): body torques (N m) from the estimated
    attitude ``att``, the commanded ``rd`` (row-major), the commanded yaw rate and the gyro,
    with its state ``row`` (:func:`stack_row`) and the stack's constants ``c``
    (:func:`constants_tuple`); returns the three torques and the new state row."""
    phi_t, theta_t, phi_rate, theta_rate = row[_PHI_T], row[_THETA_T], row[_PHI_RATE], \
        row[_THETA_RATE]
    seeded = row[_SEEDED] != 0.0
    if c[45] > 0.0:
        rt, ff0, ff1, ff2, phi_t, theta_t, phi_rate, theta_rate = _shape(
            phi_t, theta_t, phi_rate, theta_rate, seeded, c[45], c[42], c[43], rd, yaw_rate, dt)
    else:
        rt, ff0, ff1, ff2 = rd, 0.0, 0.0, yaw_rate
    # e = -vee(R_t^T R - R^T R_t) / 2, with m = R_t^T R
    m21 = rt[2] * att[1] + rt[5] * att[4] + rt[8] * att[7]
    m12 = rt[1] * att[2] + rt[4] * att[5] + rt[7] * att[8]
    m02 = rt[0] * att[2] + rt[3] * att[5] + rt[6] * att[8]
    m20 = rt[2] * att[0] + rt[5] * att[3] + rt[8] * att[6]
    m10 = rt[1] * att[0] + rt[4] * att[3] + rt[7] * att[6]
    m01 = rt[0] * att[1] + rt[3] * att[4] + rt[6] * att[7]
    t0, ai0, ri0, tg0, er0, pv0, dr0 = _axis(_axis_state(row, 0), _axis_constants(c, 0),
                                             -0.5 * (m21 - m12), g0, ff0, seeded, dt)
    t1, ai1, ri1, tg1, er1, pv1, dr1 = _axis(_axis_state(row, 1), _axis_constants(c, 1),
                                             -0.5 * (m02 - m20), g1, ff1, seeded, dt)
    t2, ai2, ri2, tg2, er2, pv2, dr2 = _axis(_axis_state(row, 2), _axis_constants(c, 2),
                                             -0.5 * (m10 - m01), g2, ff2, seeded, dt)
    new = (ai0, ai1, ai2, ri0, ri1, ri2, tg0, tg1, tg2, er0, er1, er2, pv0, pv1, pv2, dr0, dr1,
           dr2, phi_t, theta_t, phi_rate, theta_rate, 1.0)  # STATE_COLUMNS' order
    return t0, t1, t2, new
