"""The physics terms of one world step: each a plain function ``term(state, frame, params)``.

A term reads the batch state (:class:`~aerodock.world.state.WorldState`) and the step's frame
(:class:`~aerodock.world.state.StepFrame`), adds what it contributes into the frame's
accumulators (forces, torques, the force on the hanging mass) or advances a part of the state, and
returns nothing. Terms never copy the batch; they write in place into arrays the frame made for
this step (and the IMU term into the chain's own memory: :mod:`aerodock.world.state`).
:mod:`aerodock.world.step` names them in the order they run; a new effect (an IMU chain, ground
effect) is one more function here and one more name there.
"""

from __future__ import annotations

import numpy as np

from aerodock.downwash.wrench import (
    bar_wake_force_n,
    follower_body_force_n,
    follower_wrench,
    wake_step,
)
from aerodock.jit import NUMPY_LOOPS
from aerodock.rng import standard_normal_t
from aerodock.world.gripper import contact_in_gripper, contact_push, step_gripper, step_is_idle
from aerodock.world.imu import imu_coeffs, imu_step
from aerodock.world.params import WorldParams
from aerodock.world.platform import (
    any_above,
    cable_wrench_kernel,
    step_hanging_bar,
)
from aerodock.world.state import StepFrame, WorldState
from aerodock.world.term_kernels import (
    carry_captured,
    ground_kernel,
    hang_captured,
    rotor_fault_wrench,
)


# -- forces ----------------------------------------------------------------------------------
def wake_on_rotor_disks(state: WorldState, frame: StepFrame, params: WorldParams) -> None:
    """The leader's wake on a rigid follower's rotor disks: each disk takes the wake air it
    ingests, with its own (partly shared) turbulence, a force and a torque. A point mass takes
    the field's whole force (disks and body) at its centre here, and no torque. A field without
    ``wrench`` gives its whole force here. Random draws: the field's turbulence.

    A field with a ``wake_step`` (the default jet: :func:`~aerodock.downwash.wrench.wake_step`)
    gives a rigid follower's disks, body and bar their forces in that one call here, drawing the
    follower's turbulence, then the bar's, as the three terms would in turn; the body's and the
    bar's forces wait on the frame for their own terms below, which add them where they always
    did. It is made only when the step runs these three terms one after the other
    (``frame.wake_terms_together``, :mod:`aerodock.world.step`): a step of one's own that puts a
    term between them, or leaves one out, takes the three calls."""
    n = state.n
    if params.rigid:
        bar = state.bar
        parts = (wake_step(state.field, frame.lead, frame.fol, state.constants.rotor_offsets_m,
                           bar.p, bar.v, params.platform.bar_area_m2, params.dt_s,
                           frame.bar_axis_t.T) if frame.wake_terms_together else None)
        if parts is None:
            force, torque = follower_wrench(state.field, frame.lead, frame.fol,
                                            state.constants.rotor_offsets_m, params.dt_s)
        else:
            force, torque, frame.wake_body_n, frame.wake_bar_n = parts
        frame.wake_torque_nm = torque
        frame.torque_t[:, n:] += torque.T
    else:
        force = state.field.acceleration(frame.lead, frame.fol, params.dt_s)
        force *= frame.fol_mass_rows_kg
    frame.wake_force_n = force
    frame.force_n[n:] += force


def wake_on_body(state: WorldState, frame: StepFrame, params: WorldParams) -> None:
    """The leader's wake on a rigid follower's body (its drag, at the centre of mass), of the
    same step's turbulence (fields without a body force give none: their whole force is on the
    disks; a point mass took it with the disks'). No random draws."""
    n = state.n
    if frame.wake_body_n is not None:  # from the field's one call (wake_on_rotor_disks)
        force = frame.wake_body_n
    else:
        force = (follower_body_force_n(state.field, frame.lead, frame.fol) if params.rigid
                 else None)
    total = frame.wake_force_n
    if force is not None:
        frame.force_n[n:] += force
        total = total + force
    state.last_downwash_mps2 = total / frame.fol_mass_rows_kg


def wake_on_bar(state: WorldState, frame: StepFrame, params: WorldParams) -> None:
    """The wake's drag on the hanging bar (fields without a bar force give none). Random draws:
    the bar's turbulence, if the field has it (drawn by ``wake_on_rotor_disks`` with a field's
    ``wake_step``)."""
    if frame.wake_bar_n is not None:  # from the field's one call (wake_on_rotor_disks)
        force = frame.wake_bar_n
    else:
        bar = state.bar
        force = bar_wake_force_n(state.field, frame.lead, bar.p, bar.v,
                                 params.platform.bar_area_m2, params.dt_s, frame.bar_axis_t.T)
    if force is not None:
        frame.bar_force_n += force


def gripper_contact(state: WorldState, frame: StepFrame, params: WorldParams) -> None:
    """The bar against the gripper's contact arm: a spring-damper pushing the bar up the
    follower's axis and the follower down it (none once the bar is captured)."""
    n = state.n
    fol_p, fol_v, fol_R = frame.pos[n:], frame.vel[n:], frame.rot[n:]  # noqa: N806
    bar = state.bar
    contact, inside, up = contact_in_gripper(fol_p, fol_R, fol_v, bar.p, bar.v, bar.yaw_rad,
                                             params.gripper,
                                             cos_sin=(frame.bar_axis_t[0], frame.bar_axis_t[1]))
    if contact is None:  # no bar touches an arm: its zero push would change no number (the
        # accumulators, sums onto +0, hold no -0 for it to turn into +0)
        frame.contact_n, frame.inside = np.zeros(n), inside
        return
    # compiled: no push on a captured follower, the push on the follower and on the bar, and
    # contact_seen (the recorder flags the labels of a period with contact)
    contact_push(contact, up, frame.captured, frame.any_captured, state.contact_seen,
                 frame.force_n[n:], frame.bar_force_n)
    frame.contact_n, frame.inside = contact, inside


def cable_on_leader(state: WorldState, frame: StepFrame, params: WorldParams) -> None:
    """The cables pull the leader at their anchor, below its centre of mass (last step's
    tension: the bar moves after the vehicles). Compiled (:func:`~aerodock.world.platform.
    cable_wrench_kernel`: NumPy's ``force[:n] += cable`` and, for rigid bodies, the cable's
    moment about the centre of mass from ``cable^T R`` in ``np.matmul``'s rounding on the
    machine at hand)."""
    torque = frame.torque_t
    cable_wrench_kernel(state.cable_force_n, frame.rot, params.platform.anchor_below_leader_m,
                        frame.force_n, _NO_TORQUE if torque is None else torque,
                        torque is not None)


def rotor_faults(state: WorldState, frame: StepFrame, params: WorldParams) -> None:
    """An injected loss of the follower's rotor thrust (rigid bodies): the thrust its faulty
    rotors do not give, as a force and a torque; the autopilot is not told."""
    if state.rotor_loss is None:
        return
    fleet, both = params.follower_fleet.params, frame.both
    if state.rotor_loss.shape[1] >= 8:  # NumPy sums eight or more numbers pairwise
        raise ValueError("rotor faults: at most seven rotors")
    n = state.n
    rotor_fault_wrench(both.rotor_speed[n:], fleet.thrust_coeff, both.thrust_gain[n:],
                       np.asarray(state.rotor_loss, dtype=float), frame.rot[n:],
                       fleet.rotor_torque_map, frame.force_n[n:], frame.torque_t[:, n:])


# -- motion ----------------------------------------------------------------------------------
def imu(state: WorldState, frame: StepFrame, params: WorldParams) -> None:
    """What the flight computers sense at the step's start: the gyros' noise and, with the
    filtered chain, each IMU's samples (range, low-pass, latency) and the attitude estimate from
    them (:mod:`aerodock.world.imu`, :mod:`aerodock.world.attitude_estimator`; one compiled
    call, :func:`~aerodock.world.imu.imu_step`). Random draws: the gyros' noise (per trial, the
    leader's then the follower's), then with the filtered chain the accelerometers' noise (the
    same order)."""
    n = state.n
    both = frame.both
    gyro_sd = params.imu.gyro_noise_radps if params.rigid else 0.0
    ims = state.imu
    gyro_draws = standard_normal_t(state.rng, n, 6) if gyro_sd else _NO_DRAWS
    if ims is None:
        if gyro_sd:
            noise = np.empty((3, 2 * n))  # component-major: both halves are contiguous rows
            np.multiply(gyro_draws.reshape(2, 3, n), gyro_sd, out=_halves(noise, n))
            frame.gyro_noise_radps = noise.T
        return
    # The specific force's noise is drawn after the gyros' (both drawn before the kernel).
    accel_draws = standard_normal_t(state.rng, n, 6)
    m = 2 * n
    noise = np.empty((3, m)) if gyro_sd else _NO_DRAWS  # (untouched without gyro noise)
    gyro_t, accel_t, attitude = np.empty((3, m)), np.empty((3, m)), np.empty((m, 3, 3))
    # The heading the external source reports: the motion capture's, as late.
    latency = params.latency_steps
    att = state.history[(state.step_index - latency) % (latency + 1)]
    chain, estimator, vehicle = params.imu.chain, params.imu.estimator, params.vehicle
    gyro, accel = ims.gyro, ims.accel
    gyro_c, accel_c = imu_coeffs(ims)
    gyro.head, accel.head, ims.ring_head = imu_step(
        NUMPY_LOOPS, n, 0, n, both.w, gyro_draws, gyro_sd, chain.gyro_range_radps, gyro_c, gyro.z1,
        gyro.z2, gyro.delay, gyro.head, state.leader_accel, state.follower_accel,
        vehicle.gravity_mps2, frame.rot, ims.bias_body_mps2, both.thrust_n,
        state.constants.hover_thrust_n, vehicle.accel_noise_mps2 ** 2,
        params.imu.accel_vibration_mps2, accel_draws, chain.accel_range_mps2, accel_c,
        accel.z1, accel.z2, accel.delay, accel.head, ims.accel_ring, ims.ring_head,
        state.step_index, params.substeps, ims.nav_accel_mps2, att[2], att[5], ims.attitude,
        estimator.accel_gain_radps, estimator.heading_gain_radps, params.dt_s, noise, gyro_t,
        accel_t, attitude)
    if gyro_sd:
        frame.gyro_noise_radps = noise.T
    ims.accel_t, ims.attitude, ims.gyro_radps = accel_t, attitude, gyro_t.T
    frame.gyro_radps, frame.attitude_est = ims.gyro_radps, attitude


_NO_DRAWS = np.zeros((6, 0))


def vehicles(state: WorldState, frame: StepFrame, params: WorldParams) -> None:
    """Both vehicles under the forces and torques so far: autopilots on what their IMUs tell
    them, rotors, rigid bodies (or point masses); a leader on its stand stays put at hover
    thrust."""
    n = state.n
    both = frame.both
    if state.torque_log is not None:  # only when a flight log reads the torques
        noise = (frame.gyro_noise_radps if frame.gyro_radps is None
                 else frame.gyro_radps - both.w)  # the gyro the follower logs
        state.torque_log.add_step(both.w[n:], None if noise is None else noise[n:],
                                  both.rotor_speed[n:], frame.vel[n:], frame.rot[n:],
                                  frame.wake_torque_nm)
    torque = None if frame.torque_t is None else frame.torque_t.T
    sensed = None if frame.attitude_est is None else (frame.gyro_radps, frame.attitude_est)
    new, accel = params.fleet.step(both, frame.targets, frame.force_n, torque, params.dt_s,
                                   frame.gyro_noise_radps, sensed)
    if state.leader_fixed:  # on its stand: no motion, hover thrust
        new = params.fleet.hovering(new, both, slice(None, n))
        accel[:n] = 0.0
    frame.new, frame.accel = new, accel


def hanging_pair(state: WorldState, frame: StepFrame, params: WorldParams) -> None:
    """The bar on its cables below the leader's new anchor, with a captured follower hanging
    from it: the follower's own forces go to the hanging mass, and it is carried with the bar.
    The anchors and the rigid leader's yaw are computed in the bar's compiled step
    (:func:`~aerodock.world.platform.step_hanging_bar`)."""
    n, dt = state.n, params.dt_s
    new, platform, consts = frame.new, params.platform, state.constants
    accel = frame.accel
    if frame.any_captured:  # the captured followers' own forces go to the hanging mass
        hang_mass = np.empty(n)
        hang_captured(frame.captured, platform.bar_mass_kg, frame.mass_kg[n:], accel[n:],
                      consts.gravity_mps2, frame.fol_mass_rows_kg, frame.bar_force_n,
                      hang_mass)
    else:
        hang_mass = consts.bar_mass_kg
    state.bar, state.cable_force_n = step_hanging_bar(
        state.bar, frame.pos, frame.vel, accel, frame.rot, new.p,
        None if params.rigid else frame.both.rpy[:n, 2], frame.bar_force_n, hang_mass,
        platform, dt,
    )
    if frame.any_captured:  # carried with the bar
        gp = params.gripper
        carry_captured(frame.captured, state.bar.p, state.bar.v, new.R[n:], new.p[n:],
                       new.v[n:], frame.vel[n:], accel[n:], gp.mount_height_m + gp.bar_radius_m,
                       dt)


def ground(state: WorldState, frame: StepFrame, params: WorldParams) -> None:
    """The ground (z = 0, NED): a vehicle that reaches it stops there, and the trial is flagged."""
    new = frame.new
    if any_above(new.p, 0.0):  # some z above 0 (NaN aside): compiled, as the period's
        ground_kernel(new.p, new.v, state.ground_contact, 0, state.n)


def commit(state: WorldState, frame: StepFrame, params: WorldParams) -> None:
    """The new vehicles become the state and the clock advances: terms after this one see the
    time at the end of the step."""
    n = state.n
    state.both = frame.new
    state.leader_accel, state.follower_accel = frame.accel[:n], frame.accel[n:]
    state.step_index += 1
    state.t_s = state.step_index * params.dt_s


# -- sensing ---------------------------------------------------------------------------------
def gripper(state: WorldState, frame: StepFrame, params: WorldParams) -> None:
    """The gripper at the step's end time: the strain gauge sampled at its own rate, the triggers,
    the servo's latency and travel, the gate. Random draws: the strain gauge's noise."""
    gp, t, dt = params.gripper, state.t_s, params.dt_s
    sample = int(t * gp.sensor_rate_hz + 1e-9) != int((t - dt) * gp.sensor_rate_hz + 1e-9)
    if step_is_idle(state.gripper_flags()[2], sample, frame.close_command, gp):
        return  # no trigger can fire and no servo is waiting or closing: nothing changes
    state.gripper = step_gripper(state.gripper, t, frame.contact_n, frame.inside, sample,
                                 frame.close_command, gp, state.rng)
    if sample:  # what the follower knows of a touch (its labels' mask)
        state.contact_sensed |= state.gripper.reading_n > gp.contact_threshold_n


def motion_capture(state: WorldState, frame: StepFrame, params: WorldParams) -> None:
    """Keep the step's true state for motion capture, which reports it ``latency_steps`` late."""
    state.history[state.step_index % (params.latency_steps + 1)] = snapshot(state, params)


def snapshot(state: WorldState, params: WorldParams) -> tuple[np.ndarray, ...]:
    """(leader p, v, attitude, follower p, v, attitude) now: the rotation of a rigid body (angles
    are computed when observed), the Euler angles of a point mass."""
    both, n = state.both, state.n
    att = both.R if params.rigid else both.rpy
    return both.p[:n], both.v[:n], att[:n], both.p[n:], both.v[n:], att[n:]


def _halves(rows: np.ndarray, n: int) -> np.ndarray:
    """A component-major (3, 2n) array as (2, 3, n) (leaders, followers; a view): the layout of a
    (6, n) draw of the leaders' three numbers, then the followers'."""
    return rows.reshape(3, 2, n).transpose(1, 0, 2)


# cable_wrench_kernel's placeholder for a point mass's torques (writable: the kernel's type for
# the accumulator it writes; empty, so nothing can be written into it)
_NO_TORQUE = np.zeros((3, 0))
