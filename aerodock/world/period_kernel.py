"""The compiled control period's kernel: :data:`aerodock.world.step.WORLD_STEP`'s terms, in their
order, step after step, in one numba call (:func:`period_kernel`), with the constants it reads
(:func:`float_constants`) and NumPy's cos and sin loops it calls. :mod:`aerodock.world.period`
decides when it runs, hands it the world's arrays and puts back the state it leaves.
"""

from __future__ import annotations

import numpy as np

from aerodock.downwash.jet_kernel import wake_step
from aerodock.jit import _unary, any_layout, njit
from aerodock.world.gripper import contact_kernel_body, contact_push
from aerodock.world.imu import imu_step
from aerodock.world.params import WorldParams
from aerodock.world.platform import cable_wrench_kernel, hanging_bar_kernel_body
from aerodock.world.sensor_kernels import (
    CHANGED_DONE,
    CHANGED_SERVO,
    CHANGED_START,
    gripper_step_kernel_body,
)
from aerodock.world.term_kernels import (
    carry_captured,
    ground_kernel,
    hang_captured,
    rotor_fault_wrench,
)
from aerodock.world.trig_loops import TRIG_COS, TRIG_SIN
from aerodock.world.vehicles.rigid_body import (
    flown_step_body,
)
from aerodock.world.vehicles.rigid_kernel import hold_rows

# -- the kernel's float constants (one array, built once per world) -------------------------
(F_DT, F_ANCHOR_BELOW, F_CABLE_LENGTH, F_SWING_DAMPING, F_PLATFORM_GRAVITY, F_YAW_OMEGA2,
 F_YAW_DAMPING, F_GYRO_SD, F_GYRO_RANGE, F_GRAVITY, F_ACCEL_NOISE_SQ, F_VIBRATION,
 F_ACCEL_RANGE, F_K_P, F_K_YAW, F_SENSOR_RATE, F_SENSOR_NOISE, F_THRESHOLD, F_LATENCY,
 F_MOUNT, F_BAR_RADIUS, F_APERTURE, F_BAR_HALF_LENGTH, F_GATE_HEIGHT, F_STIFFNESS,
 F_DAMPING, F_BAR_MASS, F_HANG_OFFSET, F_THRUST_COEFF) = range(29)
F_SIZE = 29
# the kernel's integers in and out: the clock, the draws' cursor, the IMU chain's heads
I_STEP, I_DRAW, I_GYRO_HEAD, I_ACCEL_HEAD, I_RING_HEAD = range(5)
# why the kernel stopped (its second result)
STOP_DONE, STOP_DRAWS, STOP_GRIPPER, STOP_UNCOVERED = range(4)


def float_constants(params: WorldParams) -> np.ndarray:
    """The constants the kernel reads, in ``F_*`` order (the values the terms pass)."""
    pf, gp, imu, vehicle = params.platform, params.gripper, params.imu, params.vehicle
    values = np.empty(F_SIZE)
    values[F_DT] = params.dt_s
    values[F_ANCHOR_BELOW] = pf.anchor_below_leader_m
    values[F_CABLE_LENGTH] = pf.cable_length_m
    values[F_SWING_DAMPING] = pf.swing_damping
    values[F_PLATFORM_GRAVITY] = pf.gravity_mps2
    values[F_YAW_OMEGA2] = pf.yaw_omega2
    values[F_YAW_DAMPING] = pf.yaw_damping
    values[F_GYRO_SD] = imu.gyro_noise_radps if params.rigid else 0.0
    values[F_GYRO_RANGE] = imu.chain.gyro_range_radps
    values[F_GRAVITY] = vehicle.gravity_mps2
    values[F_ACCEL_NOISE_SQ] = vehicle.accel_noise_mps2 ** 2
    values[F_VIBRATION] = imu.accel_vibration_mps2
    values[F_ACCEL_RANGE] = imu.chain.accel_range_mps2
    values[F_K_P] = imu.estimator.accel_gain_radps
    values[F_K_YAW] = imu.estimator.heading_gain_radps
    values[F_SENSOR_RATE] = gp.sensor_rate_hz
    values[F_SENSOR_NOISE] = float(gp.sensor_noise_n)
    values[F_THRESHOLD] = float(gp.contact_threshold_n)
    values[F_LATENCY] = float(gp.latency_s)
    values[F_MOUNT] = gp.mount_height_m
    values[F_BAR_RADIUS] = gp.bar_radius_m
    values[F_APERTURE] = gp.aperture_m
    values[F_BAR_HALF_LENGTH] = gp.bar_half_length_m
    values[F_GATE_HEIGHT] = gp.gate_height_m
    values[F_STIFFNESS] = gp.contact_stiffness_npm
    values[F_DAMPING] = gp.contact_damping_nspm
    values[F_BAR_MASS] = pf.bar_mass_kg
    values[F_HANG_OFFSET] = gp.mount_height_m + gp.bar_radius_m
    fleet = params.follower_fleet.params
    values[F_THRUST_COEFF] = fleet.thrust_coeff if params.rigid else 0.0
    values.flags.writeable = False
    return values


@any_layout("iv", "processes", "bar_noise", "gz1", "gz2", "gline", "az1", "az2", "aline",
            "ring", "nav_accel", "att_ring", "contact_seen", "contact_sensed", "ground_contact",
            "P", "V", "RM",
            "W", "OM", "TH", "ACC", "INT", "YSP", "BP", "BV", "BY", "BR", "CAB", "GT", "AT",
            "ATT", "WT", "downwash", "go_reading", "go_by_contact", "go_servo", "go_gate",
            "go_inside_start", "go_slipped", "go_resolved", contiguous=("packed",))
@njit
def period_kernel(loops: np.ndarray, trig: np.ndarray, steps: int, fc: np.ndarray,
                  iv: np.ndarray, substeps: int, latency: int, has_ff: bool, g_idle: bool,
                  g_passive_any: bool, g_passive: np.ndarray, g_active_any: bool,
                  g_active: np.ndarray, close: np.ndarray, active_close: bool,
                  draws: np.ndarray, packed: np.ndarray, p0: np.ndarray, v0: np.ndarray,
                  rot0: np.ndarray, w0: np.ndarray, omega0: np.ndarray,
                  integral0: np.ndarray, yaw_sp0: np.ndarray, thrust0: np.ndarray,
                  r_des: np.ndarray, yaw_rate: np.ndarray, thrust_cmd: np.ndarray,
                  torque_ff: np.ndarray, fol_mass: np.ndarray, fol_mass_rows: np.ndarray,
                  gravity: np.ndarray, hover: np.ndarray, captured: np.ndarray,
                  any_captured: bool, thrust_gain: np.ndarray, rotor_loss: np.ndarray,
                  torque_map: np.ndarray, leader_fixed: bool,
                  jp: np.ndarray, cols: np.ndarray, offsets: np.ndarray, coeff: np.ndarray,
                  processes: np.ndarray, bar_noise: np.ndarray, bar_consts: np.ndarray,
                  bar_p0: np.ndarray, bar_v0: np.ndarray, bar_yaw0: np.ndarray,
                  bar_rate0: np.ndarray, bar_mass: np.ndarray, cable0: np.ndarray,
                  gyro_c: np.ndarray, gz1: np.ndarray, gz2: np.ndarray, gline: np.ndarray,
                  accel_c: np.ndarray, az1: np.ndarray, az2: np.ndarray, aline: np.ndarray,
                  bias: np.ndarray, ring: np.ndarray, nav_accel: np.ndarray,
                  lead_accel0: np.ndarray, fol_accel0: np.ndarray, rot_hat0: np.ndarray,
                  att_ring: np.ndarray, g_gate: np.ndarray, g_bias_true: np.ndarray,
                  g_bias_est: np.ndarray, g_reading: np.ndarray, g_servo: np.ndarray,
                  g_by_contact: np.ndarray, g_inside_start: np.ndarray,
                  g_slipped: np.ndarray, g_resolved: np.ndarray, g_close_time: np.ndarray,
                  g_stuck: np.ndarray, contact_seen: np.ndarray, contact_sensed: np.ndarray,
                  ground_contact: np.ndarray, P: np.ndarray, V: np.ndarray,  # noqa: N803
                  RM: np.ndarray, W: np.ndarray, OM: np.ndarray, TH: np.ndarray,  # noqa: N803
                  ACC: np.ndarray, INT: np.ndarray, YSP: np.ndarray,  # noqa: N803
                  BP: np.ndarray, BV: np.ndarray, BY: np.ndarray, BR: np.ndarray,  # noqa: N803
                  CAB: np.ndarray, GT: np.ndarray, AT: np.ndarray,  # noqa: N803
                  ATT: np.ndarray, WT: np.ndarray, downwash: np.ndarray,  # noqa: N803
                  go_reading: np.ndarray,
                  go_by_contact: np.ndarray, go_servo: np.ndarray, go_gate: np.ndarray,
                  go_inside_start: np.ndarray, go_slipped: np.ndarray,
                  go_resolved: np.ndarray) -> tuple[int, int, int]:
    """Up to ``steps`` physics steps of :data:`aerodock.world.step.WORLD_STEP`, each term in
    its order calling the compiled function its per-step form calls (:mod:`aerodock.world.
    terms`). Step ``s`` reads the state the step before left (the ``*0`` inputs for the first)
    and writes its own into row ``s`` of the outputs (``P`` ... ``ATT``: the vehicles, the bar,
    the cables, the IMU chain's outputs and the attitude estimates); the IMU chain's memory,
    the jet's turbulence (``processes``, ``bar_noise``), ``contact_sensed``, ``ground_contact``,
    the motion capture's attitude ring ``att_ring`` (latency + 1, 2n, 3, 3) and ``iv``
    (``I_*``) advance in place; the grippers' changed arrays end in ``go_*``.

    Returns (steps done, why it stopped (``STOP_*``), the ``CHANGED_*`` bits of the grippers'
    steps, OR-ed)."""
    m = p0.shape[0]
    n = m // 2
    k = offsets.shape[0]
    dt = fc[F_DT]
    gyro_sd = fc[F_GYRO_SD]
    rate = fc[F_SENSOR_RATE]
    slots = latency + 1
    n_draws = draws.shape[0]
    bar_axis = np.zeros((3, n))
    contact = np.empty(n)
    inside = np.empty(n, dtype=np.bool_)
    up = np.empty((n, 3))
    force = np.empty((m, 3))
    torque_t = np.empty((3, m))
    bar_force = np.empty((n, 3))
    hang_mass = np.empty(n)
    wake = np.empty((4, n, 3))
    noise = np.empty((3, m)) if gyro_sd != 0.0 else np.zeros((3, 0))
    no_rows = np.zeros((0, 3))
    no_yaw = np.zeros(0)
    no_noise = np.zeros(0)
    changed_all = 0
    g_ran = False
    for s in range(steps):
        step = iv[I_STEP]
        pos = iv[I_DRAW]
        t_end = (step + 1) * dt
        sample = int(t_end * rate + 1e-9) != int((t_end - dt) * rate + 1e-9)
        gripper_runs = not (g_idle and not sample and not active_close)
        need = 3 + k + 3 + 6 + (6 if gyro_sd != 0.0 else 0) + (1 if sample else 0)
        if pos + need > n_draws:
            return s, STOP_DRAWS, changed_all
        if s == 0:
            p, v, rot, w, omega = p0, v0, rot0, w0, omega0
            integral, yaw_sp, thrust = integral0, yaw_sp0, thrust0
            bar_p, bar_v, bar_yaw, bar_rate, cable = bar_p0, bar_v0, bar_yaw0, bar_rate0, cable0
            lead_accel, fol_accel, rot_hat = lead_accel0, fol_accel0, rot_hat0
        else:
            p, v, rot, w, omega = P[s - 1], V[s - 1], RM[s - 1], W[s - 1], OM[s - 1]
            integral, yaw_sp, thrust = INT[s - 1], YSP[s - 1], TH[s - 1]
            bar_p, bar_v, bar_yaw, bar_rate, cable = (BP[s - 1], BV[s - 1], BY[s - 1],
                                                      BR[s - 1], CAB[s - 1])
            lead_accel, fol_accel, rot_hat = ACC[s - 1][:n], ACC[s - 1][n:], ATT[s - 1]
        # the step's frame: the bars' axes (NumPy's cos and sin), zeroed accumulators
        _unary(trig[TRIG_COS], bar_yaw, bar_axis[0])
        _unary(trig[TRIG_SIN], bar_yaw, bar_axis[1])
        force[:] = 0.0
        torque_t[:] = 0.0
        bar_force[:] = 0.0
        # wake on the rotor disks, wake on the body, wake on the bar: the jet's one call
        f_draws = draws[pos:pos + 3 + k]
        pos += 3 + k
        b_draws = draws[pos:pos + 3]
        pos += 3
        wake_step(loops, jp, cols, offsets, rot[:n], thrust[:n], v[:n], p[:n], rot[n:], p[n:],
                  v[n:], coeff, processes, f_draws, dt, bar_p, bar_v, bar_axis.T, True,
                  bar_noise, b_draws, dt, True, bar_consts, wake)
        for i in range(n):
            for c in range(3):
                torque_t[c, n + i] += wake[1, i, c]
        if WT.shape[0]:  # (for the flight log's torques)
            WT[s] = wake[1]
        for i in range(n):
            for c in range(3):
                force[n + i, c] += wake[0, i, c]
        for i in range(n):  # wake on the body
            for c in range(3):
                force[n + i, c] += wake[2, i, c]
            for c in range(3):
                downwash[i, c] = (wake[0, i, c] + wake[2, i, c]) / fol_mass_rows[i, c]
        for i in range(n):  # wake on the bar
            for c in range(3):
                bar_force[i, c] += wake[3, i, c]
        # gripper contact
        if contact_kernel_body(p[n:], rot[n:], v[n:], bar_p, bar_v, bar_axis[0], bar_axis[1],
                               fc[F_MOUNT], fc[F_BAR_RADIUS], fc[F_APERTURE],
                               fc[F_BAR_HALF_LENGTH], fc[F_GATE_HEIGHT], fc[F_STIFFNESS],
                               fc[F_DAMPING], contact, inside, up):
            contact_push(contact, up, captured, any_captured, contact_seen, force, bar_force)
        # cable on the leader
        cable_wrench_kernel(cable, rot, fc[F_ANCHOR_BELOW], force, torque_t, True)
        # rotor faults
        if rotor_loss.shape[0]:
            rotor_fault_wrench(omega, fc[F_THRUST_COEFF], thrust_gain, rotor_loss, rot,
                               torque_map, force, torque_t)
        # imu
        if gyro_sd != 0.0:
            gyro_draws = draws[pos:pos + 6]
            pos += 6
        else:
            gyro_draws = draws[pos:pos]
        accel_draws = draws[pos:pos + 6]
        pos += 6
        slot = (step - latency) % slots
        if slot < 0:
            slot += slots
        iv[I_GYRO_HEAD], iv[I_ACCEL_HEAD], iv[I_RING_HEAD] = imu_step(
            loops, n, w, gyro_draws, gyro_sd, fc[F_GYRO_RANGE], gyro_c, gz1, gz2, gline,
            iv[I_GYRO_HEAD], lead_accel, fol_accel, fc[F_GRAVITY], rot, bias, thrust, hover,
            fc[F_ACCEL_NOISE_SQ], fc[F_VIBRATION], accel_draws, fc[F_ACCEL_RANGE], accel_c, az1,
            az2, aline, iv[I_ACCEL_HEAD], ring, iv[I_RING_HEAD], step, substeps, nav_accel,
            att_ring[slot, :n], att_ring[slot, n:], rot_hat, fc[F_K_P], fc[F_K_YAW], dt, noise,
            GT[s], AT[s], ATT[s])
        # vehicles: the autopilots on the chain's rates and attitude estimates
        flown_step_body(packed, p, v, rot, w, omega, ATT[s], True, r_des, yaw_rate, thrust_cmd,
                   torque_ff, has_ff, GT[s].T, no_rows, False, integral, yaw_sp, force,
                   torque_t.T, True, P[s], V[s], RM[s], W[s], OM[s], TH[s], ACC[s], INT[s],
                   YSP[s])
        if leader_fixed:  # on its stand: no motion, hover thrust
            hold_rows(0, n, p, v, rot, w, omega, integral, thrust, P[s], V[s], RM[s], W[s],
                      OM[s], INT[s], TH[s])
            for i in range(n):
                for c in range(3):
                    ACC[s][i, c] = 0.0
        # hanging pair: the bar on its cables, a captured follower hanging from it
        accel = ACC[s]
        if any_captured:
            hang_captured(captured, fc[F_BAR_MASS], fol_mass, accel[n:], gravity,
                          fol_mass_rows, bar_force, hang_mass)
        hanging_bar_kernel_body(loops, bar_p, bar_v, bar_yaw, bar_rate, p, v, accel, rot,
                                P[s], no_yaw, True, bar_force,
                                hang_mass if any_captured else bar_mass,
                                fc[F_ANCHOR_BELOW], fc[F_CABLE_LENGTH], fc[F_SWING_DAMPING],
                                fc[F_PLATFORM_GRAVITY], fc[F_YAW_OMEGA2], fc[F_YAW_DAMPING],
                                dt, BP[s], BV[s], BY[s], BR[s], CAB[s])
        if any_captured:
            carry_captured(captured, BP[s], BV[s], RM[s][n:], P[s][n:], V[s][n:], v[n:],
                           accel[n:], fc[F_HANG_OFFSET], dt)
        # ground
        ground_kernel(P[s], V[s], ground_contact)
        # commit
        step += 1
        iv[I_STEP] = step
        t = step * dt
        # gripper
        changed = 0
        if gripper_runs:
            if sample:
                g_noise = draws[pos]
                pos += 1
            else:
                g_noise = no_noise
            if g_ran:
                changed = gripper_step_kernel_body(
                    go_gate, g_bias_true, g_bias_est, go_reading, go_servo, go_by_contact,
                    go_inside_start, go_slipped, go_resolved, g_close_time, g_stuck, t,
                    contact, inside, sample, g_noise, fc[F_SENSOR_NOISE], fc[F_THRESHOLD],
                    g_passive_any, g_passive, g_active_any, g_active, close, fc[F_LATENCY],
                    go_reading, go_by_contact, go_servo, go_gate, go_inside_start,
                    go_slipped, go_resolved)
            else:
                changed = gripper_step_kernel_body(
                    g_gate, g_bias_true, g_bias_est, g_reading, g_servo, g_by_contact,
                    g_inside_start, g_slipped, g_resolved, g_close_time, g_stuck, t, contact,
                    inside, sample, g_noise, fc[F_SENSOR_NOISE], fc[F_THRESHOLD],
                    g_passive_any, g_passive, g_active_any, g_active, close, fc[F_LATENCY],
                    go_reading, go_by_contact, go_servo, go_gate, go_inside_start,
                    go_slipped, go_resolved)
                g_ran = True
            changed_all |= changed
            if sample:  # what the follower knows of a touch
                threshold = fc[F_THRESHOLD]
                for i in range(n):
                    if go_reading[i] > threshold:
                        contact_sensed[i] = True
        iv[I_DRAW] = pos
        # motion capture: the step's attitudes for the IMU's external heading
        att_ring[step % slots] = RM[s]
        if changed & (CHANGED_SERVO | CHANGED_START | CHANGED_DONE):
            return s + 1, STOP_GRIPPER, changed_all
    return steps, STOP_DONE, changed_all
