"""The compiled control period's kernel: :data:`aerodock.world.step.WORLD_STEP`'s terms, in their
order, step after step, in one numba call (:func:`period_kernel`, or :func:`period_kernel_parallel`
with the trials in blocks across the cores), with the constants it reads
(:func:`float_constants`) and NumPy's cos and sin loops it calls. :mod:`aerodock.world.period`
decides when it runs, hands it the world's arrays and puts back the state it leaves.

A step is :func:`block_step` on a block of trials (rows ``lo..hi`` of the trial arrays, and their
leaders' and followers' rows of the 2n vehicle arrays): every term computes a trial's numbers
from that trial's rows alone, so blocks stepped apart, in any order or at once, give the numbers
of the whole batch stepped at once (``tests/unit/test_period_parallel.py``). What the blocks
share (the clock, the draws' cursor, the IMU chain's ring heads, whether a gripper changed) is
decided before and after each step by :func:`_step_plan` and :func:`_step_done`, in one thread.
"""

from __future__ import annotations

import numba
import numpy as np

from aerodock.borrowed import borrowed, keep_alive
from aerodock.downwash.jet_kernel import wake_step
from aerodock.jit import _unary, any_layout, njit, njit_parallel
from aerodock.world.gripper import contact_kernel_body, contact_push
from aerodock.world.imu import _next_slot, imu_step
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
from aerodock.world.vehicles.rigid_body import flown_rows
from aerodock.world.vehicles.rigid_kernel import hold_rows

# -- the kernel's float constants (one array, built once per world) -------------------------
(F_DT, F_ANCHOR_BELOW, F_CABLE_LENGTH, F_SWING_DAMPING, F_PLATFORM_GRAVITY, F_YAW_OMEGA2,
 F_YAW_DAMPING, F_GYRO_SD, F_GYRO_RANGE, F_GRAVITY, F_ACCEL_NOISE_SQ, F_VIBRATION,
 F_ACCEL_RANGE, F_K_P, F_K_YAW, F_SENSOR_RATE, F_SENSOR_NOISE, F_THRESHOLD, F_LATENCY,
 F_MOUNT, F_BAR_RADIUS, F_APERTURE, F_BAR_HALF_LENGTH, F_GATE_HEIGHT, F_STIFFNESS,
 F_DAMPING, F_BAR_MASS, F_HANG_OFFSET, F_THRUST_COEFF) = range(29)
F_SIZE = 29
# the kernel's integers in and out: the clock, the draws' cursor, the IMU chain's heads; out:
# the normal draws the step it stopped before (STOP_DRAWS) takes
I_STEP, I_DRAW, I_GYRO_HEAD, I_ACCEL_HEAD, I_RING_HEAD, I_NEED = range(6)
I_SIZE = 6
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



# The arrays the kernels write (any_layout keeps them writable in the general signature)
_WRITES = ("iv", "processes", "bar_noise", "gz1", "gz2", "gline", "az1", "az2", "aline",
           "ring", "nav_accel", "att_ring", "contact_seen", "contact_sensed", "ground_contact",
           "P", "V", "RM", "W", "OM", "TH", "ACC", "INT", "YSP", "BP", "BV", "BY", "BR", "CAB",
           "GT", "AT", "ATT", "WT", "downwash", "go_reading", "go_by_contact", "go_servo",
           "go_gate", "go_inside_start", "go_slipped", "go_resolved")


@njit
def _physics_draws(fc: np.ndarray, k: int) -> int:
    """Each trial's normal draws of a step before the strain gauge's: the follower's wake
    (3 + k), the bar's (3), the gyros' (6, with gyro noise) and the accelerometers' (6)."""
    return 3 + k + 3 + (6 if fc[F_GYRO_SD] != 0.0 else 0) + 6


@njit
def _step_plan(iv: np.ndarray, fc: np.ndarray, k: int, n_draws: int, g_idle: bool,
               active_close: bool) -> tuple[int, int, bool, bool]:
    """What every block of a step shares, before it: (the step's index, the draws' cursor,
    whether the strain gauge samples at its end, whether the grippers step); a cursor of -1:
    the buffer does not hold the step's draws (their number then in ``iv[I_NEED]``)."""
    step = iv[I_STEP]
    pos = iv[I_DRAW]
    dt = fc[F_DT]
    t_end = (step + 1) * dt
    rate = fc[F_SENSOR_RATE]
    sample = int(t_end * rate + 1e-9) != int((t_end - dt) * rate + 1e-9)
    gripper_runs = not (g_idle and not sample and not active_close)
    need = _physics_draws(fc, k) + (1 if gripper_runs and sample else 0)  # (_step_done's)
    if pos + need > n_draws:
        iv[I_NEED] = need
        pos = -1
    return step, pos, sample, gripper_runs


@njit
def _step_done(iv: np.ndarray, fc: np.ndarray, k: int, sample: bool, gripper_runs: bool,
               gline: np.ndarray, aline: np.ndarray, ring: np.ndarray) -> None:
    """After every block of a step: the clock, the draws' cursor (the step's draws, in the
    terms' order) and the IMU chain's ring heads move on."""
    iv[I_DRAW] += _physics_draws(fc, k) + (1 if gripper_runs and sample else 0)
    iv[I_STEP] += 1
    iv[I_GYRO_HEAD] = _next_slot(gline, iv[I_GYRO_HEAD])
    iv[I_ACCEL_HEAD] = _next_slot(aline, iv[I_ACCEL_HEAD])
    iv[I_RING_HEAD] = _next_slot(ring, iv[I_RING_HEAD])


@njit
def block_step(lo: int, hi: int, s: int, step: int, pos: int, sample: bool, gripper_runs: bool,
               g_ran: bool, loops: np.ndarray, trig: np.ndarray, fc: np.ndarray,
               iv: np.ndarray, substeps: int, latency: int, has_ff: bool,
               g_passive_any: bool, g_passive: np.ndarray, g_active_any: bool,
               g_active: np.ndarray, close: np.ndarray, draws: np.ndarray, packed: np.ndarray,
               p: np.ndarray, v: np.ndarray, rot: np.ndarray, w: np.ndarray,
               omega: np.ndarray, integral: np.ndarray, yaw_sp: np.ndarray,
               thrust: np.ndarray, bar_p: np.ndarray, bar_v: np.ndarray, bar_yaw: np.ndarray,
               bar_rate: np.ndarray, cable: np.ndarray, lead_accel: np.ndarray,
               fol_accel: np.ndarray, rot_hat: np.ndarray, r_des: np.ndarray,
               yaw_rate: np.ndarray, thrust_cmd: np.ndarray, torque_ff: np.ndarray,
               fol_mass: np.ndarray, fol_mass_rows: np.ndarray, gravity: np.ndarray,
               hover: np.ndarray, captured: np.ndarray, any_captured: bool,
               thrust_gain: np.ndarray, rotor_loss: np.ndarray, torque_map: np.ndarray,
               leader_fixed: bool, jp: np.ndarray, cols: np.ndarray, offsets: np.ndarray,
               coeff: np.ndarray, processes: np.ndarray, bar_noise: np.ndarray,
               bar_consts: np.ndarray, bar_mass: np.ndarray, gyro_c: np.ndarray,
               gz1: np.ndarray, gz2: np.ndarray, gline: np.ndarray, accel_c: np.ndarray,
               az1: np.ndarray, az2: np.ndarray, aline: np.ndarray, bias: np.ndarray,
               ring: np.ndarray, nav_accel: np.ndarray, att_ring: np.ndarray,
               g_gate: np.ndarray, g_bias_true: np.ndarray, g_bias_est: np.ndarray,
               g_reading: np.ndarray, g_servo: np.ndarray, g_by_contact: np.ndarray,
               g_inside_start: np.ndarray, g_slipped: np.ndarray, g_resolved: np.ndarray,
               g_close_time: np.ndarray, g_stuck: np.ndarray, contact_seen: np.ndarray,
               contact_sensed: np.ndarray, ground_contact: np.ndarray, P: np.ndarray,  # noqa: N803
               V: np.ndarray, RM: np.ndarray, W: np.ndarray, OM: np.ndarray,  # noqa: N803
               TH: np.ndarray, ACC: np.ndarray, INT: np.ndarray, YSP: np.ndarray,  # noqa: N803
               BP: np.ndarray, BV: np.ndarray, BY: np.ndarray, BR: np.ndarray,  # noqa: N803
               CAB: np.ndarray, GT: np.ndarray, AT: np.ndarray, ATT: np.ndarray,  # noqa: N803
               WT: np.ndarray, downwash: np.ndarray, go_reading: np.ndarray,  # noqa: N803
               go_by_contact: np.ndarray, go_servo: np.ndarray, go_gate: np.ndarray,
               go_inside_start: np.ndarray, go_slipped: np.ndarray, go_resolved: np.ndarray,
               bar_axis: np.ndarray, contact: np.ndarray, inside: np.ndarray, up: np.ndarray,
               force: np.ndarray, torque_t: np.ndarray, bar_force: np.ndarray,
               hang_mass: np.ndarray, wake: np.ndarray, noise: np.ndarray) -> int:
    """Physics step ``s`` (the world's ``step``-th) of trials ``lo..hi``: each term of
    :data:`aerodock.world.step.WORLD_STEP` in its order, calling the compiled function its
    per-step form calls (:mod:`aerodock.world.terms`), on this block's rows. It reads the state
    ``p`` ... ``rot_hat`` (the step before's) and writes row ``s`` of ``P`` ... ``ATT``; the
    IMU chain's memory, the turbulence, ``contact_sensed`` and ``ground_contact`` advance in
    place, as the grippers' ``go_*``; ``bar_axis`` ... ``noise`` are the step's scratch rows.
    The draws are read from row ``pos`` on, in the terms' order; the shared counters (``iv``)
    are only read. Returns the ``CHANGED_*`` bits of the block's grippers' step."""
    m = p.shape[0]
    n = m // 2
    k = offsets.shape[0]
    dt = fc[F_DT]
    gyro_sd = fc[F_GYRO_SD]
    slots = latency + 1
    a, b, fa, fb = lo, hi, n + lo, n + hi  # the block's leaders' rows, its followers'
    # the step's frame: the bars' axes (NumPy's cos and sin), zeroed accumulators
    _unary(trig[TRIG_COS], bar_yaw[a:b], bar_axis[0, a:b])
    _unary(trig[TRIG_SIN], bar_yaw[a:b], bar_axis[1, a:b])
    for i in range(a, b):
        for c in range(3):
            force[i, c] = 0.0
            force[n + i, c] = 0.0
            torque_t[c, i] = 0.0
            torque_t[c, n + i] = 0.0
            bar_force[i, c] = 0.0
    # wake on the rotor disks, wake on the body, wake on the bar: the jet's one call
    f_draws = draws[pos:pos + 3 + k, a:b]
    pos += 3 + k
    b_draws = draws[pos:pos + 3, a:b]
    pos += 3
    wake_step(loops, jp, cols, offsets, rot[a:b], thrust[a:b], v[a:b], p[a:b], rot[fa:fb],
              p[fa:fb], v[fa:fb], coeff[:, a:b], processes[:, a:b], f_draws, dt, bar_p[a:b],
              bar_v[a:b], bar_axis.T[a:b], True, bar_noise[:, a:b], b_draws, dt, True,
              bar_consts, wake[:, a:b])
    for i in range(a, b):
        for c in range(3):
            torque_t[c, n + i] += wake[1, i, c]
    if WT.shape[0]:  # (for the flight log's torques)
        for i in range(a, b):
            for c in range(3):
                WT[s, i, c] = wake[1, i, c]
    for i in range(a, b):
        for c in range(3):
            force[n + i, c] += wake[0, i, c]
    for i in range(a, b):  # wake on the body
        for c in range(3):
            force[n + i, c] += wake[2, i, c]
        for c in range(3):
            downwash[i, c] = (wake[0, i, c] + wake[2, i, c]) / fol_mass_rows[i, c]
    for i in range(a, b):  # wake on the bar
        for c in range(3):
            bar_force[i, c] += wake[3, i, c]
    # gripper contact
    if contact_kernel_body(p[fa:fb], rot[fa:fb], v[fa:fb], bar_p[a:b], bar_v[a:b],
                           bar_axis[0, a:b], bar_axis[1, a:b], fc[F_MOUNT], fc[F_BAR_RADIUS],
                           fc[F_APERTURE], fc[F_BAR_HALF_LENGTH], fc[F_GATE_HEIGHT],
                           fc[F_STIFFNESS], fc[F_DAMPING], contact[a:b], inside[a:b],
                           up[a:b]):
        contact_push(contact[a:b], up[a:b], captured[a:b], any_captured, contact_seen[a:b],
                     force[fa:fb], bar_force[a:b])
    # cable on the leader
    cable_wrench_kernel(cable[a:b], rot[a:b], fc[F_ANCHOR_BELOW], force[a:b], torque_t[:, a:b],
                        True)
    # rotor faults
    if rotor_loss.shape[0]:
        rotor_fault_wrench(omega[fa:fb], fc[F_THRUST_COEFF], thrust_gain[fa:fb],
                           rotor_loss[a:b], rot[fa:fb], torque_map, force[fa:fb],
                           torque_t[:, fa:fb])
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
    imu_step(loops, n, a, b, w, gyro_draws, gyro_sd, fc[F_GYRO_RANGE], gyro_c, gz1, gz2, gline,
             iv[I_GYRO_HEAD], lead_accel, fol_accel, fc[F_GRAVITY], rot, bias, thrust, hover,
             fc[F_ACCEL_NOISE_SQ], fc[F_VIBRATION], accel_draws, fc[F_ACCEL_RANGE], accel_c,
             az1, az2, aline, iv[I_ACCEL_HEAD], ring, iv[I_RING_HEAD], step, substeps,
             nav_accel, att_ring[slot, :n], att_ring[slot, n:], rot_hat, fc[F_K_P],
             fc[F_K_YAW], dt, noise, GT[s], AT[s], ATT[s])
    # vehicles: the autopilots on the chain's rates and attitude estimates, leaders then
    # followers
    for r0, r1 in ((a, b), (fa, fb)):
        flown_rows(packed, r0, r1, p, v, rot, w, omega, ATT[s], True, r_des, yaw_rate,
                   thrust_cmd, torque_ff, has_ff, GT[s].T, GT[s].T[:0], False, integral,
                   yaw_sp, force, torque_t.T, True, P[s], V[s], RM[s], W[s], OM[s], TH[s],
                   ACC[s], INT[s], YSP[s])
    if leader_fixed:  # on its stand: no motion, hover thrust
        hold_rows(a, b, p, v, rot, w, omega, integral, thrust, P[s], V[s], RM[s], W[s],
                  OM[s], INT[s], TH[s])
        for i in range(a, b):
            for c in range(3):
                ACC[s, i, c] = 0.0
    # hanging pair: the bar on its cables, a captured follower hanging from it
    accel = ACC[s]
    if any_captured:
        hang_captured(captured[a:b], fc[F_BAR_MASS], fol_mass[a:b], accel[fa:fb], gravity,
                      fol_mass_rows[a:b], bar_force[a:b], hang_mass[a:b])
    hanging_bar_kernel_body(loops, bar_p[a:b], bar_v[a:b], bar_yaw[a:b], bar_rate[a:b], p[a:b],
                            v[a:b], accel[a:b], rot[a:b], P[s, a:b], bar_yaw[:0], True,
                            bar_force[a:b], hang_mass[a:b] if any_captured else bar_mass[a:b],
                            fc[F_ANCHOR_BELOW], fc[F_CABLE_LENGTH], fc[F_SWING_DAMPING],
                            fc[F_PLATFORM_GRAVITY], fc[F_YAW_OMEGA2], fc[F_YAW_DAMPING], dt,
                            BP[s, a:b], BV[s, a:b], BY[s, a:b], BR[s, a:b], CAB[s, a:b])
    if any_captured:
        carry_captured(captured[a:b], BP[s, a:b], BV[s, a:b], RM[s, fa:fb], P[s, fa:fb],
                       V[s, fa:fb], v[fa:fb], accel[fa:fb], fc[F_HANG_OFFSET], dt)
    # ground
    ground_kernel(P[s], V[s], ground_contact, a, b)
    # commit: the step's end
    t = (step + 1) * dt
    # gripper
    changed = 0
    if gripper_runs:
        g_noise = draws[pos, a:b] if sample else draws[pos, a:a]
        if g_ran:
            changed = gripper_step_kernel_body(
                go_gate[a:b], g_bias_true[a:b], g_bias_est[a:b], go_reading[a:b],
                go_servo[a:b], go_by_contact[a:b], go_inside_start[a:b], go_slipped[a:b],
                go_resolved[a:b], g_close_time[a:b], g_stuck[a:b], t, contact[a:b],
                inside[a:b], sample, g_noise, fc[F_SENSOR_NOISE], fc[F_THRESHOLD],
                g_passive_any, _trial_rows(g_passive, a, b), g_active_any,
                _trial_rows(g_active, a, b), close[a:b], fc[F_LATENCY], go_reading[a:b],
                go_by_contact[a:b], go_servo[a:b], go_gate[a:b], go_inside_start[a:b],
                go_slipped[a:b], go_resolved[a:b])
        else:
            changed = gripper_step_kernel_body(
                g_gate[a:b], g_bias_true[a:b], g_bias_est[a:b], g_reading[a:b], g_servo[a:b],
                g_by_contact[a:b], g_inside_start[a:b], g_slipped[a:b], g_resolved[a:b],
                g_close_time[a:b], g_stuck[a:b], t, contact[a:b], inside[a:b], sample, g_noise,
                fc[F_SENSOR_NOISE], fc[F_THRESHOLD], g_passive_any,
                _trial_rows(g_passive, a, b), g_active_any, _trial_rows(g_active, a, b),
                close[a:b], fc[F_LATENCY], go_reading[a:b], go_by_contact[a:b],
                go_servo[a:b], go_gate[a:b], go_inside_start[a:b], go_slipped[a:b],
                go_resolved[a:b])
        if sample:  # what the follower knows of a touch
            threshold = fc[F_THRESHOLD]
            for i in range(a, b):
                if go_reading[i] > threshold:
                    contact_sensed[i] = True
    # motion capture: the step's attitudes for the IMU's external heading
    ring_slot = (step + 1) % slots
    for i in range(a, b):
        att_ring[ring_slot, i] = RM[s, i]
        att_ring[ring_slot, n + i] = RM[s, n + i]
    return changed


@njit
def _trial_rows(flags: np.ndarray, lo: int, hi: int) -> np.ndarray:
    """A trigger's arming for trials ``lo..hi``: (1,) for every trial stays as it is."""
    return flags if flags.shape[0] == 1 else flags[lo:hi]


@njit
def _scratch(n: int, gyro_sd: float, blocks: int) -> tuple:
    """A period's scratch rows, shared by its steps and blocks (each block its own rows), and
    each block's gripper changes."""
    m = 2 * n
    return (np.zeros((3, n)), np.empty(n), np.empty(n, dtype=np.bool_), np.empty((n, 3)),
            np.empty((m, 3)), np.empty((3, m)), np.empty((n, 3)), np.empty(n),
            np.empty((4, n, 3)), np.empty((3, m)) if gyro_sd != 0.0 else np.zeros((3, 0)),
            np.zeros(blocks, dtype=np.int64))


def _period_driver(loops, trig, steps, fc, iv, substeps, latency, has_ff, g_idle, g_passive_any,
           g_passive, g_active_any, g_active, close, active_close, draws, packed, p0, v0,
           rot0, w0, omega0, integral0, yaw_sp0, thrust0, r_des, yaw_rate, thrust_cmd,
           torque_ff, fol_mass, fol_mass_rows, gravity, hover, captured, any_captured,
           thrust_gain, rotor_loss, torque_map, leader_fixed, jp, cols, offsets, coeff,
           processes, bar_noise, bar_consts, bar_p0, bar_v0, bar_yaw0, bar_rate0, bar_mass,
           cable0, gyro_c, gz1, gz2, gline, accel_c, az1, az2, aline, bias, ring, nav_accel,
           lead_accel0, fol_accel0, rot_hat0, att_ring, g_gate, g_bias_true, g_bias_est,
           g_reading, g_servo, g_by_contact, g_inside_start, g_slipped, g_resolved,
           g_close_time, g_stuck, contact_seen, contact_sensed, ground_contact, P, V, RM, W,
           OM, TH, ACC, INT, YSP, BP, BV, BY, BR, CAB, GT, AT, ATT, WT, downwash, go_reading,
           go_by_contact, go_servo, go_gate, go_inside_start, go_slipped, go_resolved,
           blocks):  # noqa: N803 (the step's rows, capitals as the kernel's outputs)
    """Up to ``steps`` physics steps of :data:`aerodock.world.step.WORLD_STEP`, each step the
    ``blocks`` blocks of trials of :func:`block_step` (numba's ``prange``: across the cores in
    :func:`period_kernel_parallel`, one after the other in :func:`period_kernel`). Step ``s``
    reads the state the step before left (the ``*0`` inputs for the first) and writes its own
    into row ``s`` of the outputs (``P`` ... ``ATT``: the vehicles, the bar, the cables, the IMU
    chain's outputs and the attitude estimates); the IMU chain's memory, the jet's turbulence
    (``processes``, ``bar_noise``), ``contact_sensed``, ``ground_contact``, the motion
    capture's attitude ring ``att_ring`` (latency + 1, 2n, 3, 3) and ``iv`` (``I_*``) advance
    in place; the grippers' changed arrays end in ``go_*``.

    Returns (steps done, why it stopped (``STOP_*``), the ``CHANGED_*`` bits of the grippers'
    steps, OR-ed)."""
    # Every array argument as a borrowed view (aerodock.borrowed): the caller holds them
    # for the call, and the step's some 1,400 reference counts then need no atomic instruction.
    (loops, trig, fc, iv, g_passive, g_active, close, draws, packed, p0, v0, rot0, w0,
     omega0, integral0, yaw_sp0, thrust0, r_des, yaw_rate, thrust_cmd, torque_ff,
     fol_mass, fol_mass_rows, gravity, hover, captured, thrust_gain, rotor_loss,
     torque_map, jp, cols, offsets, coeff, processes, bar_noise, bar_consts, bar_p0,
     bar_v0, bar_yaw0, bar_rate0, bar_mass, cable0, gyro_c, gz1, gz2, gline, accel_c,
     az1, az2, aline, bias, ring, nav_accel, lead_accel0, fol_accel0, rot_hat0,
     att_ring, g_gate, g_bias_true, g_bias_est, g_reading, g_servo, g_by_contact,
     g_inside_start, g_slipped, g_resolved, g_close_time, g_stuck, contact_seen,
     contact_sensed, ground_contact, P, V, RM, W, OM, TH, ACC, INT, YSP, BP, BV, BY, BR,
     CAB, GT, AT, ATT, WT, downwash, go_reading, go_by_contact, go_servo, go_gate,
     go_inside_start, go_slipped, go_resolved) = borrowed((
        loops, trig, fc, iv, g_passive, g_active, close, draws, packed, p0, v0, rot0,
        w0, omega0, integral0, yaw_sp0, thrust0, r_des, yaw_rate, thrust_cmd, torque_ff,
        fol_mass, fol_mass_rows, gravity, hover, captured, thrust_gain, rotor_loss,
        torque_map, jp, cols, offsets, coeff, processes, bar_noise, bar_consts, bar_p0,
        bar_v0, bar_yaw0, bar_rate0, bar_mass, cable0, gyro_c, gz1, gz2, gline, accel_c,
        az1, az2, aline, bias, ring, nav_accel, lead_accel0, fol_accel0, rot_hat0,
        att_ring, g_gate, g_bias_true, g_bias_est, g_reading, g_servo, g_by_contact,
        g_inside_start, g_slipped, g_resolved, g_close_time, g_stuck, contact_seen,
        contact_sensed, ground_contact, P, V, RM, W, OM, TH, ACC, INT, YSP, BP, BV, BY,
        BR, CAB, GT, AT, ATT, WT, downwash, go_reading, go_by_contact, go_servo,
        go_gate, go_inside_start, go_slipped, go_resolved))
    n = p0.shape[0] // 2
    k = offsets.shape[0]
    owners = _scratch(n, fc[F_GYRO_SD], blocks)  # kept to the end: views borrow them
    (bar_axis, contact, inside, up, force, torque_t, bar_force, hang_mass, wake, noise,
     changed_b) = borrowed(owners)
    changed_all = 0
    g_ran = False
    for s in range(steps):
        step, pos, sample, gripper_runs = _step_plan(iv, fc, k, draws.shape[0], g_idle,
                                                     active_close)
        if pos < 0:
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
        for blk in numba.prange(blocks):
            lo = blk * n // blocks
            hi = (blk + 1) * n // blocks
            changed_b[blk] = block_step(
                lo, hi, s, step, pos, sample, gripper_runs, g_ran, loops, trig, fc, iv,
                substeps, latency, has_ff, g_passive_any, g_passive, g_active_any, g_active,
                close, draws, packed, p, v, rot, w, omega, integral, yaw_sp, thrust, bar_p,
                bar_v, bar_yaw, bar_rate, cable, lead_accel, fol_accel, rot_hat, r_des,
                yaw_rate, thrust_cmd, torque_ff, fol_mass, fol_mass_rows, gravity, hover,
                captured, any_captured, thrust_gain, rotor_loss, torque_map, leader_fixed, jp,
                cols, offsets, coeff, processes, bar_noise, bar_consts, bar_mass, gyro_c, gz1,
                gz2, gline, accel_c, az1, az2, aline, bias, ring, nav_accel, att_ring, g_gate,
                g_bias_true, g_bias_est, g_reading, g_servo, g_by_contact, g_inside_start,
                g_slipped, g_resolved, g_close_time, g_stuck, contact_seen, contact_sensed,
                ground_contact, P, V, RM, W, OM, TH, ACC, INT, YSP, BP, BV, BY, BR, CAB, GT, AT,
                ATT, WT, downwash, go_reading, go_by_contact, go_servo, go_gate,
                go_inside_start, go_slipped, go_resolved, bar_axis, contact, inside, up, force,
                torque_t, bar_force, hang_mass, wake, noise)
        changed = 0
        for blk in range(blocks):
            changed |= changed_b[blk]
        changed_all |= changed
        if gripper_runs:
            g_ran = True
        _step_done(iv, fc, k, sample, gripper_runs, gline, aline, ring)
        if changed & (CHANGED_SERVO | CHANGED_START | CHANGED_DONE):
            return s + 1, STOP_GRIPPER, changed_all
    keep_alive(owners)
    return steps, STOP_DONE, changed_all


def _named(fn, name: str):  # noqa: ANN001, ANN202
    """``fn`` under another name: numba keeps a kernel's cache by its name, and the serial and
    the parallel kernel are compiled from one source with different options."""
    import types
    code = fn.__code__.replace(co_name=name, co_qualname=name)
    out = types.FunctionType(code, fn.__globals__, name, fn.__defaults__, fn.__closure__)
    out.__qualname__, out.__module__, out.__doc__ = name, fn.__module__, fn.__doc__
    out.__annotations__ = dict(fn.__annotations__)
    return out


period_kernel = any_layout(*_WRITES, contiguous=("packed",), general_only=False)(
    njit(_named(_period_driver, "period_kernel")))
"""The driver with its blocks one after the other (one block: the whole batch)."""
period_kernel_parallel = any_layout(*_WRITES, contiguous=("packed",), general_only=True)(
    njit_parallel(_named(_period_driver, "period_kernel_parallel")))
"""The driver with its blocks across the cores (numba's threads): the same numbers."""
