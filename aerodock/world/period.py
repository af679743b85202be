"""A control period's physics steps in one compiled call, for the default world.

:func:`run_period` runs :data:`aerodock.world.step.WORLD_STEP`'s terms, in their order, step
after step, inside one numba kernel (:func:`~aerodock.world.period_kernel.period_kernel`), for
the world it covers: rigid-body vehicles of one fleet with the filtered IMU chain, the built-in
round jet (:class:`~aerodock.downwash.jet.RoundJetField`, its parts its own), per-trial random
streams (:class:`~aerodock.rng.TrialRNG`), bars touching grippers and followers hanging from their
bars, rotor faults, the flight log's torques, a leader flying or on its stand. Each term calls the
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

import os
import time
from functools import lru_cache
from typing import Any

import numba
import numpy as np
from numba.core.errors import NumbaError

from aerodock.downwash.base import frozen_record
from aerodock.downwash.jet import RoundJetField
from aerodock.downwash.jet_inputs import offsets_array
from aerodock.jit import NUMPY_LOOPS
from aerodock.rng import TrialRNG
from aerodock.world import terms
from aerodock.world.block_choice import block_choice
from aerodock.world.gripper import (
    _any,
    _armed_any,
    _bools,
    _trigger_rows,
    gripper_after,
)
from aerodock.world.imu import imu_coeffs
from aerodock.world.params import WorldParams
from aerodock.world.period_kernel import (
    I_ACCEL_HEAD,
    I_DRAW,
    I_GYRO_HEAD,
    I_NEED,
    I_RING_HEAD,
    I_SIZE,
    I_STEP,
    STOP_DRAWS,
    STOP_UNCOVERED,
    float_constants,
    period_kernel,
    period_kernel_parallel,
)
from aerodock.world.platform import (
    BarState,
)
from aerodock.world.state import WorldState
from aerodock.world.trig_loops import TRIG_LOOPS
from aerodock.world.vehicles.fleet import RigidBodyFleet
from aerodock.world.vehicles.rigid_body import (
    RigidBodyState,
    packed_step_constants,
)
from aerodock.world.vehicles.targets import RigidTargets

PERIOD_OK = bool(TRIG_LOOPS.all())
"""Whether the compiled period can run here (numba on, NumPy's loops readable)."""

# flown_step's placeholder for an absent torque feed-forward (writable, as a command's is: one
# signature of the kernel for both)
_NO_FF = np.zeros((1, 4))
_NO_LOSS = np.zeros((0, 4))  # no rotor fault
_NO_TORQUES = np.zeros((0, 0, 3))  # no torque log
# numba's OpenMP threads sleep between control periods instead of spinning through them (the
# user's own settings stand; read when numba starts its threads, at the first period in blocks):
# a thread spinning on would take a core from the Python between control periods (a learnt model's
# prediction, the mission, the trial streams' refills) and from another process on the machine
# (the test suite's second worker). But a thread that sleeps at once pays a wake-up at every
# physics step's blocks, about 80 µs on a 2-core VM (7 December 2026: at 32-128 trials the
# period in blocks was then slower than the serial one, 0.54-0.82 of its speed): GNU OpenMP's
# threads (numba's `omp` layer) first spin this many turns, about 0.6 ms on that machine, which
# keeps them awake through a period's steps and most of the Python between two periods, then
# sleep (docs/performance.md, "The threads' wake-ups"). Both are the user's to override.
os.environ.setdefault("OMP_WAIT_POLICY", "passive")
os.environ.setdefault("GOMP_SPINCOUNT", "10000")

PARALLEL_MIN_TRIALS = 64
"""From this many trials on, a period's blocks of trials run across numba's threads
(:func:`~aerodock.world.period_kernel.period_kernel_parallel`, one block a thread); below it, in
one (a thread's start and join cost about what a small batch's step does). The numbers are the
same either way."""
CHOOSE_BLOCKS = True
"""A batch that may run in blocks runs them across the threads only while that measures faster
than one after another (:mod:`aerodock.world.block_choice`: on a machine where another process
holds a core, the threads are the slower way); False: always in blocks."""
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
        self.iv = np.zeros(I_SIZE, dtype=np.int64)
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


def kernel_blocks(n: int) -> int:
    """How many blocks of trials a period of ``n`` trials may be stepped in: one a thread of
    numba's (:func:`numba.get_num_threads`) from :data:`PARALLEL_MIN_TRIALS` trials on, else 1
    (the serial kernel). :func:`run_period` runs them one after another instead while that
    measures faster (:data:`CHOOSE_BLOCKS`)."""
    if n < PARALLEL_MIN_TRIALS:
        return 1  # (asking numba for its threads costs about 2 µs, at every period)
    threads = numba.get_num_threads()
    return threads if threads > 1 else 1


_BLAS_LIMIT: list[Any] = []


def one_blas_thread() -> None:
    """Keep BLAS (NumPy's OpenBLAS, through ``threadpoolctl``) to one thread in this process
    from now on: done once, before the first period stepped in blocks. BLAS's threads would
    compete with numba's for the cores (a learnt model's prediction comes every control period,
    and a step's blocks wait for each other), and its products here are small. The numbers do
    not change (a matrix product's elements are summed in the same order on any number of
    threads; ``targets --trials 250``'s JSON is the same). ``restore_original_limits()`` on
    ``_BLAS_LIMIT[0]`` gives BLAS its threads back."""
    if not _BLAS_LIMIT:
        from threadpoolctl import threadpool_limits

        _BLAS_LIMIT.append(threadpool_limits(limits=1, user_api="blas"))


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
    blocks = kernel_blocks(n)
    choice = block_choice(n) if blocks > 1 and CHOOSE_BLOCKS else None
    if choice is not None and not choice.parallel():
        blocks = 1
    if blocks > 1:
        one_blas_thread()
    kernel = period_kernel_parallel if blocks > 1 else period_kernel
    start = time.perf_counter()
    try:
        result = kernel(
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
            slab_by, slab_br, slab_cab, slab_gt, slab_at, slab_att, slab_wt, downwash, *go,
            blocks)
    except NumbaError as err:  # raised while compiling, before any step: nothing has moved
        global PERIOD_OK
        PERIOD_OK = False
        DISABLED.append(f"{type(err).__name__}: {err}")
        return 0, STOP_UNCOVERED
    done, why, changed = result
    if choice is not None:
        choice.record(time.perf_counter() - start, done)
    if done == 0:
        if why == STOP_DRAWS:
            rng.reserve_normals(int(iv[I_NEED]))  # (as below)
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
    # each step's entry: its leaders' then followers' positions, velocities and attitudes (the
    # views made by iterating the slabs' halves: NumPy's own loop, not one indexing a view)
    for s, entry in enumerate(zip(slab_p[:done, :n], slab_v[:done, :n], slab_r[:done, :n],
                                  slab_p[:done, n:], slab_v[:done, n:], slab_r[:done, n:])):
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
        state.gripper = gripper_after(gripper, changed, reading, by_contact, servo, gate,
                                      inside_start, slipped, resolved)
        cache.spare = _gripper_arrays(n)
    if why == STOP_DRAWS:  # the next step's draws, refilled now (the cursor moved on above) as
        # its first draw past the buffer's end would refill them (a covered step draws nothing
        # else): the next call goes on
        rng.reserve_normals(int(iv[I_NEED]))
    return done, why
