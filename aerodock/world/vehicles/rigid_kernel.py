"""The rigid-body vehicles' physics step, compiled: autopilot, mixer, rotor wrench with drag,
Euler's equations, attitude and motors, one vehicle at a time in one loop.

This is the one implementation of these terms; :mod:`aerodock.world.vehicles.rigid_body` and
:mod:`aerodock.world.vehicles.autopilot` bind the parameters and call it. Each vehicle's numbers
are computed operation by operation in the order the NumPy step computed them (the order is
part of the numbers, and the batch's numbers equal its single trials'), and the 3 x 3 products
summed as ``np.matmul`` sums them on the machine at hand (:func:`aerodock.jit.dot3_vecmat` for a
row vector times a matrix, ``v^T R``; ``dot3_matvec`` for ``R f``; ``dot3_matmat`` and
``dot3_tmatmat`` for ``R E`` and ``R_d^T R``): the order is the BLAS kernel's, read at import
(:mod:`aerodock.product_order`); OpenBLAS's AVX2 kernels, for example, round ``a^T R`` as
``fma(a2, b2, fma(a1, b1, a0 b0))`` on one processor and as plain sums from zero on another.

Maxima and minima follow NumPy's (``np.maximum`` keeps its first argument when it is NaN or
when the two are equal), so a NaN propagates as it did.

The helpers take and return numbers and tuples of numbers, never arrays: a compiled call with
array arguments pays for their reference counts (tens of nanoseconds a call, more than the
arithmetic here), so the loops over the batch index the arrays themselves. Constant matrices
travel as flat arrays (:func:`flat`), read into tuples once a call.
"""

from __future__ import annotations

import math

import numpy as np

from aerodock.jit import any_layout, dot3_matmat, dot3_matvec, dot3_tmatmat, dot3_vecmat, njit
from aerodock.world.vehicles.stack_kernel import (
    constants_tuple,
    stack_row,
    stack_torque,
    store_stack_row,
)


def flat(values: np.ndarray) -> np.ndarray:
    """A constant array as the kernels take it: its numbers, row-major, in a flat read-only
    array (the kernel reads it into a tuple once a call: :func:`tuple12` and its kin; a tuple
    argument would cost the call's dispatch a type check per number)."""
    out = np.array(values, dtype=float).ravel()
    out.flags.writeable = False
    return out


@njit
def tuple12(a: np.ndarray) -> tuple:
    """A flat 12-array's numbers as a tuple (read once per kernel call)."""
    return (a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11])


@njit
def tuple16(a: np.ndarray) -> tuple:
    """A flat 16-array's numbers as a tuple."""
    return (a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11], a[12],
            a[13], a[14], a[15])


@njit
def tuple18(a: np.ndarray) -> tuple:
    """A flat 18-array's numbers as a tuple."""
    return (a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11], a[12],
            a[13], a[14], a[15], a[16], a[17])


@njit
def tuple28(a: np.ndarray) -> tuple:
    """A flat 28-array's numbers as a tuple."""
    return (a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11], a[12],
            a[13], a[14], a[15], a[16], a[17], a[18], a[19], a[20], a[21], a[22], a[23], a[24],
            a[25], a[26], a[27])


@njit
def dot4(a0: float, a1: float, a2: float, a3: float, b0: float, b1: float, b2: float,
         b3: float) -> float:
    """``((a0 b0 + a1 b1) + a2 b2) + a3 b3``: a sum over four rotors in NumPy's order (each
    product rounded, then added one by one)."""
    s = a0 * b0 + a1 * b1
    s += a2 * b2
    s += a3 * b3
    return s


@njit
def _max(a: float, b: float) -> float:
    """``np.maximum(a, b)``: NaN propagates, ties keep ``a``."""
    return a if (a >= b or a != a) else b


@njit
def _min(a: float, b: float) -> float:
    """``np.minimum(a, b)``: NaN propagates, ties keep ``a``."""
    return a if (a <= b or a != a) else b


@njit
def exp_so3(phi0: float, phi1: float, phi2: float) -> tuple:
    """``exp([phi]x)`` row-major (Rodrigues; below theta^2 = 1e-12 the series of sin(t)/t and
    (1 - cos t)/t^2): ``b p p^T + (1 - b theta^2) I + a [p]x``."""
    theta2 = phi0 * phi0 + phi1 * phi1
    theta2 += phi2 * phi2
    if theta2 < 1e-12:
        a = 1.0 - theta2 / 6.0
        b = 0.5 - theta2 / 24.0
    else:
        theta = math.sqrt(theta2)
        a = math.sin(theta) / theta
        b = (1.0 - math.cos(theta)) / (theta * theta)
    bp0, bp1, bp2 = phi0 * b, phi1 * b, phi2 * b
    ap0, ap1, ap2 = phi0 * a, phi1 * a, phi2 * a
    diag = 1.0 - b * theta2
    return (bp0 * phi0 + diag, bp0 * phi1 + (-ap2), bp0 * phi2 + ap1,
            bp1 * phi0 + ap2, bp1 * phi1 + diag, bp1 * phi2 + (-ap0),
            bp2 * phi0 + (-ap1), bp2 * phi1 + ap0, bp2 * phi2 + diag)


@njit
def mat3_mul(r: tuple, e: tuple) -> tuple:
    """``r e`` for row-major 3 x 3 tuples, rounded as ``np.matmul`` here (:func:`dot3_matmat`)."""
    return (dot3_matmat(r[0], r[1], r[2], e[0], e[3], e[6]),
            dot3_matmat(r[0], r[1], r[2], e[1], e[4], e[7]),
            dot3_matmat(r[0], r[1], r[2], e[2], e[5], e[8]),
            dot3_matmat(r[3], r[4], r[5], e[0], e[3], e[6]),
            dot3_matmat(r[3], r[4], r[5], e[1], e[4], e[7]),
            dot3_matmat(r[3], r[4], r[5], e[2], e[5], e[8]),
            dot3_matmat(r[6], r[7], r[8], e[0], e[3], e[6]),
            dot3_matmat(r[6], r[7], r[8], e[1], e[4], e[7]),
            dot3_matmat(r[6], r[7], r[8], e[2], e[5], e[8]))


@njit
def load3x3(a: np.ndarray, i: int) -> tuple:
    """Row ``i`` of an (m, 3, 3) array as a row-major tuple."""
    return (a[i, 0, 0], a[i, 0, 1], a[i, 0, 2], a[i, 1, 0], a[i, 1, 1], a[i, 1, 2],
            a[i, 2, 0], a[i, 2, 1], a[i, 2, 2])


@njit
def store3x3(out: np.ndarray, i: int, m: tuple) -> None:
    """A row-major tuple into row ``i`` of an (m, 3, 3) array."""
    out[i, 0, 0], out[i, 0, 1], out[i, 0, 2] = m[0], m[1], m[2]
    out[i, 1, 0], out[i, 1, 1], out[i, 1, 2] = m[3], m[4], m[5]
    out[i, 2, 0], out[i, 2, 1], out[i, 2, 2] = m[6], m[7], m[8]


@njit
def mix(thrust: float, tau0: float, tau1: float, tau2: float, mixer_inv: tuple,
        rotor_thrust_max: float) -> tuple:
    """The airmode mixer of a quadrotor: four rotor thrusts from ``[T, tau_x, tau_y, tau_z]``
    through ``mixer_inv`` (4 x 4, row-major: row j multiplies the wrench's j-th entry); the
    collective shifted (down when a rotor exceeds its maximum, up when one would go below
    zero) so the torque differences survive, then every rotor clipped to
    ``[0, rotor_thrust_max]``."""
    m = mixer_inv
    f0 = dot4(m[0], m[4], m[8], m[12], thrust, tau0, tau1, tau2)
    f1 = dot4(m[1], m[5], m[9], m[13], thrust, tau0, tau1, tau2)
    f2 = dot4(m[2], m[6], m[10], m[14], thrust, tau0, tau1, tau2)
    f3 = dot4(m[3], m[7], m[11], m[15], thrust, tau0, tau1, tau2)
    lo = -_min(_min(_min(f0, f1), f2), f3)
    hi = rotor_thrust_max - _max(_max(_max(f0, f1), f2), f3)
    shift = _min(_max(lo, 0.0), hi)
    if lo > hi:
        shift = (lo + hi) * 0.5
    return (_min(_max(f0 + shift, 0.0), rotor_thrust_max),
            _min(_max(f1 + shift, 0.0), rotor_thrust_max),
            _min(_max(f2 + shift, 0.0), rotor_thrust_max),
            _min(_max(f3 + shift, 0.0), rotor_thrust_max))


@njit
def rotor_commands(thrust: float, tau0: float, tau1: float, tau2: float, mixer_inv: tuple,
                   rotor_thrust_max: float, thrust_coeff: float) -> tuple:
    """The mixer's four rotor thrusts (:func:`mix`) as rotor speed commands through the nominal
    k_T ``thrust_coeff``, rad/s."""
    f0, f1, f2, f3 = mix(thrust, tau0, tau1, tau2, mixer_inv, rotor_thrust_max)
    return (math.sqrt(f0 / thrust_coeff), math.sqrt(f1 / thrust_coeff),
            math.sqrt(f2 / thrust_coeff), math.sqrt(f3 / thrust_coeff))


@njit
def _rate_loop(sp: float, gyro: float, integral: float, limit: float, int_limit: float,
               rate_p: float, rate_i: float, inertia: float, dt: float) -> tuple:
    """One axis of the rate loop: the setpoint clipped to the rate limit, PI on the gyro with
    the integral clipped (anti-windup), times the nominal inertia: (torque N m, integral)."""
    sp = _min(_max(sp, -limit), limit)
    err = sp - gyro
    acc = err * dt
    acc += integral
    acc = _min(_max(acc, -int_limit), int_limit)
    t = err * rate_p
    t += acc * rate_i
    return t * inertia, acc


@njit
def autopilot(att: tuple, rd: tuple, yaw_rate: float, thrust_cmd: float, has_ff: bool,
              ff0: float, ff1: float, ff2: float, g0: float, g1: float, g2: float, i0: float,
              i1: float, i2: float, consts: tuple, mixer_inv: tuple, rotor_thrust_max: float,
              thrust_coeff: float, dt: float) -> tuple:
    """One vehicle's autopilot: attitude P (geometric error ``vee(R_d^T R - R^T R_d) / 2``
    times the angle gain, plus the yaw rate feed-forward), rate PI on the gyro ``g`` (integral
    ``i``), times the nominal inertia, plus the torque feed-forward ``ff``; the mixer; rotor
    speed commands through the nominal k_T. Returns the four commands (rad/s) and the new
    integral.

    ``consts`` (18,): rows -attitude_p / 2, the rate limit, the integral limit, rate_p, rate_i,
    the nominal inertia, each (x, y, z).
    """
    m21 = dot3_tmatmat(rd[2], rd[5], rd[8], att[1], att[4], att[7])
    m12 = dot3_tmatmat(rd[1], rd[4], rd[7], att[2], att[5], att[8])
    m02 = dot3_tmatmat(rd[0], rd[3], rd[6], att[2], att[5], att[8])
    m20 = dot3_tmatmat(rd[2], rd[5], rd[8], att[0], att[3], att[6])
    m10 = dot3_tmatmat(rd[1], rd[4], rd[7], att[0], att[3], att[6])
    m01 = dot3_tmatmat(rd[0], rd[3], rd[6], att[1], att[4], att[7])
    sp2 = (m10 - m01) * consts[2]
    sp2 += yaw_rate
    tau0, n0 = _rate_loop((m21 - m12) * consts[0], g0, i0, consts[3], consts[6], consts[9],
                          consts[12], consts[15], dt)
    tau1, n1 = _rate_loop((m02 - m20) * consts[1], g1, i1, consts[4], consts[7], consts[10],
                          consts[13], consts[16], dt)
    tau2, n2 = _rate_loop(sp2, g2, i2, consts[5], consts[8], consts[11], consts[14],
                          consts[17], dt)
    if has_ff:
        tau0 += ff0
        tau1 += ff1
        tau2 += ff2
    c0, c1, c2, c3 = rotor_commands(thrust_cmd, tau0, tau1, tau2, mixer_inv,
                                    rotor_thrust_max, thrust_coeff)
    return c0, c1, c2, c3, n0, n1, n2


@njit
def stack_autopilot(row: tuple, stack_c: tuple, att: tuple, rd: tuple, yaw_rate: float,
                    thrust_cmd: float, has_ff: bool, ff0: float, ff1: float, ff2: float,
                    g0: float, g1: float, g2: float, mixer_inv: tuple, rotor_thrust_max: float,
                    thrust_coeff: float, dt: float) -> tuple:
    """One vehicle's flight-stack autopilot (:func:`stack_kernel.stack_torque`) with the
    torque feed-forward, the mixer and the rotor speed commands, from its state ``row``
    (:func:`stack_kernel.stack_row`) and the stack's constants
    (:func:`stack_kernel.constants_tuple`): the four commands and the new state row."""
    tau0, tau1, tau2, new = stack_torque(row, stack_c, att, rd, yaw_rate, g0, g1, g2, dt)
    if has_ff:
        tau0 += ff0
        tau1 += ff1
        tau2 += ff2
    if stack_c[46] != 0.0:  # each rotor clipped on its own (the SJC firmware's mixer)
        m = mixer_inv
        f0 = _min(_max(dot4(m[0], m[4], m[8], m[12], thrust_cmd, tau0, tau1, tau2), 0.0),
                  rotor_thrust_max)
        f1 = _min(_max(dot4(m[1], m[5], m[9], m[13], thrust_cmd, tau0, tau1, tau2), 0.0),
                  rotor_thrust_max)
        f2 = _min(_max(dot4(m[2], m[6], m[10], m[14], thrust_cmd, tau0, tau1, tau2), 0.0),
                  rotor_thrust_max)
        f3 = _min(_max(dot4(m[3], m[7], m[11], m[15], thrust_cmd, tau0, tau1, tau2), 0.0),
                  rotor_thrust_max)
        return (math.sqrt(f0 / thrust_coeff), math.sqrt(f1 / thrust_coeff),
                math.sqrt(f2 / thrust_coeff), math.sqrt(f3 / thrust_coeff), new)
    c0, c1, c2, c3 = rotor_commands(thrust_cmd, tau0, tau1, tau2, mixer_inv, rotor_thrust_max,
                                    thrust_coeff)
    return c0, c1, c2, c3, new


@njit
def rotor_wrench(o0: float, o1: float, o2: float, o3: float, kc: float, torque_gain: float,
                 vb0: float, vb1: float, vb2: float, wx: float, wy: float, wz: float,
                 tm: tuple, ds: tuple, kd: float, kz: float) -> tuple:
    """One vehicle's rotor force and torque, body FRD: thrust and yaw reaction of each rotor
    (k_T ``kc``; ``tm`` the (4, 3) torque map), and rotor drag at each hub (RotorPy's H-force
    and induced-inflow terms on the local airspeed ``v_b + w x r_i``, through the speeds'
    weighted sums of the (4, 7) ``ds``: columns 1, -y, x, y, xx, yy, xy). Returns (force x, y,
    z, torque x, y, z)."""
    f0 = o0 * o0 * kc
    f1 = o1 * o1 * kc
    f2 = o2 * o2 * kc
    f3 = o3 * o3 * kc
    tq0 = dot4(tm[0], tm[3], tm[6], tm[9], f0, f1, f2, f3)
    tq1 = dot4(tm[1], tm[4], tm[7], tm[10], f0, f1, f2, f3)
    tq2 = dot4(tm[2], tm[5], tm[8], tm[11], f0, f1, f2, f3)
    tq2 *= torque_gain
    thrust = f0 + f1
    thrust += f2
    thrust += f3
    fb0 = 0.0
    fb1 = 0.0
    fb2 = -thrust
    if kd != 0.0 or kz != 0.0:
        s0 = _drag_sum(o0, o1, o2, o3, ds, 0)
        s1 = _drag_sum(o0, o1, o2, o3, ds, 1)
        s2 = _drag_sum(o0, o1, o2, o3, ds, 2)
        s3 = _drag_sum(o0, o1, o2, o3, ds, 3)
        s4 = _drag_sum(o0, o1, o2, o3, ds, 4)
        s5 = _drag_sum(o0, o1, o2, o3, ds, 5)
        s6 = _drag_sum(o0, o1, o2, o3, ds, 6)
        # the axial force and the roll and pitch moments: rows (0, 3, 2 | 3, 5, 6 | 2, 6, 4)
        ax0 = s0 * vb2
        ax0 += wx * s3
        ax0 -= wy * s2
        ax0 *= kz
        ax1 = s3 * vb2
        ax1 += wx * s5
        ax1 -= wy * s6
        ax1 *= kz
        ax2 = s2 * vb2
        ax2 += wx * s6
        ax2 -= wy * s4
        ax2 *= kz
        fb2 -= ax0
        tq0 -= ax1
        tq1 += ax2
        pl0 = s0 * vb0
        pl0 += wz * s1
        pl0 *= kd
        pl1 = s0 * vb1
        pl1 += wz * s2
        pl1 *= kd
        fb0 = 0.0 - pl0
        fb1 = 0.0 - pl1
        yaw = s2 * vb1
        yaw -= s3 * vb0
        spin = s4 + s5
        spin *= wz
        yaw += spin
        yaw *= kd
        tq2 -= yaw
    return fb0, fb1, fb2, tq0, tq1, tq2


@njit
def _drag_sum(o0: float, o1: float, o2: float, o3: float, ds: tuple, c: int) -> float:
    """Column ``c`` of the rotor drag's weighted sums, ``sum_i omega_i ds[i, c]`` in order."""
    return dot4(ds[c], ds[7 + c], ds[14 + c], ds[21 + c], o0, o1, o2, o3)


@njit
def step_vehicles_body(p: np.ndarray, v: np.ndarray, rot: np.ndarray, w: np.ndarray,
                       omega: np.ndarray, thrust_coeffs: np.ndarray, torque_gain: np.ndarray,
                       mass_rows: np.ndarray, inertia: np.ndarray, alpha: np.ndarray,
                       autopilot_on: bool, omega_cmd: np.ndarray, att: np.ndarray, use_att: bool,
                       r_des: np.ndarray, yaw_rate: np.ndarray, thrust_cmd: np.ndarray,
                       torque_ff: np.ndarray, has_ff: bool, gyro: np.ndarray,
                       gyro_noise: np.ndarray, noisy: bool, integral: np.ndarray,
                       yaw_sp: np.ndarray, consts_a: np.ndarray, stack_on: bool,
                       stack_c: np.ndarray, mixer_a: np.ndarray, rotor_thrust_max: float,
                       thrust_coeff: float, ext_force: np.ndarray, ext_torque: np.ndarray,
                       has_ext_torque: bool, torque_map_a: np.ndarray, drag_sums_a: np.ndarray,
                       kd: float, kz: float, c_drag: float, gravity: float, dt: float,
                       p_new: np.ndarray, v_new: np.ndarray, rot_new: np.ndarray, w_new: np.ndarray,
                       omega_new: np.ndarray, thrust_new: np.ndarray, accel: np.ndarray,
                       integral_new: np.ndarray, yaw_sp_new: np.ndarray) -> None:
    """One physics step of ``n`` rigid bodies, written into the ``*_new`` arrays and ``accel``
    (the step's acceleration, NED).

    With ``autopilot_on`` each vehicle's autopilot (:func:`autopilot`) flies its held targets
    (``r_des``, ``yaw_rate``, ``thrust_cmd``, ``torque_ff``) on the gyro (``gyro`` plus
    ``gyro_noise`` when ``noisy``) and the attitude ``att`` (when ``use_att``, else the true
    one), and the yaw setpoint advances by the yaw rate; without it the rotors are commanded
    ``omega_cmd`` (n, 4). External forces (n, 3, world NED) and torques (n, 3, body FRD) act at
    the centre of mass.

    Velocity and body rates by explicit Euler on the current derivatives; position and
    attitude on the mean of old and new rates (the attitude by the exact Rodrigues
    exponential); the motors by their exact first-order step (``alpha``: ``1 - exp(-dt/tau)``,
    (n,) or one number in a (1,) array).

    It is long because it is one fused loop per vehicle (autopilot, mixer, rotor wrench,
    Euler's equations, attitude, motors): split into kernels that each loop over the batch, the
    step would write and re-read its intermediates through memory, which halved the compiled
    step's gain when measured (issue 38); the stages it calls stand alone above.
    """
    consts, mixer_inv = tuple18(consts_a), tuple16(mixer_a)
    torque_map, drag_sums = tuple12(torque_map_a), tuple28(drag_sums_a)
    stack = constants_tuple(stack_on, stack_c)
    per_vehicle_alpha = alpha.shape[0] > 1
    half = 0.5 * dt
    for i in range(p.shape[0]):
        r = load3x3(rot, i)
        if autopilot_on:
            g0, g1, g2 = gyro[i, 0], gyro[i, 1], gyro[i, 2]
            if noisy:
                g0 += gyro_noise[i, 0]
                g1 += gyro_noise[i, 1]
                g2 += gyro_noise[i, 2]
            ff0 = ff1 = ff2 = 0.0
            if has_ff:
                ff0, ff1, ff2 = torque_ff[i, 0], torque_ff[i, 1], torque_ff[i, 2]
            if stack_on:
                c0, c1, c2, c3, row = stack_autopilot(
                    stack_row(integral, i), stack, load3x3(att, i) if use_att else r,
                    load3x3(r_des, i), yaw_rate[i], thrust_cmd[i], has_ff, ff0, ff1, ff2, g0,
                    g1, g2, mixer_inv, rotor_thrust_max, thrust_coeff, dt)
                store_stack_row(integral_new, i, row)
            else:
                c0, c1, c2, c3, n0, n1, n2 = autopilot(
                    load3x3(att, i) if use_att else r, load3x3(r_des, i), yaw_rate[i],
                    thrust_cmd[i], has_ff, ff0, ff1, ff2, g0, g1, g2, integral[i, 0],
                    integral[i, 1], integral[i, 2], consts, mixer_inv, rotor_thrust_max,
                    thrust_coeff, dt)
                integral_new[i, 0], integral_new[i, 1], integral_new[i, 2] = n0, n1, n2
                for col in range(3, integral.shape[1]):  # a wider state, carried unread
                    integral_new[i, col] = integral[i, col]
            y = yaw_rate[i] * dt
            y += yaw_sp[i]
            y += math.pi
            y %= 2 * math.pi
            yaw_sp_new[i] = y - math.pi
        else:
            c0, c1, c2, c3 = omega_cmd[i, 0], omega_cmd[i, 1], omega_cmd[i, 2], omega_cmd[i, 3]
        vx, vy, vz = v[i, 0], v[i, 1], v[i, 2]
        wx, wy, wz = w[i, 0], w[i, 1], w[i, 2]
        o0, o1, o2, o3 = omega[i, 0], omega[i, 1], omega[i, 2], omega[i, 3]
        kc = thrust_coeffs[i]
        # v^T R: the velocity in the body frame
        vb0 = dot3_vecmat(vx, vy, vz, r[0], r[3], r[6])
        vb1 = dot3_vecmat(vx, vy, vz, r[1], r[4], r[7])
        vb2 = dot3_vecmat(vx, vy, vz, r[2], r[5], r[8])
        fb0, fb1, fb2, tq0, tq1, tq2 = rotor_wrench(o0, o1, o2, o3, kc, torque_gain[i], vb0,
                                                    vb1, vb2, wx, wy, wz, torque_map,
                                                    drag_sums, kd, kz)
        if has_ext_torque:
            tq0 += ext_torque[i, 0]
            tq1 += ext_torque[i, 1]
            tq2 += ext_torque[i, 2]
        # translation: R f_b, parasitic drag, external force, gravity
        a0 = dot3_matvec(r[0], r[1], r[2], fb0, fb1, fb2)
        a1 = dot3_matvec(r[3], r[4], r[5], fb0, fb1, fb2)
        a2 = dot3_matvec(r[6], r[7], r[8], fb0, fb1, fb2)
        if c_drag != 0.0:
            speed = vx * vx + vy * vy
            speed += vz * vz
            speed = math.sqrt(speed) * c_drag
            a0 -= vx * speed
            a1 -= vy * speed
            a2 -= vz * speed
        a0 = (a0 + ext_force[i, 0]) / mass_rows[i, 0]
        a1 = (a1 + ext_force[i, 1]) / mass_rows[i, 1]
        a2 = (a2 + ext_force[i, 2]) / mass_rows[i, 2]
        a2 += gravity
        accel[i, 0], accel[i, 1], accel[i, 2] = a0, a1, a2
        # rotation: Euler's equations with diagonal inertia, J dw = tau - w x (J w)
        jx, jy, jz = inertia[i, 0], inertia[i, 1], inertia[i, 2]
        jwx, jwy, jwz = wx * jx, wy * jy, wz * jz
        tq0 -= wy * jwz - wz * jwy
        tq1 -= wz * jwx - wx * jwz
        tq2 -= wx * jwy - wy * jwx
        wn0 = wx + tq0 / jx * dt
        wn1 = wy + tq1 / jy * dt
        wn2 = wz + tq2 / jz * dt
        w_new[i, 0], w_new[i, 1], w_new[i, 2] = wn0, wn1, wn2
        vn0 = a0 * dt + vx
        vn1 = a1 * dt + vy
        vn2 = a2 * dt + vz
        v_new[i, 0], v_new[i, 1], v_new[i, 2] = vn0, vn1, vn2
        p_new[i, 0] = p[i, 0] + (vx + vn0) * half
        p_new[i, 1] = p[i, 1] + (vy + vn1) * half
        p_new[i, 2] = p[i, 2] + (vz + vn2) * half
        store3x3(rot_new, i, mat3_mul(r, exp_so3((wx + wn0) * half, (wy + wn1) * half,
                                                 (wz + wn2) * half)))
        # the motors' first-order lag, and the thrust they give
        al = alpha[i] if per_vehicle_alpha else alpha[0]
        n0 = (c0 - o0) * al + o0
        n1 = (c1 - o1) * al + o1
        n2 = (c2 - o2) * al + o2
        n3 = (c3 - o3) * al + o3
        omega_new[i, 0], omega_new[i, 1], omega_new[i, 2], omega_new[i, 3] = n0, n1, n2, n3
        tn = n0 * n0 * kc + n1 * n1 * kc
        tn += n2 * n2 * kc
        tn += n3 * n3 * kc
        thrust_new[i] = tn


@any_layout("p_new", "v_new", "rot_new", "w_new", "omega_new", "thrust_new", "accel",
            "integral_new", "yaw_sp_new")
@njit
def step_vehicles(p: np.ndarray, v: np.ndarray, rot: np.ndarray, w: np.ndarray,
                  omega: np.ndarray, thrust_coeffs: np.ndarray, torque_gain: np.ndarray,
                  mass_rows: np.ndarray, inertia: np.ndarray, alpha: np.ndarray,
                  autopilot_on: bool, omega_cmd: np.ndarray, att: np.ndarray, use_att: bool,
                  r_des: np.ndarray, yaw_rate: np.ndarray, thrust_cmd: np.ndarray,
                  torque_ff: np.ndarray, has_ff: bool, gyro: np.ndarray, gyro_noise: np.ndarray,
                  noisy: bool, integral: np.ndarray, yaw_sp: np.ndarray, consts_a: np.ndarray,
                  stack_on: bool, stack_c: np.ndarray,
                  mixer_a: np.ndarray, rotor_thrust_max: float, thrust_coeff: float,
                  ext_force: np.ndarray, ext_torque: np.ndarray, has_ext_torque: bool,
                  torque_map_a: np.ndarray, drag_sums_a: np.ndarray, kd: float, kz: float,
                  c_drag: float,
                  gravity: float, dt: float, p_new: np.ndarray, v_new: np.ndarray,
                  rot_new: np.ndarray, w_new: np.ndarray, omega_new: np.ndarray,
                  thrust_new: np.ndarray, accel: np.ndarray, integral_new: np.ndarray,
                  yaw_sp_new: np.ndarray) -> None:
    """:func:`step_vehicles_body` for a call from Python: any array layout (sealed to one general
    signature, :func:`aerodock.jit.any_layout`); compiled callers call the body itself, which no
    seal stops from compiling for their types."""
    step_vehicles_body(p, v, rot, w, omega, thrust_coeffs, torque_gain, mass_rows, inertia, alpha,
                       autopilot_on, omega_cmd, att, use_att, r_des, yaw_rate, thrust_cmd,
                       torque_ff, has_ff, gyro, gyro_noise, noisy, integral, yaw_sp, consts_a,
                       stack_on, stack_c, mixer_a, rotor_thrust_max, thrust_coeff, ext_force,
                       ext_torque, has_ext_torque, torque_map_a, drag_sums_a, kd, kz, c_drag,
                       gravity, dt, p_new, v_new, rot_new, w_new, omega_new, thrust_new, accel,
                       integral_new, yaw_sp_new)


@njit
def autopilot_batch(att: np.ndarray, r_des: np.ndarray, yaw_rate: np.ndarray,
                    thrust_cmd: np.ndarray, torque_ff: np.ndarray, has_ff: bool,
                    gyro: np.ndarray, gyro_noise: np.ndarray, noisy: bool,
                    integral: np.ndarray, consts_a: np.ndarray, stack_on: bool,
                    stack_c: np.ndarray, mixer_a: np.ndarray,
                    rotor_thrust_max: float, thrust_coeff: float, dt: float,
                    cmd: np.ndarray, integral_new: np.ndarray) -> None:
    """:func:`autopilot` for ``n`` vehicles: rotor speed commands ``cmd`` (n, 4) and new
    integrals (n, 3). The gyro reads ``gyro`` (plus ``gyro_noise`` when ``noisy``)."""
    consts, mixer_inv = tuple18(consts_a), tuple16(mixer_a)
    stack = constants_tuple(stack_on, stack_c)
    for i in range(att.shape[0]):
        g0, g1, g2 = gyro[i, 0], gyro[i, 1], gyro[i, 2]
        if noisy:
            g0 += gyro_noise[i, 0]
            g1 += gyro_noise[i, 1]
            g2 += gyro_noise[i, 2]
        ff0 = ff1 = ff2 = 0.0
        if has_ff:
            ff0, ff1, ff2 = torque_ff[i, 0], torque_ff[i, 1], torque_ff[i, 2]
        if stack_on:
            c0, c1, c2, c3, row = stack_autopilot(
                stack_row(integral, i), stack, load3x3(att, i), load3x3(r_des, i), yaw_rate[i],
                thrust_cmd[i], has_ff, ff0, ff1, ff2, g0, g1, g2, mixer_inv, rotor_thrust_max,
                thrust_coeff, dt)
            store_stack_row(integral_new, i, row)
            cmd[i, 0], cmd[i, 1], cmd[i, 2], cmd[i, 3] = c0, c1, c2, c3
            continue
        out = autopilot(load3x3(att, i), load3x3(r_des, i), yaw_rate[i], thrust_cmd[i], has_ff,
                        ff0, ff1, ff2, g0, g1, g2, integral[i, 0], integral[i, 1], integral[i, 2],
                        consts, mixer_inv, rotor_thrust_max, thrust_coeff, dt)
        cmd[i, 0], cmd[i, 1], cmd[i, 2], cmd[i, 3] = out[0], out[1], out[2], out[3]
        integral_new[i, 0], integral_new[i, 1], integral_new[i, 2] = out[4], out[5], out[6]
        for col in range(3, integral.shape[1]):  # a wider state, carried unread
            integral_new[i, col] = integral[i, col]


@njit
def mix_batch(thrust: np.ndarray, torque: np.ndarray, mixer_a: np.ndarray,
              rotor_thrust_max: float, out: np.ndarray) -> None:
    """:func:`mix` for ``n`` vehicles: collective (n,), torques (n, 3) -> (n, 4)."""
    mixer_inv = tuple16(mixer_a)
    for i in range(thrust.shape[0]):
        f = mix(thrust[i], torque[i, 0], torque[i, 1], torque[i, 2], mixer_inv,
                rotor_thrust_max)
        out[i, 0], out[i, 1], out[i, 2], out[i, 3] = f[0], f[1], f[2], f[3]


@njit
def wrench_batch(omega: np.ndarray, thrust_coeffs: np.ndarray, torque_gain: np.ndarray,
                 v_body: np.ndarray, w: np.ndarray, torque_map_a: np.ndarray,
                 drag_sums_a: np.ndarray, kd: float, kz: float, force: np.ndarray,
                 torque: np.ndarray) -> None:
    """:func:`rotor_wrench` for ``n`` vehicles (body-frame velocities ``v_body``)."""
    torque_map, drag_sums = tuple12(torque_map_a), tuple28(drag_sums_a)
    for i in range(omega.shape[0]):
        out = rotor_wrench(omega[i, 0], omega[i, 1], omega[i, 2], omega[i, 3],
                           thrust_coeffs[i], torque_gain[i], v_body[i, 0], v_body[i, 1],
                           v_body[i, 2], w[i, 0], w[i, 1], w[i, 2], torque_map, drag_sums, kd,
                           kz)
        force[i, 0], force[i, 1], force[i, 2] = out[0], out[1], out[2]
        torque[i, 0], torque[i, 1], torque[i, 2] = out[3], out[4], out[5]


@njit
def rotate_batch(rot: np.ndarray, phi: np.ndarray, out: np.ndarray) -> None:
    """``out[i] = rot[i] exp([phi[:, i]]x)`` for component-major rotation vectors (3, n)."""
    for i in range(rot.shape[0]):
        store3x3(out, i, mat3_mul(load3x3(rot, i), exp_so3(phi[0, i], phi[1, i], phi[2, i])))


@njit
def hold_rows(start: int, stop: int, p: np.ndarray, v: np.ndarray, rot: np.ndarray,
              w: np.ndarray, omega: np.ndarray, integral: np.ndarray, thrust: np.ndarray,
              p_new: np.ndarray, v_new: np.ndarray, rot_new: np.ndarray, w_new: np.ndarray,
              omega_new: np.ndarray, integral_new: np.ndarray, thrust_new: np.ndarray) -> None:
    """Rows ``start..stop-1`` of the new state (``*_new``) held as in the old one (a leader on
    a rigid stand): position, velocity, attitude, rates, rotor speeds, the autopilot's state and
    the thrust, copied."""
    for i in range(start, stop):
        for c in range(3):
            p_new[i, c] = p[i, c]
            v_new[i, c] = v[i, c]
            w_new[i, c] = w[i, c]
            for d in range(3):
                rot_new[i, c, d] = rot[i, c, d]
        for j in range(omega.shape[1]):
            omega_new[i, j] = omega[i, j]
        for j in range(integral.shape[1]):
            integral_new[i, j] = integral[i, j]
        thrust_new[i] = thrust[i]

