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
was *received* on the node's monotonic clock: staleness is judged on receive times, which do
not depend on the sender's clock being in step with the node's.

The rule for stale or missing inputs (:func:`prediction_step`): if either vehicle's newest state
is older than ``max_age_s`` (or missing, or not finite), the node publishes **zero** and sets the
stale flag. It never repeats an old prediction.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from aerodock.geometry import euler_to_rotmat, quat_to_rotmat
from aerodock.ingest.common import ENU_TO_NED, FLIP_YZ

ODOMETRY = "nav_msgs/msg/Odometry"
CURRENT_STATE = "freyja_msgs/msg/CurrentState"
PX4_ODOMETRY = "px4_msgs/msg/VehicleOdometry"
STATE_TYPES = (ODOMETRY, CURRENT_STATE, PX4_ODOMETRY)
# px4_msgs VehicleOdometry velocity_frame values
PX4_VELOCITY_NED, PX4_VELOCITY_FRD, PX4_VELOCITY_BODY_FRD = 1, 2, 3

DEFAULT_RATE_HZ = 100.0
DEFAULT_MAX_AGE_S = 0.05


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
    """

    p_m: np.ndarray
    v_mps: np.ndarray
    R: np.ndarray
    received_s: float
    stamp_s: float | None = None

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
    rot_src = quat_to_rotmat(np.asarray(quat_wxyz, dtype=float))
    lin = np.asarray(linear, dtype=float)
    if twist == "body":
        lin = rot_src @ lin
    elif twist != "world":
        raise ValueError(f"twist {twist!r}: use 'body' or 'world'")
    return VehicleState(world @ np.asarray(position, dtype=float), world @ lin,
                        world @ rot_src @ body.T, received_s, stamp_s)


def current_state(state_vector: Sequence[float], *, received_s: float,
                  stamp_s: float | None = None) -> VehicleState:
    """A Freyja ``CurrentState``'s ``state_vector`` (pn, pe, pd, vn, ve, vd, roll, pitch, yaw)."""
    sv = np.asarray(state_vector, dtype=float)
    if sv.shape[0] < 9:
        raise ValueError(f"state_vector has {sv.shape[0]} values, expected at least 9")
    return VehicleState(sv[0:3].copy(), sv[3:6].copy(), euler_to_rotmat(sv[6], sv[7], sv[8]),
                        received_s, stamp_s)


def px4_odometry_state(position: Sequence[float], q_wxyz: Sequence[float],
                       velocity: Sequence[float], velocity_frame: int, *, received_s: float,
                       timestamp_us: int | None = None) -> VehicleState:
    """A ``px4_msgs/VehicleOdometry`` (NED position, FRD-to-NED ``q``) as a :class:`VehicleState`.

    Raises:
        ValueError: a ``velocity_frame`` other than NED (1), FRD (2) or body FRD (3).
    """
    rot = quat_to_rotmat(np.asarray(q_wxyz, dtype=float))
    vel = np.asarray(velocity, dtype=float)
    if velocity_frame == PX4_VELOCITY_BODY_FRD:
        vel = rot @ vel
    elif velocity_frame not in (PX4_VELOCITY_NED, PX4_VELOCITY_FRD):
        raise ValueError(f"VehicleOdometry velocity_frame {velocity_frame}: unknown frame")
    stamp = None if timestamp_us is None else timestamp_us * 1e-6
    return VehicleState(np.asarray(position, dtype=float), vel, rot, received_s, stamp)


def input_age_s(state: VehicleState | None, now_s: float) -> float:
    """Seconds since ``state`` was received (``inf`` when there is none)."""
    return math.inf if state is None else max(now_s - state.received_s, 0.0)


def is_stale(leader: VehicleState | None, follower: VehicleState | None, now_s: float,
             max_age_s: float) -> bool:
    """True when either state is missing, older than ``max_age_s`` or not finite."""
    for state in (leader, follower):
        if state is None or input_age_s(state, now_s) > max_age_s or not state.is_finite():
            return True
    return False


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
    """

    f_ext_mps2: np.ndarray
    stale: bool
    leader_age_s: float
    follower_age_s: float
    compute_s: float
    leader_stamp_s: float | None
    follower_stamp_s: float | None


def prediction_step(predictor: Any, leader: VehicleState | None,
                    follower: VehicleState | None, now_s: float, *, max_age_s: float,
                    output_frame: str = "ned", clock: Any = None,
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
        wake_scales: (3,) a leader-aware model's wake scales (leader_vh_mps, leader_size_m,
            follower_vh_mps; :func:`aerodock.learning.features.wake_scales`). The state
            messages carry no thrust, so the node passes None: the model file's recorded
            training scales (``Predictor.default_wake_scales``). Ignored by other kinds, which
            run exactly as before.

    A prediction that is not finite is also replaced by zero and flagged stale.
    """
    import time

    clock = clock or time.perf_counter
    ages = input_age_s(leader, now_s), input_age_s(follower, now_s)
    stamps = (None if leader is None else leader.stamp_s,
              None if follower is None else follower.stamp_s)
    if is_stale(leader, follower, now_s, max_age_s):
        return StepResult(np.zeros(3), True, *ages, 0.0, *stamps)
    assert leader is not None and follower is not None
    x, rot = model_inputs(leader, follower)
    t0 = clock()
    if getattr(predictor, "needs_wake_scales", False):
        f_ned = predictor.predict_one(x, rot, wake_scales)
    else:
        f_ned = predictor.predict_one(x, rot)
    compute = clock() - t0
    if not np.all(np.isfinite(f_ned)):
        return StepResult(np.zeros(3), True, *ages, compute, *stamps)
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
