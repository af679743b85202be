"""The rigid-body vehicles' physics step, compiled: autopilot, mixer, rotor wrench with drag,
Euler's equations, attitude and motors, one vehicle at a time in one loop.

This is the one implementation of these terms; :mod:`aerodock.world.vehicles.rigid_body` and
:mod:`aerodock.world.vehicles.autopilot` bind the parameters and call it. Each vehicle's numbers
are computed operation by operation in the order the NumPy step computed them (the order is
part of the numbers, and the batch's numbers equal its single trials'), and the 3 x 3 products
in OpenBLAS's order (:func:`aerodock.jit.fma`):

- a row vector times a matrix (``v^T R``) and a matrix times a matrix:
  ``fma(a2, b2, fma(a1, b1, a0 b0))``;
- a matrix times a column vector (``R f``): ``fma(a2, b2, fma(a0, b0, a1 b1))``.

Maxima and minima follow NumPy's (``np.maximum`` keeps its first argument when it is NaN or
when the two are equal), so a NaN propagates as it did.
"""

from __future__ import annotations

import math

import numpy as np

from aerodock.jit import fma, njit


@njit
def _max(a: float, b: float) -> float:
    """``np.maximum(a, b)``: NaN propagates, ties keep ``a``."""
    return a if (a >= b or a != a) else b


@njit
def _min(a: float, b: float) -> float:
    """``np.minimum(a, b)``: NaN propagates, ties keep ``a``."""
    return a if (a <= b or a != a) else b


@njit
def _vecmat(v0: float, v1: float, v2: float, m: np.ndarray, k: int) -> float:
    """Column ``k`` of ``v^T m`` (3 x 3 ``m``), rounded as OpenBLAS's ``v @ m``."""
    return fma(v2, m[2, k], fma(v1, m[1, k], v0 * m[0, k]))


@njit
def _matvec(m: np.ndarray, r: int, f0: float, f1: float, f2: float) -> float:
    """Row ``r`` of ``m f`` (3 x 3 ``m``), rounded as OpenBLAS's ``m @ f``."""
    return fma(m[r, 2], f2, fma(m[r, 0], f0, m[r, 1] * f1))


@njit
def rotate_into(rot: np.ndarray, phi0: float, phi1: float, phi2: float,
                out: np.ndarray) -> None:
    """``out = rot exp([phi]x)`` for one 3 x 3 ``rot`` and a body rotation vector (Rodrigues;
    below theta^2 = 1e-12 the series of sin(t)/t and (1 - cos t)/t^2)."""
    theta2 = phi0 * phi0 + phi1 * phi1
    theta2 += phi2 * phi2
    theta = math.sqrt(theta2)
    if theta2 < 1e-12:
        a = 1.0 - theta2 / 6.0
        b = 0.5 - theta2 / 24.0
    else:
        a = math.sin(theta) / theta
        b = (1.0 - math.cos(theta)) / (theta * theta)
    bp0, bp1, bp2 = phi0 * b, phi1 * b, phi2 * b
    ap0, ap1, ap2 = phi0 * a, phi1 * a, phi2 * a
    diag = 1.0 - b * theta2
    # exp = I + a K + b K^2 = b p p^T + (1 - b theta^2) I + a [p]x
    e00 = bp0 * phi0 + diag
    e01 = bp0 * phi1 + (-ap2)
    e02 = bp0 * phi2 + ap1
    e10 = bp1 * phi0 + ap2
    e11 = bp1 * phi1 + diag
    e12 = bp1 * phi2 + (-ap0)
    e20 = bp2 * phi0 + (-ap1)
    e21 = bp2 * phi1 + ap0
    e22 = bp2 * phi2 + diag
    for r in range(3):
        r0, r1, r2 = rot[r, 0], rot[r, 1], rot[r, 2]
        out[r, 0] = fma(r2, e20, fma(r1, e10, r0 * e00))
        out[r, 1] = fma(r2, e21, fma(r1, e11, r0 * e01))
        out[r, 2] = fma(r2, e22, fma(r1, e12, r0 * e02))


@njit
def autopilot_into(att: np.ndarray, rd: np.ndarray, yaw_rate: float, thrust_cmd: float,
                   ff: np.ndarray, has_ff: bool, g0: float, g1: float, g2: float,
                   integral: np.ndarray, consts: np.ndarray, mixer_inv: np.ndarray,
                   rotor_thrust_max: float, thrust_coeff: float, dt: float,
                   cmd: np.ndarray, integral_new: np.ndarray) -> None:
    """One vehicle's autopilot: attitude P (geometric error ``vee(R_d^T R - R^T R_d) / 2``
    times the angle gain, plus the yaw rate feed-forward), rate PI on the gyro ``g`` (with
    anti-windup), times the nominal inertia, plus the torque feed-forward; the airmode mixer
    (the collective shifted so the torques keep priority, each rotor clipped); rotor speed
    commands ``cmd`` (4,) through the nominal k_T, and the new rate integral (3,).

    ``consts`` (6, 3): rows -attitude_p / 2, the rate limit, the integral limit, rate_p,
    rate_i, the nominal inertia.
    """
    m21 = fma(rd[2, 2], att[2, 1], fma(rd[1, 2], att[1, 1], rd[0, 2] * att[0, 1]))
    m12 = fma(rd[2, 1], att[2, 2], fma(rd[1, 1], att[1, 2], rd[0, 1] * att[0, 2]))
    m02 = fma(rd[2, 0], att[2, 2], fma(rd[1, 0], att[1, 2], rd[0, 0] * att[0, 2]))
    m20 = fma(rd[2, 2], att[2, 0], fma(rd[1, 2], att[1, 0], rd[0, 2] * att[0, 0]))
    m10 = fma(rd[2, 1], att[2, 0], fma(rd[1, 1], att[1, 0], rd[0, 1] * att[0, 0]))
    m01 = fma(rd[2, 0], att[2, 1], fma(rd[1, 0], att[1, 1], rd[0, 0] * att[0, 1]))
    sp0 = (m21 - m12) * consts[0, 0]
    sp1 = (m02 - m20) * consts[0, 1]
    sp2 = (m10 - m01) * consts[0, 2]
    sp2 += yaw_rate
    tau0 = _rate_loop(sp0, g0, 0, integral, consts, dt, integral_new)
    tau1 = _rate_loop(sp1, g1, 1, integral, consts, dt, integral_new)
    tau2 = _rate_loop(sp2, g2, 2, integral, consts, dt, integral_new)
    if has_ff:
        tau0 += ff[0]
        tau1 += ff[1]
        tau2 += ff[2]
    mix_into(thrust_cmd, tau0, tau1, tau2, mixer_inv, rotor_thrust_max, cmd)
    for j in range(4):
        cmd[j] = math.sqrt(cmd[j] / thrust_coeff)


@njit
def mix_into(thrust: float, tau0: float, tau1: float, tau2: float, mixer_inv: np.ndarray,
             rotor_thrust_max: float, out: np.ndarray) -> None:
    """The airmode mixer: rotor thrusts ``out`` (k,) from ``[T, tau_x, tau_y, tau_z]`` through
    ``mixer_inv`` (4, k); the collective shifted (down when a rotor exceeds its maximum, up
    when one would go below zero) so the torque differences survive, then every rotor clipped
    to ``[0, rotor_thrust_max]``."""
    k = mixer_inv.shape[1]
    lo = math.inf
    hi = -math.inf
    for j in range(k):
        fj = mixer_inv[0, j] * thrust + mixer_inv[1, j] * tau0
        fj += mixer_inv[2, j] * tau1
        fj += mixer_inv[3, j] * tau2
        out[j] = fj
        lo = fj if j == 0 else _min(lo, fj)
        hi = fj if j == 0 else _max(hi, fj)
    lo = -lo
    hi = rotor_thrust_max - hi
    shift = _min(_max(lo, 0.0), hi)
    if lo > hi:
        shift = (lo + hi) * 0.5
    for j in range(k):
        out[j] = _min(_max(out[j] + shift, 0.0), rotor_thrust_max)


@njit
def mix_batch(thrust: np.ndarray, torque: np.ndarray, mixer_inv: np.ndarray,
              rotor_thrust_max: float, out: np.ndarray) -> None:
    """:func:`mix_into` for ``n`` vehicles: collective (n,), torques (n, 3) -> (n, k)."""
    for i in range(thrust.shape[0]):
        mix_into(thrust[i], torque[i, 0], torque[i, 1], torque[i, 2], mixer_inv,
                 rotor_thrust_max, out[i])


@njit
def _rate_loop(sp: float, gyro: float, k: int, integral: np.ndarray, consts: np.ndarray,
               dt: float, integral_new: np.ndarray) -> float:
    """Axis ``k`` of the rate loop: the setpoint clipped to the rate limit, PI on the gyro with
    the integral clipped (anti-windup), times the nominal inertia; the torque, N m."""
    sp = _min(_max(sp, -consts[1, k]), consts[1, k])
    err = sp - gyro
    acc = err * dt
    acc += integral[k]
    acc = _min(_max(acc, -consts[2, k]), consts[2, k])
    integral_new[k] = acc
    t = err * consts[3, k]
    t += acc * consts[4, k]
    return t * consts[5, k]


@njit
def rotor_wrench(omega: np.ndarray, kc: float, torque_gain: float, vb0: float, vb1: float,
                 vb2: float, wx: float, wy: float, wz: float, torque_map: np.ndarray,
                 drag_sums: np.ndarray, kd: float, kz: float,
                 sums: np.ndarray) -> tuple[float, float, float, float, float, float]:
    """One vehicle's rotor force and torque, body FRD: thrust and yaw reaction of each rotor
    (k_T ``kc``), and rotor drag at each hub (RotorPy's H-force and induced-inflow terms on
    the local airspeed ``v_b + w x r_i``, through the weighted sums of ``drag_sums``).
    ``sums`` (7,) is scratch. Returns (force x, y, z, torque x, y, z)."""
    f0 = omega[0] * omega[0] * kc
    f1 = omega[1] * omega[1] * kc
    f2 = omega[2] * omega[2] * kc
    f3 = omega[3] * omega[3] * kc
    tq0 = torque_map[0, 0] * f0 + torque_map[1, 0] * f1
    tq0 += torque_map[2, 0] * f2
    tq0 += torque_map[3, 0] * f3
    tq1 = torque_map[0, 1] * f0 + torque_map[1, 1] * f1
    tq1 += torque_map[2, 1] * f2
    tq1 += torque_map[3, 1] * f3
    tq2 = torque_map[0, 2] * f0 + torque_map[1, 2] * f1
    tq2 += torque_map[2, 2] * f2
    tq2 += torque_map[3, 2] * f3
    tq2 *= torque_gain
    thrust = f0 + f1
    thrust += f2
    thrust += f3
    fb0 = 0.0
    fb1 = 0.0
    fb2 = -thrust
    if kd != 0.0 or kz != 0.0:
        for c in range(7):
            s = drag_sums[0, c] * omega[0] + drag_sums[1, c] * omega[1]
            s += drag_sums[2, c] * omega[2]
            s += drag_sums[3, c] * omega[3]
            sums[c] = s
        # sums: (1, -y, x, y, xx, yy, xy) weighted by the rotor speeds
        ax0 = sums[0] * vb2
        ax0 += wx * sums[3]
        ax0 -= wy * sums[2]
        ax0 *= kz
        ax1 = sums[3] * vb2
        ax1 += wx * sums[5]
        ax1 -= wy * sums[6]
        ax1 *= kz
        ax2 = sums[2] * vb2
        ax2 += wx * sums[6]
        ax2 -= wy * sums[4]
        ax2 *= kz
        fb2 -= ax0
        tq0 -= ax1
        tq1 += ax2
        pl0 = sums[0] * vb0
        pl0 += wz * sums[1]
        pl0 *= kd
        pl1 = sums[0] * vb1
        pl1 += wz * sums[2]
        pl1 *= kd
        fb0 = 0.0 - pl0
        fb1 = 0.0 - pl1
        yaw = sums[2] * vb1
        yaw -= sums[3] * vb0
        spin = sums[4] + sums[5]
        spin *= wz
        yaw += spin
        yaw *= kd
        tq2 -= yaw
    return fb0, fb1, fb2, tq0, tq1, tq2


@njit
def step_vehicles(p: np.ndarray, v: np.ndarray, rot: np.ndarray, w: np.ndarray,
                  omega: np.ndarray, thrust_coeffs: np.ndarray, torque_gain: np.ndarray,
                  mass_rows: np.ndarray, inertia: np.ndarray, alpha: np.ndarray,
                  omega_cmd: np.ndarray, ext_force: np.ndarray, ext_torque: np.ndarray,
                  has_ext_torque: bool, torque_map: np.ndarray, drag_sums: np.ndarray,
                  kd: float, kz: float, c_drag: float, gravity: float, dt: float,
                  p_new: np.ndarray, v_new: np.ndarray, rot_new: np.ndarray, w_new: np.ndarray,
                  omega_new: np.ndarray, thrust_new: np.ndarray, accel: np.ndarray) -> None:
    """One physics step of ``n`` rigid bodies under rotor speed commands ``omega_cmd``
    (n, 4), external forces (n, 3, world NED) and torques (n, 3, body FRD), written into the
    ``*_new`` arrays and ``accel`` (the step's acceleration, NED).

    Velocity and body rates by explicit Euler on the current derivatives; position and
    attitude on the mean of old and new rates (the attitude by the exact Rodrigues
    exponential); the motors by their exact first-order step (``alpha``: ``1 - exp(-dt/tau)``,
    (n,) or one number in a (1,) array).
    """
    sums = np.empty(7)
    per_vehicle_alpha = alpha.shape[0] > 1
    half = 0.5 * dt
    for i in range(p.shape[0]):
        r = rot[i]
        vx, vy, vz = v[i, 0], v[i, 1], v[i, 2]
        wx, wy, wz = w[i, 0], w[i, 1], w[i, 2]
        kc = thrust_coeffs[i]
        fb0, fb1, fb2, tq0, tq1, tq2 = rotor_wrench(
            omega[i], kc, torque_gain[i], _vecmat(vx, vy, vz, r, 0), _vecmat(vx, vy, vz, r, 1),
            _vecmat(vx, vy, vz, r, 2), wx, wy, wz, torque_map, drag_sums, kd, kz, sums)
        if has_ext_torque:
            tq0 += ext_torque[i, 0]
            tq1 += ext_torque[i, 1]
            tq2 += ext_torque[i, 2]
        # translation
        a0 = _matvec(r, 0, fb0, fb1, fb2)
        a1 = _matvec(r, 1, fb0, fb1, fb2)
        a2 = _matvec(r, 2, fb0, fb1, fb2)
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
        accel[i, 0] = a0
        accel[i, 1] = a1
        accel[i, 2] = a2
        # rotation: Euler's equations with diagonal inertia, J dw = tau - w x (J w)
        jx, jy, jz = inertia[i, 0], inertia[i, 1], inertia[i, 2]
        jwx, jwy, jwz = wx * jx, wy * jy, wz * jz
        tq0 -= wy * jwz - wz * jwy
        tq1 -= wz * jwx - wx * jwz
        tq2 -= wx * jwy - wy * jwx
        wn0 = wx + tq0 / jx * dt
        wn1 = wy + tq1 / jy * dt
        wn2 = wz + tq2 / jz * dt
        w_new[i, 0] = wn0
        w_new[i, 1] = wn1
        w_new[i, 2] = wn2
        for k in range(3):
            vk = v[i, k]
            vn = accel[i, k] * dt + vk
            v_new[i, k] = vn
            p_new[i, k] = p[i, k] + (vk + vn) * half
        rotate_into(r, (wx + wn0) * half, (wy + wn1) * half, (wz + wn2) * half, rot_new[i])
        # the motors' first-order lag, and the thrust they give
        al = alpha[i] if per_vehicle_alpha else alpha[0]
        thrust = 0.0
        for j in range(4):
            o = (omega_cmd[i, j] - omega[i, j]) * al + omega[i, j]
            omega_new[i, j] = o
            fj = o * o * kc
            thrust = fj if j == 0 else thrust + fj
        thrust_new[i] = thrust


@njit
def autopilot_batch(att: np.ndarray, r_des: np.ndarray, yaw_rate: np.ndarray,
                    thrust_cmd: np.ndarray, torque_ff: np.ndarray, has_ff: bool,
                    gyro: np.ndarray, gyro_noise: np.ndarray, noisy: bool,
                    integral: np.ndarray, consts: np.ndarray, mixer_inv: np.ndarray,
                    rotor_thrust_max: float, thrust_coeff: float, dt: float,
                    cmd: np.ndarray, integral_new: np.ndarray) -> None:
    """:func:`autopilot_into` for ``n`` vehicles: rotor speed commands ``cmd`` (n, 4) and new
    integrals (n, 3). The gyro reads ``gyro`` (plus ``gyro_noise`` when ``noisy``)."""
    for i in range(att.shape[0]):
        if noisy:
            g0 = gyro[i, 0] + gyro_noise[i, 0]
            g1 = gyro[i, 1] + gyro_noise[i, 1]
            g2 = gyro[i, 2] + gyro_noise[i, 2]
        else:
            g0, g1, g2 = gyro[i, 0], gyro[i, 1], gyro[i, 2]
        autopilot_into(att[i], r_des[i], yaw_rate[i], thrust_cmd[i], torque_ff[i], has_ff,
                       g0, g1, g2, integral[i], consts, mixer_inv, rotor_thrust_max,
                       thrust_coeff, dt, cmd[i], integral_new[i])


@njit
def wrench_batch(omega: np.ndarray, thrust_coeffs: np.ndarray, torque_gain: np.ndarray,
                 v_body: np.ndarray, w: np.ndarray, torque_map: np.ndarray,
                 drag_sums: np.ndarray, kd: float, kz: float, force: np.ndarray,
                 torque: np.ndarray) -> None:
    """:func:`rotor_wrench` for ``n`` vehicles (body-frame velocities ``v_body``)."""
    sums = np.empty(7)
    for i in range(omega.shape[0]):
        out = rotor_wrench(omega[i], thrust_coeffs[i], torque_gain[i], v_body[i, 0],
                           v_body[i, 1], v_body[i, 2], w[i, 0], w[i, 1], w[i, 2], torque_map,
                           drag_sums, kd, kz, sums)
        force[i, 0], force[i, 1], force[i, 2] = out[0], out[1], out[2]
        torque[i, 0], torque[i, 1], torque[i, 2] = out[3], out[4], out[5]


@njit
def rotate_batch(rot: np.ndarray, phi: np.ndarray, out: np.ndarray) -> None:
    """``out[i] = rot[i] exp([phi[:, i]]x)`` for component-major rotation vectors (3, n)."""
    for i in range(rot.shape[0]):
        rotate_into(rot[i], phi[0, i], phi[1, i], phi[2, i], out[i])
