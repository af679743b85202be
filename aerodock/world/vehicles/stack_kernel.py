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


@njit
def _shape_axis(s: np.ndarray, i: int, k: int, accel: float, command: float, p: float,
                dt: float) -> float:
    """One shaped axis (roll ``k`` = 0, pitch 1) of vehicle ``i``: its target's new rate, the
    target advanced by it in place."""
    target = s[i, _PHI_T + k]
    rate = s[i, _PHI_RATE + k]
    wanted = sqrt_controller(command - target, p, accel)
    if accel > 0.0:
        wanted = min(max(wanted, rate - accel * dt), rate + accel * dt)
    s[i, _PHI_RATE + k] = wanted
    s[i, _PHI_T + k] = target + wanted * dt
    return wanted


@njit
def _shape(s: np.ndarray, i: int, c: np.ndarray, rd: tuple, yaw_rate: float,
           dt: float) -> tuple:
    """The shaper's step for vehicle ``i``: the target rotation (row-major) and the target's
    body rates (feed-forward), from the commanded ``rd``."""
    phi_cmd = math.atan2(rd[7], rd[8])
    theta_cmd = math.asin(min(max(-rd[6], -1.0), 1.0))
    psi = math.atan2(rd[3], rd[0])
    tc = c[45]
    if s[i, _SEEDED] == 0.0:
        s[i, _PHI_T], s[i, _THETA_T] = phi_cmd, theta_cmd
        s[i, _PHI_RATE] = s[i, _THETA_RATE] = 0.0
    rate_phi = _shape_axis(s, i, 0, c[42], phi_cmd, 1.0 / tc, dt)
    rate_theta = _shape_axis(s, i, 1, c[43], theta_cmd, 1.0 / tc, dt)
    phi, theta = s[i, _PHI_T], s[i, _THETA_T]
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
    return rt, w0, w1, w2


@njit
def _axis(s: np.ndarray, i: int, c: np.ndarray, j: int, e: float, gyro: float, ff: float,
          seeded: bool, dt: float) -> float:
    """Axis ``j`` of vehicle ``i``'s loops (module docstring): its torque, N m, from the
    attitude error ``e``, the gyro and the feed-forward rate ``ff``; its state in place."""
    ref = sqrt_controller(e, c[j], c[3 + j])
    if c[6 + j] != 0.0:
        lim = c[9 + j]
        acc = min(max(s[i, _A_INT + j] + e * dt, -lim), lim)
        s[i, _A_INT + j] = acc
        ref += c[6 + j] * acc
    ref += ff
    if not seeded:
        s[i, _TGT + j] = ref
        s[i, _ERR + j] = ref - gyro
        s[i, _PREV + j] = gyro if c[33 + j] != 0.0 else ref - gyro
    tgt = s[i, _TGT + j]
    tgt += _alpha(c[24 + j], dt) * (ref - tgt)
    s[i, _TGT + j] = tgt
    err = s[i, _ERR + j]
    err += _alpha(c[27 + j], dt) * ((tgt - gyro) - err)
    s[i, _ERR + j] = err
    lim = c[21 + j]
    integ = min(max(s[i, _R_INT + j] + err * dt, -lim), lim)
    s[i, _R_INT + j] = integ
    if c[33 + j] != 0.0:  # D on the measurement: the gyro's rate of change, negated
        x = gyro
        slope = -(x - s[i, _PREV + j]) / dt
    else:
        x = err
        slope = (x - s[i, _PREV + j]) / dt
    s[i, _PREV + j] = x
    der = s[i, _DER + j] if seeded else 0.0
    der += _alpha(c[30 + j], dt) * (slope - der)
    s[i, _DER + j] = der
    t = c[12 + j] * err + c[15 + j] * integ + c[18 + j] * der
    # the SJC law's J_tune dw_r/dt: w_r = lambda (q_r - q) + dq_r/dt with the reference's
    # second derivative zero, so dw_r/dt = lambda (dq_r/dt - dq/dt), dq/dt from the gyro
    # (controller_sjc.c computes it so: Z(q) w; the identity at small angles)
    t += c[36 + j] * c[j] * (ff - gyro)
    tmax = c[39 + j]
    return min(max(t, -tmax), tmax)


@njit
def stack_torque(s: np.ndarray, i: int, c: np.ndarray, att: tuple, rd: tuple,
                 yaw_rate: float, g0: float, g1: float, g2: float, dt: float) -> tuple:
    """One vehicle's attitude loops (module docstring): body torques (N m) from the estimated
    attitude ``att``, the commanded ``rd`` (row-major), the commanded yaw rate and the gyro;
    the state row ``s[i]`` advanced in place."""
    if c[45] > 0.0:
        rt, ff0, ff1, ff2 = _shape(s, i, c, rd, yaw_rate, dt)
    else:
        rt, ff0, ff1, ff2 = rd, 0.0, 0.0, yaw_rate
    # e = -vee(R_t^T R - R^T R_t) / 2, with m = R_t^T R
    m21 = rt[2] * att[1] + rt[5] * att[4] + rt[8] * att[7]
    m12 = rt[1] * att[2] + rt[4] * att[5] + rt[7] * att[8]
    m02 = rt[0] * att[2] + rt[3] * att[5] + rt[6] * att[8]
    m20 = rt[2] * att[0] + rt[5] * att[3] + rt[8] * att[6]
    m10 = rt[1] * att[0] + rt[4] * att[3] + rt[7] * att[6]
    m01 = rt[0] * att[1] + rt[3] * att[4] + rt[6] * att[7]
    seeded = s[i, _SEEDED] != 0.0
    t0 = _axis(s, i, c, 0, -0.5 * (m21 - m12), g0, ff0, seeded, dt)
    t1 = _axis(s, i, c, 1, -0.5 * (m02 - m20), g1, ff1, seeded, dt)
    t2 = _axis(s, i, c, 2, -0.5 * (m10 - m01), g2, ff2, seeded, dt)
    s[i, _SEEDED] = 1.0
    return t0, t1, t2
