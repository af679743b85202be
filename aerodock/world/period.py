"""A control period's physics steps in one compiled call, for the default world.

:func:`run_period` runs :data:`aerodock.world.step.WORLD_STEP`'s terms, in their order, step
after step, inside one numba kernel (:func:`period_kernel`), for the world it covers: rigid-body
vehicles of one fleet with the filtered IMU chain, the built-in round jet
(:class:`~aerodock.downwash.jet.RoundJetField`, its parts its own), per-trial random streams
(:class:`~aerodock.rng.TrialRNG`), bars touching grippers and followers hanging from their bars,
rotor faults, the flight log's torques, a leader flying or on its stand. Each term calls the
njit function its per-step form calls (:mod:`aerodock.world.terms`), with the same arguments, so
the numbers are the per-step path's to the bit (``tests/unit/test_period_kernel.py``).

The kernel stops and returns how many steps it did; the caller
(:meth:`aerodock.world.World.advance`) runs the rest of the period with the per-step path:

- before a step whose random draws the trial streams' buffer does not hold (the Python path
  then refills it at the draw that needs it, as always: never earlier);
- after a step in which a gripper's servo or gate changed (a trigger fired, the gate began or
  finished closing: what later steps read of the gripper changes).

The state the steps leave is the per-step path's, as new arrays: each step's vehicles (the
motion capture's history keeps each step's positions, velocities and attitudes), the bar, the
cables, the IMU chain's outputs and the gripper are written into arrays made for this period and
handed on as the state's records; the IMU chain's memory, the jet's turbulence, the trial
streams' cursor, ``contact_seen``, ``contact_sensed`` and ``ground_contact`` advance in place,
as each step does.
"""

from __future__ import annotations

import ctypes
from functools import lru_cache
from typing import Any

import numpy as np
from numba.core.errors import NumbaError

from aerodock.downwash.base import frozen_record
from aerodock.downwash.jet import RoundJetField
from aerodock.downwash.jet_inputs import offsets_array
from aerodock.downwash.jet_kernel import wake_step
from aerodock.jit import (
    JIT_ENABLED,
    NUMPY_LOOPS,
    NUMPY_LOOPS_OK,
    _ufunc_loop,
    _unary,
    any_layout,
    njit,
)
from aerodock.rng import TrialRNG
from aerodock.world import terms
from aerodock.world.gripper import (
    GripperState,
    _any,
    _armed_any,
    _bools,
    _trigger_rows,
    contact_kernel_body,
    contact_push,
)
from aerodock.world.imu import imu_coeffs, imu_step
from aerodock.world.params import WorldParams
from aerodock.world.platform import (
    BarState,
    cable_wrench_kernel,
    hanging_bar_kernel_body,
)
from aerodock.world.sensor_kernels import (
    CHANGED_BY_CONTACT,
    CHANGED_DONE,
    CHANGED_READING,
    CHANGED_SERVO,
    CHANGED_START,
    gripper_step_kernel_body,
)
from aerodock.world.state import WorldState
from aerodock.world.term_kernels import (
    carry_captured,
    ground_kernel,
    hang_captured,
    rotor_fault_wrench,
)
from aerodock.world.vehicles.fleet import RigidBodyFleet
from aerodock.world.vehicles.rigid_body import (
    RigidBodyState,
    RigidTargets,
    flown_step_body,
    packed_step_constants,
)
from aerodock.world.vehicles.rigid_kernel import hold_rows

# -- NumPy's cos and sin, from compiled code (the bar's axis: np.cos(yaw), np.sin(yaw)) -------

TRIG_COS, TRIG_SIN = 0, 1


def _trig_loops() -> np.ndarray:
    """The addresses of NumPy's float64 cos and sin loops (as :data:`aerodock.jit.NUMPY_LOOPS`
    reads exp's), checked against the ufuncs themselves; zeros when they cannot be read or do
    not give NumPy's numbers (the compiled period is then not used)."""
    loops = np.array([_ufunc_loop(np.cos, "dd"), _ufunc_loop(np.sin, "dd")], dtype=np.int64)
    if not loops.all() or not JIT_ENABLED or not NUMPY_LOOPS_OK:
        return np.zeros(2, dtype=np.int64)
    proto = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p,
                             ctypes.c_void_p)
    for size in (1, 3, 7, 64, 257):  # the tails of the SIMD loop too
        x = np.linspace(-40.0, 40.0, size) + 0.1234
        for addr, ufunc in ((loops[TRIG_COS], np.cos), (loops[TRIG_SIN], np.sin)):
            out = np.empty_like(x)
            ptrs = np.array([x.ctypes.data, out.ctypes.data], dtype=np.intp)
            dims = np.array([size], dtype=np.intp)
            steps = np.array([8, 8], dtype=np.intp)
            proto(int(addr))(ptrs.ctypes.data, dims.ctypes.data, steps.ctypes.data, None)
            if not np.array_equal(out, ufunc(x)):
                return np.zeros(2, dtype=np.int64)
    return loops


TRIG_LOOPS = _trig_loops()
TRIG_LOOPS.flags.writeable = False
PERIOD_OK = bool(TRIG_LOOPS.all())
"""Whether the compiled period can run here (numba on, NumPy's loops readable)."""


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


# -- the Python side ------------------------------------------------------------------------
# flown_step's placeholder for an absent torque feed-forward (writable, as a command's is: one
# signature of the kernel for both)
_NO_FF = np.zeros((1, 4))
_NO_LOSS = np.zeros((0, 4))  # no rotor fault
_NO_TORQUES = np.zeros((0, 0, 3))  # no torque log
DISABLED: list[str] = []
"""Why the compiled period was turned off in this process (empty: it was not): a kernel
signature numba could not compile here (e.g. a callee sealed by :func:`aerodock.jit.any_layout`
before this kernel's first compile). The per-step path then runs every step."""


class PeriodCache:
    """What the compiled period keeps between calls for one world state: the float constants,
    the motion capture's attitudes as one ring array (``(latency + 1, 2n, 3, 3)``, slot ``j``
    the leaders' then the followers' attitude of ``state.history[j]``, recopied from the
    history only where a slot's tuple is not the one last seen), and spare arrays for the
    grippers' next state."""

    def __init__(self, state: WorldState, params: WorldParams):
        n, slots = state.n, params.latency_steps + 1
        self.state = state
        self.consts = float_constants(params)
        self.att_ring = np.empty((slots, 2 * n, 3, 3))
        self.seen: list[Any] = [None] * slots
        self.spare = _gripper_arrays(n)
        self.iv = np.zeros(5, dtype=np.int64)
        gp = params.gripper  # the armed triggers, as the gripper's step reads them
        self.triggers = (_armed_any(gp.passive), _trigger_rows(gp.passive),
                         _armed_any(gp.active), _trigger_rows(gp.active))

    def ring(self, history: list[tuple[np.ndarray, ...]]) -> np.ndarray:
        """The attitude ring, up to date with ``history``."""
        n = self.state.n
        ring, seen = self.att_ring, self.seen
        for j, entry in enumerate(history):
            if entry is not seen[j]:
                ring[j, :n] = entry[2]
                ring[j, n:] = entry[5]
                seen[j] = entry
        return ring


def _gripper_arrays(n: int) -> tuple[np.ndarray, ...]:
    """The grippers' arrays a step may change, in ``go_*`` order."""
    return (np.empty(n), np.empty(n, dtype=bool), np.empty(n), np.empty(n, dtype=np.int8),
            np.empty(n, dtype=bool), np.empty(n, dtype=bool), np.empty(n))


# The terms the kernel runs, in its order: the step it stands for. A step whose terms are not
# these (one added to, taken out of or moved in WORLD_STEP without the kernel following) runs
# per step.
_KERNEL_STEP = (
    ("wake on the rotor disks", terms.wake_on_rotor_disks),
    ("wake on the body", terms.wake_on_body),
    ("wake on the bar", terms.wake_on_bar),
    ("gripper contact", terms.gripper_contact),
    ("cable on the leader", terms.cable_on_leader),
    ("rotor faults", terms.rotor_faults),
    ("imu", terms.imu),
    ("vehicles", terms.vehicles),
    ("hanging pair", terms.hanging_pair),
    ("ground", terms.ground),
    ("commit", terms.commit),
    ("gripper", terms.gripper),
    ("motion capture", terms.motion_capture),
)


def runs_step(step: tuple[Any, ...]) -> bool:
    """Whether the kernel runs ``step``: its terms are the kernel's (the names and functions of
    :data:`aerodock.world.step.WORLD_STEP` as the kernel was written for them), in order."""
    try:
        return _runs_step(step)
    except TypeError:  # a term of one's own that cannot be hashed: not the kernel's
        return False


@lru_cache(maxsize=16)
def _runs_step(step: tuple[Any, ...]) -> bool:
    return tuple((term.name, term.apply) for term in step) == _KERNEL_STEP


def covered(state: WorldState, params: WorldParams) -> bool:
    """Whether the compiled period covers this world now (module docstring): the conditions
    that hold for a whole period (the kernel itself stops at the ones that change within it)."""
    field, rng, n = state.field, state.rng, state.n
    if not (PERIOD_OK and type(params.fleet) is RigidBodyFleet and state.imu is not None
            and isinstance(rng, TrialRNG) and rng.n == n and isinstance(field, RoundJetField)):
        return False
    loss = state.rotor_loss
    if loss is not None and (loss.dtype != np.float64 or loss.shape != (n, 4)):
        return False  # (the term's own checks and conversions)
    k = state.constants.rotor_offsets_m.shape[0]
    try:  # the jet's state as its wake_step reads it (a jet whose internals moved on: per step)
        processes = field._processes
        return (field._rng is rng and field._parts_are_the_jets()
                and processes.shape == (3 + k, n) and processes.flags.c_contiguous
                and field._bar_noise.shape == (3, n) and all(
                    callable(getattr(field, name, None)) for name in _JET_METHODS))
    except AttributeError:
        return False


# What run_period asks the jet for (its wake_step's own preparations)
_JET_METHODS = ("_pair_distance", "_jet_params", "_columns", "_force_coeff", "_bar_params")


def run_period(state: WorldState, params: WorldParams, targets: RigidTargets,
               close_command: np.ndarray | None, steps: int) -> tuple[int, int]:
    """Up to ``steps`` physics steps of the default world in one compiled call: (the number
    done, why it stopped: ``STOP_*``). The caller has checked :func:`covered`; the steps not
    done are the per-step path's."""
    n, field, rng, both = state.n, state.field, state.rng, state.both
    cache = state.__dict__.get("_period")  # not a field: a working copy of state, for speed
    if cache is None or cache.state is not state:
        cache = state.__dict__["_period"] = PeriodCache(state, params)
    packed = packed_step_constants(both.body, params.fleet.params, params.dt_s,
                                   both.thrust_gain)
    if packed is None or type(targets) is not RigidTargets:
        return 0, STOP_UNCOVERED  # (the rest per step)
    draws, cursor = rng.normal_buffer()
    ims, bar, gripper = state.imu, state.bar, state.gripper
    close = state.constants.no_close if close_command is None else close_command
    k = state.constants.rotor_offsets_m.shape[0]
    offsets = offsets_array(state.constants.rotor_offsets_m)
    field._pair_distance(offsets)
    _, fol_mass, fol_mass_rows = state.body_halves()
    iv = cache.iv
    iv[I_STEP], iv[I_DRAW] = state.step_index, cursor
    iv[I_GYRO_HEAD], iv[I_ACCEL_HEAD], iv[I_RING_HEAD] = (ims.gyro.head, ims.accel.head,
                                                          ims.ring_head)
    m = 2 * n
    cols_ap = both.autopilot_state.shape[1]
    slab_p, slab_v, slab_r = np.empty((steps, m, 3)), np.empty((steps, m, 3)), \
        np.empty((steps, m, 3, 3))
    slab_w, slab_om, slab_th = np.empty((steps, m, 3)), np.empty((steps, m, 4)), \
        np.empty((steps, m))
    slab_acc, slab_int, slab_ysp = np.empty((steps, m, 3)), np.empty((steps, m, cols_ap)), \
        np.empty((steps, m))
    slab_bp, slab_bv, slab_by, slab_br, slab_cab = (np.empty((steps, n, 3)),
                                                    np.empty((steps, n, 3)), np.empty((steps, n)),
                                                    np.empty((steps, n)), np.empty((steps, n, 3)))
    slab_gt, slab_at, slab_att = np.empty((steps, 3, m)), np.empty((steps, 3, m)), \
        np.empty((steps, m, 3, 3))
    downwash = np.empty((n, 3))
    log = state.torque_log  # the flight log's torques: the wake's torque of every step kept
    slab_wt = np.empty((steps, n, 3)) if log is not None else _NO_TORQUES
    bar_noise = np.array(field._bar_noise, order="C")
    gyro_c, accel_c = imu_coeffs(ims)
    ff = targets.torque_ff_nm
    go = cache.spare
    captured, any_captured, idle = state.gripper_flags()
    passive_any, passive, active_any, active = cache.triggers
    loss = state.rotor_loss
    try:
        result = period_kernel(
            NUMPY_LOOPS, TRIG_LOOPS, steps, cache.consts, iv, params.substeps,
            params.latency_steps, ff is not None, idle, passive_any, passive, active_any, active,
            _bools(close), active_any and _any(close), draws, packed, both.p, both.v,
            both.R, both.w, both.rotor_speed, both.autopilot_state, both.yaw_setpoint,
            both.thrust_n, targets.R_des, targets.yaw_rate_radps, targets.thrust_n,
            _NO_FF if ff is None else ff, fol_mass, fol_mass_rows, state.constants.gravity_mps2,
            state.constants.hover_thrust_n, captured, any_captured, both.thrust_gain,
            _NO_LOSS if loss is None else loss, params.follower_fleet.params.rotor_torque_map,
            state.leader_fixed,
            field._jet_params(), field._columns(k), offsets, field._force_coeff(fol_mass, k),
            field._processes, bar_noise, field._bar_params(params.platform.bar_area_m2), bar.p,
            bar.v, bar.yaw_rad, bar.yaw_rate_radps, state.constants.bar_mass_kg,
            state.cable_force_n, gyro_c, ims.gyro.z1, ims.gyro.z2, ims.gyro.delay, accel_c,
            ims.accel.z1, ims.accel.z2, ims.accel.delay, ims.bias_body_mps2, ims.accel_ring,
            ims.nav_accel_mps2, state.leader_accel, state.follower_accel, ims.attitude,
            cache.ring(state.history), gripper.gate, gripper.bias_true_n, gripper.bias_est_n,
            gripper.reading_n, gripper.servo_start_s, gripper.triggered_by_contact,
            gripper.inside_at_start, gripper.slipped, gripper.resolved_s, gripper.close_time_s,
            gripper.sensor_stuck_n, state.contact_seen, state.contact_sensed, state.ground_contact,
            slab_p, slab_v,
            slab_r, slab_w, slab_om, slab_th, slab_acc, slab_int, slab_ysp, slab_bp, slab_bv,
            slab_by, slab_br, slab_cab, slab_gt, slab_at, slab_att, slab_wt, downwash, *go)
    except NumbaError as err:  # raised while compiling, before any step: nothing has moved
        global PERIOD_OK
        PERIOD_OK = False
        DISABLED.append(f"{type(err).__name__}: {err}")
        return 0, STOP_UNCOVERED
    done, why, changed = result
    if done == 0:
        return 0, why
    # the state the steps left, as the per-step path leaves it
    rng.set_normal_cursor(int(iv[I_DRAW]))
    field._bar_noise = bar_noise
    field._last_dt = params.dt_s
    field._body_key = field._body_force = None
    ims.gyro.head, ims.accel.head, ims.ring_head = (int(iv[I_GYRO_HEAD]),
                                                    int(iv[I_ACCEL_HEAD]), int(iv[I_RING_HEAD]))
    last = done - 1
    slots = params.latency_steps + 1
    history, seen = state.history, cache.seen
    step0 = state.step_index
    for s in range(done):
        p, v, r = slab_p[s], slab_v[s], slab_r[s]
        entry = (p[:n], v[:n], r[:n], p[n:], v[n:], r[n:])
        slot = (step0 + s + 1) % slots
        history[slot] = seen[slot] = entry
    if log is not None:  # what the vehicles term hands the log, step by step
        for s in range(done):  # each step's followers at its start, the chain's gyro
            w, speed, v, r = ((both.w, both.rotor_speed, both.v, both.R) if s == 0 else
                              (slab_w[s - 1], slab_om[s - 1], slab_v[s - 1], slab_r[s - 1]))
            log.add_step(w[n:], slab_gt[s].T[n:] - w[n:], speed[n:], v[n:], r[n:], slab_wt[s])
    state.both = frozen_record(
        RigidBodyState, p=slab_p[last], v=slab_v[last], R=slab_r[last], w=slab_w[last],
        rotor_speed=slab_om[last], autopilot_state=slab_int[last], yaw_setpoint=slab_ysp[last],
        thrust_gain=both.thrust_gain, thrust_n=slab_th[last], body=both.body)
    accel = slab_acc[last]
    state.leader_accel, state.follower_accel = accel[:n], accel[n:]
    state.last_downwash_mps2 = downwash
    state.bar = frozen_record(BarState, p=slab_bp[last], v=slab_bv[last],
                              yaw_rad=slab_by[last], yaw_rate_radps=slab_br[last])
    state.cable_force_n = slab_cab[last]
    ims.accel_t, ims.attitude, ims.gyro_radps = slab_at[last], slab_att[last], slab_gt[last].T
    state.step_index = int(iv[I_STEP])
    state.t_s = state.step_index * params.dt_s
    if changed:
        reading, by_contact, servo, gate, inside_start, slipped, resolved = go
        done_bit = changed & CHANGED_DONE
        state.gripper = GripperState(
            gate if changed & (CHANGED_START | CHANGED_DONE) else gripper.gate,
            gripper.bias_true_n, gripper.bias_est_n,
            reading if changed & CHANGED_READING else gripper.reading_n,
            servo if changed & CHANGED_SERVO else gripper.servo_start_s,
            by_contact if changed & CHANGED_BY_CONTACT else gripper.triggered_by_contact,
            inside_start if changed & CHANGED_START else gripper.inside_at_start,
            slipped if done_bit else gripper.slipped, resolved if done_bit else gripper.resolved_s,
            gripper.close_time_s, gripper.sensor_stuck_n)
        cache.spare = _gripper_arrays(n)
    return done, why
