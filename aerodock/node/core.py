"""The ROS-free part of ``aerodock node``: message fields to NED states, staleness, one step.

State messages (picked by the topic mapping of :mod:`aerodock.ingest.rosbag`, the type found on
the ROS graph or in the bag):

- ``nav_msgs/msg/Odometry``: ``frame = "enu"`` (REP-103: ENU world, FLU body) or ``"ned"``;
  the twist is in the body frame (``odom_twist = "body"``, REP-105) or the world frame.
- ``freyja_msgs/msg/CurrentState``: ``state_vector`` = pn, pe, pd, vn, ve, vd, roll, pitch,
  yaw (NED by definition).
- ``px4_msgs/msg/VehicleOdometry``: ``position`` and ``q`` (FRD to NED, w first) in NED,
  ``velocity`` in the frame ``velocity_frame`` names (1 NED, 2 FRD world, 3 body FRD).

Every state becomes a :class:`VehicleState` (NED world, FRD body, SI) stamped with the time it
was *received* on the node's monotonic clock, and keeps the message's own stamp. Age is judged
on receive times (they do not depend on the sender's clock being in step with the node's);
whether the data is new is judged on the data itself:

- :class:`InputMonitor` (one per vehicle) compares each message with the one before it: a
  stamp of zero, a stamp that goes backwards, a stamp that does not move (frozen) and a message
  identical to the previous one (a relay repeating it, a stuck publisher) make that vehicle's
  input unusable until a good message arrives;
- :func:`stale_reasons` adds the stateless rules: missing, older than ``max_age_s``, not finite,
  beyond the plausible range (:data:`MAX_POSITION_M`, :data:`MAX_SPEED_MPS`), or an attitude
  that is no rotation: a quaternion whose norm is not 1 within :data:`QUAT_NORM_TOLERANCE`
  (zero, not finite, or overflowing like (1e200, 1e200, 0, 0)), an Euler angle beyond
  :data:`MAX_ANGLE_RAD` (:func:`quaternion_attitude`, :func:`euler_attitude`);
- :class:`aerodock.node.refusals.RefusalLog` keeps the node's account of refused messages
  bounded: counts per kind of reason and the last few reasons word for word.

The rule for unusable inputs (:func:`prediction_step`): the node publishes **zero**, sets the
stale flag and says why (``StepResult.reason``, the diagnostics' ``stale_reason``). It never
repeats an old prediction. The converters raise no NumPy warnings for NaN, zero or overflowing
quaternions: such a state carries the converter's reason (``VehicleState.fault``), hence stale.

The output frame (:func:`output_frame_choice`) follows the follower's state type, once it is
known: ``nav_msgs/Odometry`` in the mapping's frame (ENU unless the mapping says ``"ned"``:
REP 103), Freyja's and PX4's states in NED. The model works in NED; the node converts once, at
its boundary.

When the node publishes (:class:`PublishMode`, :func:`output_trigger`): on each follower state
message (the prediction is for that state, out as soon as it is in), with the fixed-rate timer
as a watchdog that publishes only when no message-triggered output went out within the last
period and a half (:data:`WATCHDOG_PERIODS`); or on the timer alone. Every output, whatever
triggered it, is one :func:`prediction_step` on the newest states.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

import numpy as np

from aerodock.geometry import euler_to_rotmat, quat_to_rotmat
from aerodock.ingest.common import ENU_TO_NED, FLIP_YZ
from aerodock.learning.features import GRAVITY_MPS2, N_WAKE_SCALES, wake_scales

ODOMETRY = "nav_msgs/msg/Odometry"
CURRENT_STATE = "freyja_msgs/msg/CurrentState"
PX4_ODOMETRY = "px4_msgs/msg/VehicleOdometry"
STATE_TYPES = (ODOMETRY, CURRENT_STATE, PX4_ODOMETRY)
# px4_msgs VehicleOdometry velocity_frame values
PX4_VELOCITY_NED, PX4_VELOCITY_FRD, PX4_VELOCITY_BODY_FRD = 1, 2, 3

DEFAULT_RATE_HZ = 100.0
DEFAULT_MAX_AGE_S = 0.05


class PublishMode(StrEnum):
    """What makes the node publish f_ext.

    - ``on-follower``: each follower state message (the follower's state is what the
      prediction is for), with the ``rate_hz`` timer as a watchdog: a tick publishes only when
      no message-triggered output went out within the last :data:`WATCHDOG_PERIODS` periods,
      so a consumer still gets output at ``rate_hz`` when the follower's messages stop.
    - ``timer``: the ``rate_hz`` timer alone, from the newest states (the wait for the next
      tick, up to one period, adds to the latency).
    """

    ON_FOLLOWER = "on-follower"
    TIMER = "timer"


DEFAULT_PUBLISH_MODE = PublishMode.ON_FOLLOWER
"""A controller (Freyja's LQR, a PX4 offboard loop) acts on the follower's state as it arrives:
the f_ext for that state is wanted then, not up to a timer period later (docs/deploy.md)."""

WATCHDOG_PERIODS = 1.5
"""How many timer periods without a message-triggered output make a tick publish
(``on-follower``). More than one: the follower's messages usually come at about the timer's
rate, and with the strict one period a message a little late (jitter of a fraction of a
millisecond) made the tick publish a duplicate of the last answer just before the message's
own: a quarter of all outputs at 100 Hz on a loaded machine (docs/deploy.md). Half a period
more leaves those out and still publishes within two and a half periods of the last answer,
then once per period."""

FOLLOWER_EVENT, TICK_EVENT = "follower message", "tick"
"""The events the node sees: a follower state message arrived; the ``rate_hz`` timer fired."""
TRIGGER_FOLLOWER, TRIGGER_TIMER, TRIGGER_WATCHDOG = "follower", "timer", "watchdog"
"""What made an output (the diagnostics' ``trigger``): a follower message (``on-follower``), a
tick (``timer``), a tick with no message-triggered output within the last
:data:`WATCHDOG_PERIODS` periods (``on-follower``'s watchdog)."""


def output_trigger(mode: PublishMode | str, event: str, now_s: float,
                   last_follower_output_s: float | None, period_s: float) -> str | None:
    """Whether ``event`` makes an output, and what the diagnostics call its trigger.

    Args:
        mode: the node's :class:`PublishMode`.
        event: :data:`FOLLOWER_EVENT` or :data:`TICK_EVENT`.
        now_s: the node's monotonic time of the event, s.
        last_follower_output_s: when the last follower-triggered output went out (None: none
            yet), s, same clock.
        period_s: the timer's period, ``1 / rate_hz``, s.

    Returns:
        :data:`TRIGGER_FOLLOWER`, :data:`TRIGGER_TIMER` or :data:`TRIGGER_WATCHDOG`, or None
        (no output). In ``on-follower`` mode the watchdog's own outputs do not count as recent
        ones: once the follower's messages stop, every tick publishes (the first within
        :data:`WATCHDOG_PERIODS` + 1 periods of the last message-triggered output, the timer's
        phase being free).

    Raises:
        ValueError: an unknown mode or event.
    """
    mode = PublishMode(mode)
    if event not in (FOLLOWER_EVENT, TICK_EVENT):
        raise ValueError(f"event {event!r}: use {FOLLOWER_EVENT!r} or {TICK_EVENT!r}")
    if mode is PublishMode.TIMER:
        return TRIGGER_TIMER if event == TICK_EVENT else None
    if event == FOLLOWER_EVENT:
        return TRIGGER_FOLLOWER
    if (last_follower_output_s is None
            or now_s - last_follower_output_s >= WATCHDOG_PERIODS * period_s):
        return TRIGGER_WATCHDOG
    return None

MAX_POSITION_M = 1.0e4
"""Largest accepted |coordinate| of a position, m. A docking happens within a few metres of a
local (motion-capture or EKF) origin; 10 km is far beyond any such volume yet well below where
float64 differences of positions lose centimetres (1e4 m keeps ~1e-12 m resolution). A larger
value is a units, frame or origin error (or a garbage 1e300), not a vehicle."""
MAX_SPEED_MPS = 100.0
"""Largest accepted |component| of a velocity, m/s: about 4 times the fastest multirotor this
model is meant for and 100 times a docking approach; faster is a units error or garbage, and
the model was never trained anywhere near it."""

QUAT_NORM_TOLERANCE = 0.01
"""Largest accepted ``| |q| - 1 |`` of a message's attitude quaternion. Senders publish unit
quaternions (rounding leaves ~1e-7 in float32, as PX4's ``q``); a norm off by more than 1 % is
not a rotation anyone meant: zero, garbage, or a norm that overflows (1e200, 1e200, 0, 0),
which a plain normalisation read as level."""
MAX_ANGLE_RAD = 2.0 * math.pi
"""Largest accepted |roll|, |pitch|, |yaw| of Freyja's ``state_vector``, rad: one full turn.
Estimators publish wrapped angles (within [-pi, pi], or [0, 2 pi)); beyond a turn is degrees
sent as radians, or garbage (a roll of 1e300 rad has a sine, but not a meaningful one)."""

_QUIET = {"divide": "ignore", "invalid": "ignore", "over": "ignore"}
"""``np.errstate`` settings of the converters: a NaN, zero or overflowing attitude gives a state
that carries its reason (stale), not a NumPy warning on stderr."""
_NAN_ROTATION = np.full((3, 3), np.nan)


def quaternion_attitude(quat_wxyz: Sequence[float]) -> tuple[np.ndarray, str | None]:
    """A message's quaternion (w, x, y, z) as a rotation matrix, or why it is none.

    The norm is taken of the quaternion scaled by its largest component (no overflow for
    1e200, no underflow for 1e-200); a quaternion that is not finite, zero, or whose norm is
    not 1 within :data:`QUAT_NORM_TOLERANCE` is refused.

    Returns:
        ``(R, None)`` with ``R`` (3, 3) from the normalised quaternion, or ``(NaN (3, 3),
        reason)``.
    """
    q = np.asarray(quat_wxyz, dtype=float).reshape(4)
    if not np.isfinite(q).all():
        return _NAN_ROTATION.copy(), "attitude quaternion not finite"
    scale = float(np.abs(q).max())
    if scale == 0.0:
        return _NAN_ROTATION.copy(), "attitude quaternion is zero"
    with np.errstate(**_QUIET):
        norm = scale * float(np.linalg.norm(q / scale))  # inf when it overflows
    if not abs(norm - 1.0) <= QUAT_NORM_TOLERANCE:
        return _NAN_ROTATION.copy(), (f"attitude quaternion norm {norm:.3g}, not 1 "
                                      f"(tolerance {QUAT_NORM_TOLERANCE:g})")
    return quat_to_rotmat(q / norm), None


def euler_attitude(roll_rad: float, pitch_rad: float, yaw_rad: float
                   ) -> tuple[np.ndarray, str | None]:
    """ZYX Euler angles as a rotation matrix, or why they are none (not finite, or beyond
    :data:`MAX_ANGLE_RAD`): ``(R, None)`` or ``(NaN (3, 3), reason)``."""
    for name, angle in (("roll", roll_rad), ("pitch", pitch_rad), ("yaw", yaw_rad)):
        value = float(angle)
        if not math.isfinite(value):
            return _NAN_ROTATION.copy(), f"{name} not finite"
        if abs(value) > MAX_ANGLE_RAD:
            return _NAN_ROTATION.copy(), (f"{name} {value:.3g} rad beyond "
                                          f"{MAX_ANGLE_RAD:.3g} rad (one turn)")
    return euler_to_rotmat(float(roll_rad), float(pitch_rad), float(yaw_rad)), None


@dataclass(frozen=True)
class VehicleState:
    """One vehicle's state: NED world, FRD body, SI.

    Attributes:
        p_m: position (3,).
        v_mps: velocity (3,).
        R: attitude, body FRD to world NED (3, 3).
        received_s: when the node received it (its monotonic clock), s.
        stamp_s: the message's own stamp, s (``header.stamp``, or PX4's µs since boot), or
            None when it has none.
        fault: why the message's own data is no state, found by its converter (an attitude
            that is no rotation: :func:`quaternion_attitude`, :func:`euler_attitude`; ``R``
            is then NaN), or None.
    """

    p_m: np.ndarray
    v_mps: np.ndarray
    R: np.ndarray
    received_s: float
    stamp_s: float | None = None
    fault: str | None = None

    def is_finite(self) -> bool:
        """True when position, velocity and attitude are all finite."""
        return bool(np.isfinite(self.p_m).all() and np.isfinite(self.v_mps).all()
                    and np.isfinite(self.R).all())


def frames_for(frame: str) -> tuple[np.ndarray, np.ndarray]:
    """``(world, body)`` maps to NED and FRD for a mapping ``frame`` (``"enu"`` or ``"ned"``)."""
    if frame == "enu":
        return ENU_TO_NED, FLIP_YZ
    if frame == "ned":
        return np.eye(3), np.eye(3)
    raise ValueError(f"frame {frame!r}: use 'enu' or 'ned'")


def odometry_state(position: Sequence[float], quat_wxyz: Sequence[float],
                   linear: Sequence[float], *, frame: str, twist: str,
                   received_s: float, stamp_s: float | None = None) -> VehicleState:
    """A ``nav_msgs/Odometry``'s pose and linear twist as a NED :class:`VehicleState`.

    Args:
        position: ``pose.pose.position`` (x, y, z) in the mapping's world frame.
        quat_wxyz: ``pose.pose.orientation`` as (w, x, y, z), body to world.
        linear: ``twist.twist.linear``: in the body frame (``twist="body"``, REP-105) or the
            world frame (``twist="world"``).
        frame: ``"enu"`` (REP-103: ENU world, FLU body) or ``"ned"`` (NED world, FRD body).
        twist: ``"body"`` or ``"world"``.
        received_s: receive time on the node's clock, s.
        stamp_s: ``header.stamp`` in s.
    """
    world, body = frames_for(frame)
    if twist not in ("body", "world"):
        raise ValueError(f"twist {twist!r}: use 'body' or 'world'")
    rot_src, fault = quaternion_attitude(quat_wxyz)
    with np.errstate(**_QUIET):
        lin = np.asarray(linear, dtype=float)
        if twist == "body":
            lin = rot_src @ lin
        return VehicleState(world @ np.asarray(position, dtype=float), world @ lin,
                            world @ rot_src @ body.T, received_s, stamp_s, fault)


def current_state(state_vector: Sequence[float], *, received_s: float,
                  stamp_s: float | None = None) -> VehicleState:
    """A Freyja ``CurrentState``'s ``state_vector`` (pn, pe, pd, vn, ve, vd, roll, pitch, yaw)."""
    sv = np.asarray(state_vector, dtype=float)
    if sv.shape[0] < 9:
        raise ValueError(f"state_vector has {sv.shape[0]} values, expected at least 9")
    rot, fault = euler_attitude(sv[6], sv[7], sv[8])
    return VehicleState(sv[0:3].copy(), sv[3:6].copy(), rot, received_s, stamp_s, fault)


def px4_odometry_state(position: Sequence[float], q_wxyz: Sequence[float],
                       velocity: Sequence[float], velocity_frame: int, *, received_s: float,
                       timestamp_us: int | None = None) -> VehicleState:
    """A ``px4_msgs/VehicleOdometry`` (NED position, FRD-to-NED ``q``) as a :class:`VehicleState`.

    Raises:
        ValueError: a ``velocity_frame`` other than NED (1), FRD (2) or body FRD (3).
    """
    if velocity_frame not in (PX4_VELOCITY_NED, PX4_VELOCITY_FRD, PX4_VELOCITY_BODY_FRD):
        raise ValueError(f"VehicleOdometry velocity_frame {velocity_frame}: unknown frame")
    rot, fault = quaternion_attitude(q_wxyz)
    with np.errstate(**_QUIET):
        vel = np.asarray(velocity, dtype=float)
        if velocity_frame == PX4_VELOCITY_BODY_FRD:
            vel = rot @ vel
    stamp = None if timestamp_us is None else timestamp_us * 1e-6
    return VehicleState(np.asarray(position, dtype=float), vel, rot, received_s, stamp, fault)


def input_age_s(state: VehicleState | None, now_s: float) -> float:
    """Seconds since ``state`` was received (``inf`` when there is none)."""
    return math.inf if state is None else max(now_s - state.received_s, 0.0)


def implausible(state: VehicleState) -> str | None:
    """Why ``state``'s data cannot be a vehicle's, or None: the converter's ``fault`` first (an
    attitude that is no rotation; a body-frame velocity turned by it is NaN too), then values
    not finite, then a position or velocity out of range.

    Components are compared, not norms: a norm of 1e300 would overflow (and warn).
    """
    if state.fault:
        return state.fault
    if not state.is_finite():
        return "not finite"
    p_max, v_max = float(np.abs(state.p_m).max()), float(np.abs(state.v_mps).max())
    if p_max > MAX_POSITION_M:
        return f"position {p_max:.3g} m beyond {MAX_POSITION_M:g} m"
    if v_max > MAX_SPEED_MPS:
        return f"velocity {v_max:.3g} m/s beyond {MAX_SPEED_MPS:g} m/s"
    return None


class InputMonitor:
    """Judges one vehicle's messages by their data: is each newer than the one before it?

    :meth:`receive` compares a state with the previous one received (accepted or not):

    - a stamp of exactly zero (an unset ``header.stamp``, PX4's ``timestamp`` 0);
    - a stamp earlier than the previous one (``went backwards``);
    - the same stamp as the previous one with other values (``frozen``);
    - the same stamp and the same position, velocity and attitude, bit for bit (``repeated``:
      a relay or bridge re-sending one message, a stuck publisher). Without stamps, identical
      values alone: a real estimator's velocity never repeats to the last bit.

    Each verdict holds until the next message: one bad message makes the vehicle's input unusable
    (zero output, stale) until a good one arrives. The comparison is with the *previous* message,
    so after a sender restart (stamps jump back once) the next message is accepted again.
    """

    def __init__(self) -> None:
        self.previous: VehicleState | None = None
        self.verdict: str | None = None

    def receive(self, state: VehicleState) -> str | None:
        """Record ``state``; why it is unusable (see the class), or None when it is fine."""
        prev, self.previous = self.previous, state
        self.verdict = sequence_fault(prev, state)
        return self.verdict


def sequence_fault(prev: VehicleState | None, state: VehicleState) -> str | None:
    """The :class:`InputMonitor` rule for ``state`` following ``prev`` (None: first message)."""
    stamp = state.stamp_s
    if stamp is not None and stamp == 0.0:
        return "stamp is zero"
    if prev is None:
        return None
    same_values = (np.array_equal(state.p_m, prev.p_m) and np.array_equal(state.v_mps, prev.v_mps)
                   and np.array_equal(state.R, prev.R))
    if stamp is None or prev.stamp_s is None:
        return "repeated message (same values)" if same_values else None
    if stamp == prev.stamp_s:
        if same_values:
            return f"repeated message (stamp {stamp!r} and values unchanged)"
        return f"stamp frozen at {stamp!r}"
    if stamp < prev.stamp_s:
        return f"stamp went backwards ({prev.stamp_s!r} -> {stamp!r})"
    return None


def stale_reasons(leader: VehicleState | None, follower: VehicleState | None, now_s: float,
                  max_age_s: float, faults: Mapping[str, str | None] | None = None) -> list[str]:
    """Why the inputs cannot be used (empty: they can), one ``"role: why"`` per problem.

    Args:
        leader: newest leader state (None: none yet).
        follower: newest follower state.
        now_s: the node's monotonic time, s.
        max_age_s: the oldest accepted input, s.
        faults: role -> the :class:`InputMonitor` verdict on its newest message.
    """
    reasons = []
    for role, state in (("leader", leader), ("follower", follower)):
        if state is None:
            reasons.append(f"{role}: missing")
            continue
        age = input_age_s(state, now_s)
        if age > max_age_s:
            reasons.append(f"{role}: {age * 1e3:.0f} ms old (max {max_age_s * 1e3:g} ms)")
        why = (faults or {}).get(role) or implausible(state)
        if why:
            reasons.append(f"{role}: {why}")
    return reasons


def is_stale(leader: VehicleState | None, follower: VehicleState | None, now_s: float,
             max_age_s: float) -> bool:
    """True when either state is missing, too old, not finite or implausible."""
    return bool(stale_reasons(leader, follower, now_s, max_age_s))


UNDECIDED = "undecided"
"""The diagnostics' ``output_frame`` before the follower's state type is known (no f_ext yet)."""


def output_frame_choice(requested: str | None, mapping_frame: str,
                        follower_type: str | None) -> tuple[str | None, str]:
    """The output world frame and the rule that chose it (the diagnostics' ``output_frame`` and
    ``output_frame_rule``).

    Args:
        requested: ``--output-frame`` (``"ned"``/``"enu"``), or None for automatic.
        mapping_frame: the mapping's ``frame`` (``"enu"`` unless the mapping file says ``"ned"``).
        follower_type: the follower's state type, None while it is not known (given by
            ``--state-type``, else found on the ROS graph).

    Automatic: ``nav_msgs/Odometry`` input gives the mapping's frame, ENU by default as ROS's
    REP 103 has it; Freyja's ``CurrentState`` and PX4's ``VehicleOdometry`` give NED, their
    world frame. While the follower's type is unknown the frame is None (undecided: the node
    publishes no f_ext then, so the frame it publishes in never changes).
    """
    if requested is not None:
        frames_for(requested)  # checks the name
        return requested, f"--output-frame {requested}"
    if follower_type is None:
        return None, "the follower's state type is not known yet (--state-type, or the ROS graph)"
    if follower_type == ODOMETRY:
        return mapping_frame, (f"{ODOMETRY} input: the mapping's frame ({mapping_frame}; "
                               "ENU unless the mapping sets frame = \"ned\", REP 103)")
    return "ned", f"{follower_type} input: NED, its world frame"


def model_inputs(leader: VehicleState, follower: VehicleState) -> tuple[np.ndarray, np.ndarray]:
    """The model's ``x = [p_B - p_A, v_A, v_B]`` (9,) and ``leader_R`` (3, 3)."""
    x = np.concatenate([follower.p_m - leader.p_m, leader.v_mps, follower.v_mps])
    return x, leader.R


def to_output_frame(f_ned_mps2: np.ndarray, frame: str) -> np.ndarray:
    """A NED world vector in the consumer's world frame (``"ned"``, or ``"enu"`` for REP-103)."""
    world, _ = frames_for(frame)
    return world.T @ np.asarray(f_ned_mps2, dtype=float)


@dataclass(frozen=True)
class StepResult:
    """One tick of the node.

    Attributes:
        f_ext_mps2: predicted f_ext in the output frame (zeros when stale), (3,).
        stale: inputs missing, too old or not finite (output is zero).
        leader_age_s: seconds since the leader's state was received (inf: never).
        follower_age_s: the follower's.
        compute_s: time spent in the predictor, s (0 when stale).
        leader_stamp_s: the leader state's own stamp (None: none or no state).
        follower_stamp_s: the follower state's.
        reason: why the output is stale (``"; "``-joined ``"role: why"``), ``""`` when fresh.
    """

    f_ext_mps2: np.ndarray
    stale: bool
    leader_age_s: float
    follower_age_s: float
    compute_s: float
    leader_stamp_s: float | None
    follower_stamp_s: float | None
    reason: str = ""


def configured_wake_scales(predictor: Any, leader: Any, follower: Any) -> np.ndarray | None:
    """A leader-aware model's wake scales (k,: the ones its kind reads) for the vehicles the node
    flies with, or None for other kinds.

    The state messages carry no thrust, so the leader's is its hover thrust (its weight): the
    scales are :func:`aerodock.learning.features.wake_scales` of the leader's weight and rotors
    and the follower's mass and rotors, as a simulated mission builds them for a hovering leader
    (:meth:`aerodock.learning.runtime.Predictor.wake_scales_for_bodies`).

    Args:
        predictor: the node's predictor (``needs_wake_scales`` says whether it is leader-aware).
        leader, follower: the vehicles' config sections (``mass_kg``, ``rotor_radius_m``,
            ``n_rotors``), e.g. ``cfg.leader`` and ``cfg.vehicle``.
    """
    if not getattr(predictor, "needs_wake_scales", False):
        return None
    return wake_scales(leader.mass_kg * GRAVITY_MPS2, leader.rotor_radius_m,
                       int(leader.n_rotors), follower.mass_kg, follower.rotor_radius_m,
                       int(follower.n_rotors))[0, :N_WAKE_SCALES[predictor.kind]]


def prediction_step(predictor: Any, leader: VehicleState | None,
                    follower: VehicleState | None, now_s: float, *, max_age_s: float,
                    output_frame: str = "ned", clock: Any = None,
                    faults: Mapping[str, str | None] | None = None,
                    wake_scales: np.ndarray | None = None) -> StepResult:
    """One tick: the prediction for the newest states, or zero (flagged stale).

    Args:
        predictor: a :class:`aerodock.learning.runtime.Predictor` (``predict_one``).
        leader: newest leader state (None: none yet).
        follower: newest follower state.
        now_s: the node's monotonic time, s.
        max_age_s: the oldest accepted input, s.
        output_frame: ``"ned"`` or ``"enu"``.
        clock: a ``() -> float`` seconds clock timing the prediction (default
            ``time.perf_counter``).
        faults: role -> the :class:`InputMonitor` verdict on its newest message (None: fine).
        wake_scales: (k,) a leader-aware model's wake scales (leader_vh_mps, leader_size_m,
            follower_vh_mps, and for ``so2-pair`` follower_size_m;
            :func:`aerodock.learning.features.wake_scales`): the flown
            vehicles' (:func:`configured_wake_scales`, from ``aerodock node --config``), or
            None: the model file's recorded training scales
            (``Predictor.default_wake_scales``). Ignored by other kinds, which run exactly as
            before.

    A prediction that is not finite is also replaced by zero and flagged stale.
    """
    import time

    clock = clock or time.perf_counter
    ages = input_age_s(leader, now_s), input_age_s(follower, now_s)
    stamps = (None if leader is None else leader.stamp_s,
              None if follower is None else follower.stamp_s)
    reasons = stale_reasons(leader, follower, now_s, max_age_s, faults)
    if reasons:
        return StepResult(np.zeros(3), True, *ages, 0.0, *stamps, "; ".join(reasons))
    assert leader is not None and follower is not None
    x, rot = model_inputs(leader, follower)
    t0 = clock()
    if getattr(predictor, "needs_wake_scales", False):
        f_ned = predictor.predict_one(x, rot, wake_scales)
    else:
        f_ned = predictor.predict_one(x, rot)
    compute = clock() - t0
    if not np.all(np.isfinite(f_ned)):
        return StepResult(np.zeros(3), True, *ages, compute, *stamps,
                          "prediction not finite")
    return StepResult(to_output_frame(f_ned, output_frame), False, *ages, compute, *stamps)


def odometry_fields(state: VehicleState, *, frame: str, twist: str
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The inverse of :func:`odometry_state`: ``(position, quat_wxyz, linear)`` of an Odometry.

    Used to replay a NED FlightLog as ``nav_msgs/Odometry`` messages in the mapping's frame.
    """
    from aerodock.geometry import rotmat_to_quat

    world, body = frames_for(frame)
    rot_src = world.T @ state.R @ body  # source body to source world
    lin = world.T @ state.v_mps
    if twist == "body":
        lin = rot_src.T @ lin
    return world.T @ state.p_m, rotmat_to_quat(rot_src), lin
