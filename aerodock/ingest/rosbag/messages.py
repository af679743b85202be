"""The ROS 2 message types the bag reader understands: definitions, numbers and meaning.

Message types understood (detected from the bag):

- state: ``freyja_msgs/msg/CurrentState`` (``state_vector`` = pn, pe, pd, vn, ve, vd, roll, pitch,
  yaw, ...), ``nav_msgs/msg/Odometry``, ``geometry_msgs/msg/PoseStamped`` or
  ``geometry_msgs/msg/PoseWithCovarianceStamped`` (velocity from ``twist`` if given, else the
  time derivative of the position);
- command, label basis ``"command"``: ``freyja_msgs/msg/ControllerDebug`` (``lqr_u[0:3]`` is
  ``u - g e3``, NED), ``geometry_msgs/msg/Vector3Stamped`` or ``geometry_msgs/msg/AccelStamped``
  (the commanded acceleration ``u_1:3``, zero at hover, world frame);
- attitude-thrust command: ``freyja_msgs/msg/CtrlCommand`` (roll, pitch in rad relative to the
  current heading, thrust in N), turned into ``u = g e3 - R(roll, pitch, yaw) e3 T / m`` with the
  follower's heading from its state: needs the follower mass;
- IMU: ``sensor_msgs/msg/Imu`` ``linear_acceleration`` (body specific force), rotated with the
  state's attitude: ``a = R f + g e3``.

- PX4 (``px4_msgs``, through the uXRCE-DDS bridge; NED world, FRD body by definition):
  ``px4_msgs/msg/VehicleOdometry`` as a state (``position``, ``q``, ``velocity`` in the frame
  ``velocity_frame`` names), ``px4_msgs/msg/VehicleThrustSetpoint`` as the command (``xyz``,
  normalised thrust in the body frame, turned into ``cmd = g e3 + R xyz g / hover_thrust``:
  needs ``hover_thrust`` in the role's table; label basis ``"thrust"``), and
  ``px4_msgs/msg/VehicleLocalPosition`` as the ``imu`` topic (``ax, ay, az``: NED, gravity
  removed). PX4's own ``timestamp`` counts from each vehicle's boot, so these messages are timed
  by the bag.

Freyja's and PX4's message definitions are built in (``px4_msgs`` as of PX4 1.15); a bag that
stores its own definitions (rosbag2 version 8+ and MCAP do) is read with those. Each message is
turned into a few numbers as soon as it is deserialised (:data:`EXTRACT`); the functions here
turn a topic's numbers into NED states, commands and accelerations.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from aerodock.geometry import (
    E3,
    GRAVITY_MPS2,
    euler_to_rotmat,
    quat_to_rotmat,
    rotmat_to_quat,
    specific_force_to_accel,
    thrust_accel,
)
from aerodock.ingest.common import (
    ENU_TO_NED,
    FLIP_YZ,
    IDENTITY,
    check_finite,
    check_kinematics,
    check_specific_force,
    check_upright,
    convert_rotations,
    convert_vectors,
    differentiate,
    resample_hold,
    resample_linear,
)
from aerodock.ingest.errors import IngestError, ingest_warning

# Freyja (github.com/unl-nimbus-lab/Freyja) message definitions, freyja_msgs.
FREYJA_MSGS: dict[str, str] = {
    "freyja_msgs/msg/CurrentState": (
        "std_msgs/Header header\nfloat64[13] state_vector\nuint8 state_valid\n"
    ),
    "freyja_msgs/msg/ReferenceState": (
        "std_msgs/Header header\nfloat64 pn\nfloat64 pe\nfloat64 pd\nfloat64 vn\nfloat64 ve\n"
        "float64 vd\nfloat64 yaw\nfloat64 an\nfloat64 ae\nfloat64 ad\n"
    ),
    "freyja_msgs/msg/CtrlCommand": (
        "float64 roll\nfloat64 pitch\nfloat64 yaw\nfloat64 thrust\nuint8 ctrl_mode\n"
    ),
    "freyja_msgs/msg/ControllerDebug": (
        "uint8 CTRL_OK=1\nuint8 BIAS_EN=2\nuint8 FLAT_FF=4\nuint8 MASS_CR=8\n"
        "std_msgs/Header header\nfloat32[4] lqr_u\nfloat32[4] biasv\nfloat32[7] errv\n"
        "uint8 flags\n"
    ),
}

# PX4 (github.com/PX4/px4_msgs, PX4 1.15) message definitions, px4_msgs. A bag that stores its
# own definitions is read with those instead.
PX4_MSGS: dict[str, str] = {
    "px4_msgs/msg/VehicleOdometry": (
        "uint64 timestamp\nuint64 timestamp_sample\n"
        "uint8 POSE_FRAME_UNKNOWN=0\nuint8 POSE_FRAME_NED=1\nuint8 POSE_FRAME_FRD=2\n"
        "uint8 pose_frame\nfloat32[3] position\nfloat32[4] q\n"
        "uint8 VELOCITY_FRAME_UNKNOWN=0\nuint8 VELOCITY_FRAME_NED=1\n"
        "uint8 VELOCITY_FRAME_FRD=2\nuint8 VELOCITY_FRAME_BODY_FRD=3\n"
        "uint8 velocity_frame\nfloat32[3] velocity\nfloat32[3] angular_velocity\n"
        "float32[3] position_variance\nfloat32[3] orientation_variance\n"
        "float32[3] velocity_variance\nuint8 reset_counter\nint8 quality\n"
    ),
    "px4_msgs/msg/VehicleThrustSetpoint": (
        "uint64 timestamp\nuint64 timestamp_sample\nfloat32[3] xyz\n"
    ),
    "px4_msgs/msg/VehicleLocalPosition": (
        "uint64 timestamp\nuint64 timestamp_sample\n"
        "bool xy_valid\nbool z_valid\nbool v_xy_valid\nbool v_z_valid\n"
        "float32 x\nfloat32 y\nfloat32 z\n"
        "float32[2] delta_xy\nuint8 xy_reset_counter\nfloat32 delta_z\nuint8 z_reset_counter\n"
        "float32 vx\nfloat32 vy\nfloat32 vz\nfloat32 z_deriv\n"
        "float32[2] delta_vxy\nuint8 vxy_reset_counter\nfloat32 delta_vz\n"
        "uint8 vz_reset_counter\n"
        "float32 ax\nfloat32 ay\nfloat32 az\n"
        "float32 heading\nfloat32 delta_heading\nuint8 heading_reset_counter\n"
        "bool heading_good_for_control\n"
        "bool xy_global\nbool z_global\nuint64 ref_timestamp\nfloat64 ref_lat\n"
        "float64 ref_lon\nfloat32 ref_alt\n"
        "float32 dist_bottom\nbool dist_bottom_valid\nuint8 dist_bottom_sensor_bitfield\n"
        "uint8 DIST_BOTTOM_SENSOR_NONE=0\nuint8 DIST_BOTTOM_SENSOR_RANGE=1\n"
        "uint8 DIST_BOTTOM_SENSOR_FLOW=2\n"
        "float32 eph\nfloat32 epv\nfloat32 evh\nfloat32 evv\n"
        "bool dead_reckoning\n"
        "float32 vxy_max\nfloat32 vz_max\nfloat32 hagl_min\nfloat32 hagl_max\n"
    ),
}
PX4_ODOMETRY = "px4_msgs/msg/VehicleOdometry"
PX4_THRUST = "px4_msgs/msg/VehicleThrustSetpoint"
PX4_LOCAL_POSITION = "px4_msgs/msg/VehicleLocalPosition"
REFERENCE_STATE = "freyja_msgs/msg/ReferenceState"

STATE_TYPES = (
    "freyja_msgs/msg/CurrentState", "nav_msgs/msg/Odometry", "geometry_msgs/msg/PoseStamped",
    "geometry_msgs/msg/PoseWithCovarianceStamped", PX4_ODOMETRY,
)
ACCEL_COMMAND_TYPES = (
    "freyja_msgs/msg/ControllerDebug", "geometry_msgs/msg/Vector3Stamped",
    "geometry_msgs/msg/AccelStamped",
)
ATTITUDE_THRUST_TYPES = ("freyja_msgs/msg/CtrlCommand",)
THRUST_SETPOINT_TYPES = (PX4_THRUST,)
IMU_TYPES = ("sensor_msgs/msg/Imu", PX4_LOCAL_POSITION)


def _xyz(v: Any) -> tuple[float, float, float]:
    return (v.x, v.y, v.z)


def _pose(p: Any) -> tuple[float, ...]:
    o = p.orientation
    return (*_xyz(p.position), o.w, o.x, o.y, o.z)


# Each type's numbers, taken from a message as soon as it is deserialised (the message object is
# dropped at once): position (3) + quaternion w, x, y, z (4) + velocity (3) for states, ...
EXTRACT: dict[str, Callable[[Any], tuple[float, ...]]] = {
    "freyja_msgs/msg/CurrentState": lambda m: tuple(float(v) for v in m.state_vector[:9]),
    "nav_msgs/msg/Odometry": lambda m: (*_pose(m.pose.pose), *_xyz(m.twist.twist.linear)),
    "geometry_msgs/msg/PoseStamped": lambda m: _pose(m.pose),
    "geometry_msgs/msg/PoseWithCovarianceStamped": lambda m: _pose(m.pose.pose),
    "geometry_msgs/msg/TwistStamped": lambda m: _xyz(m.twist.linear),
    "freyja_msgs/msg/ControllerDebug": lambda m: tuple(float(v) for v in m.lqr_u[:3]),
    "geometry_msgs/msg/Vector3Stamped": lambda m: _xyz(m.vector),
    "geometry_msgs/msg/AccelStamped": lambda m: _xyz(m.accel.linear),
    "freyja_msgs/msg/CtrlCommand": lambda m: (m.roll, m.pitch, m.thrust),
    REFERENCE_STATE: lambda m: (m.pn, m.pe, m.pd, m.vn, m.ve, m.vd, m.an, m.ae, m.ad),
    "sensor_msgs/msg/Imu": lambda m: _xyz(m.linear_acceleration),
    PX4_ODOMETRY: lambda m: (*(float(v) for v in m.position), *(float(v) for v in m.q),
                             *(float(v) for v in m.velocity), float(m.velocity_frame),
                             float(m.pose_frame)),
    PX4_THRUST: lambda m: tuple(float(v) for v in m.xyz),
    PX4_LOCAL_POSITION: lambda m: (m.x, m.y, m.z, m.vx, m.vy, m.vz, m.ax, m.ay, m.az),
}


def typestore_for(connections: list[Any]) -> Any:
    """A rosbags type store for the bag's ``connections``: ROS 2 Humble's types, the bag's own
    definitions, then Freyja's and PX4's built-in ones for types still unknown."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore
    from rosbags.typesys.base import TypesysError

    store = get_typestore(Stores.ROS2_HUMBLE)
    for conn in connections:
        if conn.msgtype in store.fielddefs:
            continue
        data = getattr(conn.msgdef, "data", "")
        if data and getattr(conn.msgdef.format, "name", "") == "MSG":
            try:
                store.register(get_types_from_msg(data, conn.msgtype))
            except TypesysError:
                pass
    for name, text in {**FREYJA_MSGS, **PX4_MSGS}.items():
        if name not in store.fielddefs:
            store.register(get_types_from_msg(text, name))
    return store


def stamp_ns(msg: Any) -> int | None:
    """A message's ``header.stamp`` in ns, or None if it has no header."""
    header = getattr(msg, "header", None)
    if header is None:
        return None
    return int(header.stamp.sec) * 1_000_000_000 + int(header.stamp.nanosec)


@dataclass
class Stream:
    """One topic: header (or bag) times and bag times, s from ``origin_s``; type; values.

    ``values`` holds each message's numbers (:data:`EXTRACT`), one row per message.
    """

    topic: str
    msgtype: str
    t_s: np.ndarray
    bag_t_s: np.ndarray
    values: np.ndarray
    origin_s: float = 0.0


@dataclass(frozen=True)
class StateSamples:
    """A state topic's samples in NED: times (s), position, velocity, attitude."""

    t_s: np.ndarray
    pos: np.ndarray
    vel: np.ndarray
    rot: np.ndarray
    quat: np.ndarray


@dataclass(frozen=True)
class CommandSamples:
    """A command topic's samples: ``kind`` and its ``values`` per message.

    ``kind`` is ``"accel"`` (values: the commanded acceleration, NED, zero at hover),
    ``"attitude-thrust"`` (roll, pitch, thrust) or ``"thrust-setpoint"`` (PX4's normalised
    body-frame thrust ``xyz``).
    """

    kind: str
    t_s: np.ndarray
    values: np.ndarray


def source_frames(msgtype: str, frame: str) -> tuple[np.ndarray, np.ndarray]:
    """``(world, body)`` maps to NED and FRD for a message type in the mapping's ``frame``."""
    if msgtype.startswith(("freyja_msgs/", "px4_msgs/")) or frame == "ned":
        return IDENTITY, IDENTITY
    return ENU_TO_NED, FLIP_YZ


def decode_state(stream: Stream, twist: Stream | None, frame: str, odom_twist: str,
                 path: Path) -> StateSamples:
    """Position, velocity (NED), attitude (quaternion, rotation) of a state topic.

    ``twist`` (a TwistStamped topic) gives a pose-only state's velocity; without it the
    position is differentiated. ``frame`` and ``odom_twist`` are the mapping's.

    Raises:
        IngestError: another message type, NaNs, non-unit quaternions, a vehicle upside down or
            implausible kinematics.
    """
    kind = stream.msgtype
    where = f"{path}: {stream.topic}"
    if kind == "freyja_msgs/msg/CurrentState":
        vals = stream.values
        check_finite({"state_vector": vals}, where, row_name="message")
        pos, vel = vals[:, 0:3], vals[:, 3:6]
        rot = euler_to_rotmat(vals[:, 6], vals[:, 7], vals[:, 8])
    elif kind == PX4_ODOMETRY:
        pos, vel, rot = _px4_state(stream.values, where)
    elif kind in STATE_TYPES:
        pos, vel, rot = _ros_state(stream, twist, frame, odom_twist, path)
    else:
        raise IngestError(path, f"topic {stream.topic} is {kind}; a state topic must be one of "
                                f"{', '.join(t.split('/')[-1] for t in STATE_TYPES)}")
    check_upright(rot, where, "the", "orientation in x, y, z, w order, or the wrong frame "
                                     "(mapping frame = enu or ned)?")
    check_kinematics(stream.t_s, pos, vel, where, "the")
    return StateSamples(t_s=stream.t_s, pos=pos, vel=vel, rot=rot, quat=rotmat_to_quat(rot))


def _px4_state(vals: np.ndarray, where: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Position, velocity and attitude of VehicleOdometry numbers (NED, FRD)."""
    check_finite({"position": vals[:, 0:3], "q": vals[:, 3:7], "velocity": vals[:, 7:10]},
                 where, row_name="message")
    _check_unit_quaternions(vals[:, 3:7], where)
    pos, rot = vals[:, 0:3], quat_to_rotmat(vals[:, 3:7])
    frames = vals[:, 10].astype(int)
    if np.any((frames < 1) | (frames > 3)):
        raise IngestError(where, f"velocity_frame {int(frames[(frames < 1) | (frames > 3)][0])}"
                                 " is not NED (1), FRD (2) or body FRD (3)")
    if np.any(vals[:, 11] == 2):
        # stacklevel 4: the caller of read_rosbag (read_rosbag -> decode_state -> here)
        warnings.warn(ingest_warning(where, "pose_frame FRD: an earth frame of arbitrary "
                                            "heading, taken as NED"), stacklevel=4)
    vel = np.where((frames == 3)[:, None], np.einsum("tij,tj->ti", rot, vals[:, 7:10]),
                   vals[:, 7:10])
    return pos, vel, rot


def _ros_state(stream: Stream, twist: Stream | None, frame: str, odom_twist: str,
               path: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Position, velocity and attitude (NED, FRD) of a standard ROS pose or odometry topic."""
    world, body = source_frames(stream.msgtype, frame)
    where = f"{path}: {stream.topic}"
    vals = stream.values
    pos_src, quat_src = vals[:, 0:3], vals[:, 3:7]
    check_finite({"position": pos_src, "orientation": quat_src}, where, row_name="message")
    _check_unit_quaternions(quat_src, where)
    rot_src = quat_to_rotmat(quat_src)
    pos = convert_vectors(world, pos_src)
    rot = convert_rotations(world, rot_src, body)
    if stream.msgtype == "nav_msgs/msg/Odometry":
        lin = vals[:, 7:10]
        check_finite({"twist.linear": lin}, where, row_name="message")
        if odom_twist == "body":
            lin = np.einsum("tij,tj->ti", rot_src, lin)
        vel = convert_vectors(world, lin)
    elif twist is not None:
        if twist.msgtype != "geometry_msgs/msg/TwistStamped":
            raise IngestError(path, f"topic {twist.topic} is {twist.msgtype}; a twist topic "
                                    "must be geometry_msgs/msg/TwistStamped")
        lin = twist.values
        check_finite({"twist.linear": lin}, f"{path}: {twist.topic}", row_name="message")
        vel = resample_linear(twist.t_s, convert_vectors(world, lin),
                              np.clip(stream.t_s, twist.t_s[0], twist.t_s[-1]))
    else:
        vel = differentiate(stream.t_s, pos)
    return pos, vel, rot


def _check_unit_quaternions(quat: np.ndarray, where: str) -> None:
    norms = np.linalg.norm(quat, axis=1)
    if np.any(np.abs(norms - 1.0) > 0.1):
        i = int(np.argmax(np.abs(norms - 1.0) > 0.1))
        raise IngestError(where, f"orientation of message {i} has norm {norms[i]:.3g}, "
                                 "not a unit quaternion")


def decode_command(stream: Stream, frame: str, path: Path) -> CommandSamples:
    """Commanded acceleration (NED, zero at hover), attitude-thrust or thrust-setpoint samples.

    Raises:
        IngestError: another message type, or NaNs.
    """
    kind = stream.msgtype
    world, _ = source_frames(kind, frame)
    where = f"{path}: {stream.topic}"
    vals = stream.values
    if kind == "freyja_msgs/msg/ControllerDebug":
        u = vals[:, 0:3] + GRAVITY_MPS2 * E3
        check_finite({"lqr_u": u}, where, row_name="message")
        return CommandSamples("accel", stream.t_s, u)
    if kind in ("geometry_msgs/msg/Vector3Stamped", "geometry_msgs/msg/AccelStamped"):
        check_finite({"acceleration": vals}, where, row_name="message")
        return CommandSamples("accel", stream.t_s, convert_vectors(world, vals))
    if kind in ATTITUDE_THRUST_TYPES:
        check_finite({"roll/pitch/thrust": vals}, where, row_name="message")
        return CommandSamples("attitude-thrust", stream.t_s, vals)
    if kind in THRUST_SETPOINT_TYPES:
        check_finite({"xyz": vals}, where, row_name="message")
        return CommandSamples("thrust-setpoint", stream.t_s, vals)
    known = ", ".join(t.split("/")[-1] for t in
                      ACCEL_COMMAND_TYPES + ATTITUDE_THRUST_TYPES + THRUST_SETPOINT_TYPES)
    raise IngestError(path, f"topic {stream.topic} is {kind}; a command topic must be one of "
                            f"{known}")


def command_accel(cmd: CommandSamples, t: np.ndarray, rot: np.ndarray,
                  mass_kg: float, hover_thrust: float | None = None
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Commanded acceleration (NED) and collective thrust (N) at times ``t``.

    ``rot`` is the vehicle's attitude at ``t``: an attitude-thrust command takes its heading, a
    PX4 thrust set point (body FRD, normalised) its direction.
    """
    if cmd.kind == "accel":
        accel = resample_hold(cmd.t_s, cmd.values, t)
        return accel, mass_kg * np.linalg.norm(GRAVITY_MPS2 * E3 - accel, axis=1)
    if cmd.kind == "thrust-setpoint":
        assert hover_thrust is not None
        xyz = resample_hold(cmd.t_s, cmd.values, t)
        per_unit = GRAVITY_MPS2 / hover_thrust
        accel = GRAVITY_MPS2 * E3 + np.einsum("tij,tj->ti", rot, xyz) * per_unit
        return accel, mass_kg * np.linalg.norm(xyz, axis=1) * per_unit
    rpt = resample_hold(cmd.t_s, cmd.values, t)
    # Freyja's roll and pitch are relative to the current heading: R = Rz(yaw) Ry(pitch) Rx(roll).
    heading = np.arctan2(rot[:, 1, 0], rot[:, 0, 0])
    rot_cmd = euler_to_rotmat(rpt[:, 0], rpt[:, 1], heading)
    return thrust_accel(rot_cmd, rpt[:, 2], mass_kg), rpt[:, 2]


def observed_accel(imu: Stream, frame: str, t: np.ndarray, rot: np.ndarray,
                   path: Path) -> np.ndarray:
    """The follower's kinematic acceleration (NED) at times ``t`` from its IMU topic.

    ``rot`` is its attitude at ``t`` (an Imu message's specific force is in the body frame).

    Raises:
        IngestError: another message type, NaNs, or specific forces in g or of the wrong sign.
    """
    if imu.msgtype not in IMU_TYPES:
        raise IngestError(path, f"topic {imu.topic} is {imu.msgtype}; the IMU topic must "
                                f"be one of {', '.join(IMU_TYPES)}")
    where_imu = f"{path}: {imu.topic}"
    if imu.msgtype == PX4_LOCAL_POSITION:  # NED kinematic acceleration, gravity removed
        check_finite({"ax/ay/az": imu.values[:, 6:9]}, where_imu, row_name="message")
        return resample_linear(imu.t_s, imu.values[:, 6:9], t)
    _, body = source_frames(imu.msgtype, frame)
    force = imu.values @ body.T
    check_finite({"linear_acceleration": force}, where_imu, row_name="message")
    check_specific_force(force, where_imu, "linear_acceleration", down_axis=E3,
                         frame="the body frame already flipped? (set frame in the "
                               "mapping)")
    return specific_force_to_accel(rot, resample_linear(imu.t_s, force, t))
