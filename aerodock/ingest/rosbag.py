"""Reader for ROS 2 bags (``.db3`` and ``.mcap``, or a bag folder) through ``rosbags``.

One bag holds one flight of both vehicles. A *mapping* (a TOML file or a dict) says which topic
carries what; every key is optional and defaults to :data:`DEFAULT_MAPPING`, which matches a
Freyja-like setup with the paper's vehicle names (leader ``alpha``, follower ``bravo``)::

    frame = "enu"        # standard ROS messages: "enu" (REP-103: ENU world, FLU body) or "ned"
                         # (NED world, FRD body). Freyja messages are NED by definition.
    time = "header"      # "header": header.stamp (messages without one use the bag time);
                         # "bag": the bag's receive time for every message
    odom_twist = "body"  # nav_msgs/Odometry twist frame: "body" (REP-105 child frame) or "world"
    max_gap_s = 0.25     # samples where the leader or command has a longer gap are dropped

    [leader]
    state = "/alpha/current_state"   # CurrentState | Odometry | PoseStamped | PoseWithCov...
    twist = ""                       # TwistStamped (world frame) with a PoseStamped state
    command = ""                     # optional; gives extra["leader_thrust_n"]
    # mass_kg = 0.7

    [follower]
    state = "/bravo/current_state"
    twist = ""
    command = ["/bravo/controller_debug", "/bravo/rpyt_command"]  # first present is used
    reference = "/bravo/reference_state"   # optional, kept as extra["follower_ref_*"]
    imu = "/bravo/imu"                     # optional sensor_msgs/Imu; else d/dt of velocity
    # mass_kg = 0.7

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
stores its own definitions (rosbag2 version 8+ and MCAP do) is read with those. Only the mapped
topics are deserialised, each message straight into a few numbers (no message objects are
kept), so memory grows only with the arrays returned.
"""

from __future__ import annotations

import copy
import tomllib
import warnings
from array import array
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from aerodock.flightlog import FlightLog
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
    bracket_gap_s,
    check_finite,
    check_hover_thrust,
    check_kinematics,
    check_mass,
    check_specific_force,
    check_time,
    check_time_unit,
    check_upright,
    convert_rotations,
    convert_vectors,
    differentiate,
    resample_hold,
    resample_linear,
    resample_quat,
)
from aerodock.ingest.errors import IngestError, ingest_warning

SOURCE = "rosbag"
DEFAULT_MASS_KG = 1.0

DEFAULT_MAPPING: dict[str, Any] = {
    "frame": "enu",
    "time": "header",
    "odom_twist": "body",
    "max_gap_s": 0.25,
    "leader": {
        "state": "/alpha/current_state",
        "twist": "",
        "command": "",
        "mass_kg": None,
        "hover_thrust": None,
    },
    "follower": {
        "state": "/bravo/current_state",
        "twist": "",
        "command": ["/bravo/controller_debug", "/bravo/rpyt_command"],
        "reference": "/bravo/reference_state",
        "imu": "/bravo/imu",
        "mass_kg": None,
        "hover_thrust": None,
    },
}
# Topics of the default mapping that may be absent; a topic the user names must be present.
_OPTIONAL_KEYS = ("twist", "reference", "imu", "command")

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
    "freyja_msgs/msg/ReferenceState": lambda m: (m.pn, m.pe, m.pd, m.vn, m.ve, m.vd, m.an,
                                                 m.ae, m.ad),
    "sensor_msgs/msg/Imu": lambda m: _xyz(m.linear_acceleration),
    PX4_ODOMETRY: lambda m: (*(float(v) for v in m.position), *(float(v) for v in m.q),
                             *(float(v) for v in m.velocity), float(m.velocity_frame),
                             float(m.pose_frame)),
    PX4_THRUST: lambda m: tuple(float(v) for v in m.xyz),
    PX4_LOCAL_POSITION: lambda m: (m.x, m.y, m.z, m.vx, m.vy, m.vz, m.ax, m.ay, m.az),
}


# --------------------------------------------------------------------------------------------
# Mapping
# --------------------------------------------------------------------------------------------


def load_mapping(
    mapping: Mapping[str, Any] | str | Path | None,
) -> tuple[dict[str, Any], set[str]]:
    """The default mapping overridden by ``mapping`` (a dict or a TOML file).

    Returns:
        ``(mapping, explicit)``: the merged mapping, and the ``"role.key"`` names the user set.

    Raises:
        IngestError: unreadable TOML, unknown keys, or values of the wrong kind.
    """
    where = "mapping"
    if mapping is None:
        user: dict[str, Any] = {}
    elif isinstance(mapping, Mapping):
        user = dict(mapping)
    else:
        where = str(mapping)
        try:
            with open(mapping, "rb") as fh:
                user = tomllib.load(fh)
        except FileNotFoundError:
            raise IngestError(where, "mapping file not found") from None
        except tomllib.TOMLDecodeError as err:
            raise IngestError(where, f"invalid TOML ({err})") from None
    merged = copy.deepcopy(DEFAULT_MAPPING)
    explicit: set[str] = set()
    for key, value in user.items():
        if key not in DEFAULT_MAPPING:
            raise IngestError(where, f"unknown key {key!r} (known: {', '.join(DEFAULT_MAPPING)})")
        if key in ("leader", "follower"):
            if not isinstance(value, Mapping):
                raise IngestError(where, f"[{key}] must be a table")
            for sub, sub_value in value.items():
                if sub not in DEFAULT_MAPPING[key]:
                    raise IngestError(where, f"unknown key {key}.{sub!r} "
                                             f"(known: {', '.join(DEFAULT_MAPPING[key])})")
                merged[key][sub] = sub_value
                explicit.add(f"{key}.{sub}")
        else:
            merged[key] = value
    for key, allowed in (("frame", ("enu", "ned")), ("time", ("header", "bag")),
                         ("odom_twist", ("body", "world"))):
        merged[key] = str(merged[key]).lower()
        if merged[key] not in allowed:
            raise IngestError(where, f"{key} = {merged[key]!r}; use {' or '.join(allowed)}")
    gap = merged["max_gap_s"]
    if (isinstance(gap, bool) or not isinstance(gap, int | float)
            or not 0 < gap <= 60):  # also false for NaN
        raise IngestError(where, f"max_gap_s must be a number of seconds in (0, 60], got {gap!r}")
    merged["max_gap_s"] = float(gap)
    for role in ("leader", "follower"):
        for key, value in merged[role].items():
            if key == "mass_kg":
                if value is not None:
                    merged[role][key] = check_mass(value, where, f"{role}.mass_kg")
            elif key == "hover_thrust":
                if value is not None and (isinstance(value, bool) or not isinstance(
                        value, int | float) or not check_hover_thrust(float(value))):
                    raise IngestError(where, f"{role}.hover_thrust = {value!r}: expected the "
                                             "normalised hover thrust, 0.05-0.95")
            elif key == "command":
                topics = [value] if isinstance(value, str) else value
                if not isinstance(topics, list) or not all(isinstance(t, str) for t in topics):
                    raise IngestError(where, f"{role}.command must be a topic or a list of them")
                merged[role][key] = [t for t in topics if t]
            elif not isinstance(value, str):
                raise IngestError(where, f"{role}.{key} must be a topic name (a string)")
        if not merged[role]["state"]:
            raise IngestError(where, f"{role}.state (the {role}'s state topic) is required")
    if not merged["follower"]["command"]:
        raise IngestError(where, "follower.command (the commanded acceleration or attitude-"
                                 "thrust topic) is required")
    return merged, explicit


# --------------------------------------------------------------------------------------------
# Reading
# --------------------------------------------------------------------------------------------


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


def _typestore_for(connections: list[Any]) -> Any:
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


def _stamp_ns(msg: Any) -> int | None:
    header = getattr(msg, "header", None)
    if header is None:
        return None
    return int(header.stamp.sec) * 1_000_000_000 + int(header.stamp.nanosec)


class _Column:
    """Compact growing storage of one topic (typed arrays, not message objects)."""

    def __init__(self, msgtype: str) -> None:
        self.msgtype = msgtype
        self.bag_ns = array("q")
        self.stamp_ns = array("q")
        self.has_stamps = True
        self.values = array("d")
        self.width = -1

    def add(self, bag_ns: int, stamp_ns: int | None, row: tuple[float, ...]) -> None:
        self.bag_ns.append(bag_ns)
        if stamp_ns is None:
            self.has_stamps = False
        else:
            self.stamp_ns.append(stamp_ns)
        self.width = len(row)
        self.values.extend(row)


def _read_streams(path: Path, topics: set[str], use_header: bool,
                  progress: Callable[[int, int], None] | None = None
                  ) -> tuple[dict[str, Stream], list[str]]:
    try:
        from rosbags.rosbag2 import Reader
        from rosbags.rosbag2.errors import ReaderError
    except ImportError:  # pragma: no cover - the ingest extra is not installed
        raise IngestError(path, "reading ROS 2 bags needs rosbags: pip install "
                                "'aerodock[ingest]'") from None
    if not path.exists():
        raise IngestError(path, "file not found")
    if path.is_file() and path.stat().st_size == 0:
        raise IngestError(path, "empty file")
    streams: dict[str, Stream] = {}
    raw: dict[str, _Column] = {}
    try:
        with Reader(path) as reader:
            present = sorted({c.topic for c in reader.connections})
            wanted = [c for c in reader.connections if c.topic in topics]
            store = _typestore_for(wanted)
            total = sum(int(getattr(c, "msgcount", 0) or 0) for c in wanted)
            done = 0
            for conn, bag_ns, data in reader.messages(connections=wanted):
                if conn.msgtype not in store.fielddefs:
                    raise IngestError(path, f"topic {conn.topic}: unknown message type "
                                            f"{conn.msgtype} and no definition in the bag")
                msg = store.deserialize_cdr(data, conn.msgtype)
                extract = EXTRACT.get(conn.msgtype)
                column = raw.setdefault(conn.topic, _Column(conn.msgtype))
                column.add(bag_ns, _stamp_ns(msg) if use_header else None,
                           extract(msg) if extract else ())
                done += 1
                if progress and (done % 1000 == 0 or done == total):
                    progress(done, max(total, done))
    except IngestError:
        raise
    except (ReaderError, FileNotFoundError) as err:
        raise IngestError(path, f"not a readable ROS 2 bag ({err})") from None
    except Exception as err:  # rosbags raises assorted errors on corrupt storage
        raise IngestError(path, f"corrupt ROS 2 bag ({type(err).__name__}: {err})") from None
    # Stamps are ~1.7e18 ns: subtract a common integer origin before going to float seconds.
    stamps_ns: dict[str, tuple[np.ndarray, np.ndarray, str]] = {}
    for topic, column in raw.items():
        bag_arr = np.frombuffer(column.bag_ns, dtype=np.int64)
        if column.has_stamps and len(column.stamp_ns) == len(column.bag_ns):
            stamps = np.frombuffer(column.stamp_ns, dtype=np.int64)
            name = f"{topic} header.stamp"
            if np.all(stamps == 0):
                raise IngestError(path, f"{name} is zero in every message: set time = "
                                        "\"bag\" in the mapping")
        else:
            stamps, name = bag_arr, f"{topic} bag time"
        stamps_ns[topic] = (stamps, bag_arr, name)
    origin = min((int(s[0]) for s, _, _ in stamps_ns.values() if len(s)), default=0)
    for topic, (stamps, bag_arr, name) in stamps_ns.items():
        rel = (stamps - origin).astype(float)
        check_time(rel, str(path), column=name, row_name="message")
        check_time_unit(rel, "ns", str(path), column=name)
        column = raw[topic]
        values = np.frombuffer(column.values, dtype=float).reshape(len(bag_arr), -1) \
            if column.width > 0 else np.zeros((len(bag_arr), 0))
        streams[topic] = Stream(topic, column.msgtype, rel * 1e-9, (bag_arr - origin) * 1e-9,
                                values, origin * 1e-9)
    return streams, present


def _require(streams: dict[str, Stream], present: list[str], topic: str, what: str,
             path: Path) -> Stream:
    if topic not in streams:
        listed = ", ".join(present[:8]) + (" ..." if len(present) > 8 else "")
        if topic in present:
            raise IngestError(path, f"topic {topic} ({what}) has no messages")
        raise IngestError(path, f"missing topic {topic} ({what}); the bag has: {listed or 'none'}")
    return streams[topic]


def _frames(mapping: dict[str, Any], msgtype: str) -> tuple[np.ndarray, np.ndarray]:
    if msgtype.startswith(("freyja_msgs/", "px4_msgs/")) or mapping["frame"] == "ned":
        return IDENTITY, IDENTITY
    return ENU_TO_NED, FLIP_YZ


def _state(stream: Stream, twist: Stream | None, mapping: dict[str, Any],
           path: Path) -> dict[str, np.ndarray]:
    """Position, velocity (NED), attitude (quaternion, rotation) of a state topic."""
    kind = stream.msgtype
    world, body = _frames(mapping, kind)
    where = f"{path}: {stream.topic}"
    vals = stream.values
    if kind == "freyja_msgs/msg/CurrentState":
        check_finite({"state_vector": vals}, where, row_name="message")
        pos, vel = vals[:, 0:3], vals[:, 3:6]
        rot = euler_to_rotmat(vals[:, 6], vals[:, 7], vals[:, 8])
    elif kind == PX4_ODOMETRY:
        check_finite({"position": vals[:, 0:3], "q": vals[:, 3:7], "velocity": vals[:, 7:10]},
                     where, row_name="message")
        _check_unit_quaternions(vals[:, 3:7], where)
        pos, rot = vals[:, 0:3], quat_to_rotmat(vals[:, 3:7])
        frames = vals[:, 10].astype(int)
        if np.any((frames < 1) | (frames > 3)):
            raise IngestError(where, f"velocity_frame {int(frames[(frames < 1) | (frames > 3)][0])}"
                                     " is not NED (1), FRD (2) or body FRD (3)")
        if np.any(vals[:, 11] == 2):
            warnings.warn(ingest_warning(where, "pose_frame FRD: an earth frame of arbitrary "
                                                "heading, taken as NED"), stacklevel=3)
        vel = np.where((frames == 3)[:, None], np.einsum("tij,tj->ti", rot, vals[:, 7:10]),
                       vals[:, 7:10])
    elif kind in STATE_TYPES:
        pos_src, quat_src = vals[:, 0:3], vals[:, 3:7]
        check_finite({"position": pos_src, "orientation": quat_src}, where, row_name="message")
        _check_unit_quaternions(quat_src, where)
        rot_src = quat_to_rotmat(quat_src)
        pos = convert_vectors(world, pos_src)
        rot = convert_rotations(world, rot_src, body)
        if kind == "nav_msgs/msg/Odometry":
            lin = vals[:, 7:10]
            check_finite({"twist.linear": lin}, where, row_name="message")
            if mapping["odom_twist"] == "body":
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
    else:
        raise IngestError(path, f"topic {stream.topic} is {kind}; a state topic must be one of "
                                f"{', '.join(t.split('/')[-1] for t in STATE_TYPES)}")
    check_upright(rot, where, "the", "orientation in x, y, z, w order, or the wrong frame "
                                     "(mapping frame = enu or ned)?")
    check_kinematics(stream.t_s, pos, vel, where, "the")
    return {"t": stream.t_s, "pos": pos, "vel": vel, "rot": rot, "quat": rotmat_to_quat(rot)}


def _check_unit_quaternions(quat: np.ndarray, where: str) -> None:
    norms = np.linalg.norm(quat, axis=1)
    if np.any(np.abs(norms - 1.0) > 0.1):
        i = int(np.argmax(np.abs(norms - 1.0) > 0.1))
        raise IngestError(where, f"orientation of message {i} has norm {norms[i]:.3g}, "
                                 "not a unit quaternion")


def _command(stream: Stream, mapping: dict[str, Any], path: Path) -> dict[str, Any]:
    """Commanded acceleration (NED, zero at hover), attitude-thrust or thrust-setpoint samples."""
    kind = stream.msgtype
    world, _ = _frames(mapping, kind)
    where = f"{path}: {stream.topic}"
    vals = stream.values
    if kind == "freyja_msgs/msg/ControllerDebug":
        u = vals[:, 0:3] + GRAVITY_MPS2 * E3
        check_finite({"lqr_u": u}, where, row_name="message")
        return {"kind": "accel", "t": stream.t_s, "accel": u}
    if kind in ("geometry_msgs/msg/Vector3Stamped", "geometry_msgs/msg/AccelStamped"):
        check_finite({"acceleration": vals}, where, row_name="message")
        return {"kind": "accel", "t": stream.t_s, "accel": convert_vectors(world, vals)}
    if kind in ATTITUDE_THRUST_TYPES:
        check_finite({"roll/pitch/thrust": vals}, where, row_name="message")
        return {"kind": "attitude-thrust", "t": stream.t_s, "rpt": vals}
    if kind in THRUST_SETPOINT_TYPES:
        check_finite({"xyz": vals}, where, row_name="message")
        return {"kind": "thrust-setpoint", "t": stream.t_s, "xyz": vals}
    known = ", ".join(t.split("/")[-1] for t in
                      ACCEL_COMMAND_TYPES + ATTITUDE_THRUST_TYPES + THRUST_SETPOINT_TYPES)
    raise IngestError(path, f"topic {stream.topic} is {kind}; a command topic must be one of "
                            f"{known}")


def _mass(mapping: dict[str, Any], role: str, option: float | None, path: Path,
          needed: bool) -> tuple[float, bool]:
    if option is not None:
        return check_mass(option, path, "--mass-kg"), False
    if mapping[role]["mass_kg"] is not None:
        return float(mapping[role]["mass_kg"]), False
    if needed:
        raise IngestError(path, f"the {role}'s attitude-thrust command needs its mass: set "
                                f"{role}.mass_kg in the mapping or pass --mass-kg")
    return DEFAULT_MASS_KG, True


def _command_topic(role_map: dict[str, Any], streams: dict[str, Stream], present: list[str],
                   path: Path, role: str, required: bool) -> Stream | None:
    for topic in role_map["command"]:
        if topic in streams:
            return streams[topic]
    if required:
        _require(streams, present, role_map["command"][0] if len(role_map["command"]) == 1
                 else " or ".join(role_map["command"]), f"{role} command", path)
    return None


def read_rosbag(path: Path, *, mapping: Mapping[str, Any] | str | Path | None = None,
                mass_kg: float | None = None,
                progress: Callable[[int, int], None] | None = None) -> FlightLog:
    """Read one ROS 2 bag (a ``.db3``/``.mcap`` file or a bag folder) into a FlightLog.

    Args:
        path: The bag.
        mapping: Topic mapping (dict or TOML file) over :data:`DEFAULT_MAPPING`.
        mass_kg: Mass of both vehicles, overriding the mapping.
        progress: Called as ``progress(messages_read, messages_to_read)`` while reading.

    Raises:
        IngestError: unreadable or empty bag, missing topics, unsupported message types, NaNs,
            bad stamps (duplicated, non-monotonic, zero, wrong unit), too little overlap.
    """
    path = Path(path)
    cfg, explicit = load_mapping(mapping)
    leader_map, follower_map = cfg["leader"], cfg["follower"]
    topics = {leader_map["state"], follower_map["state"]}
    for role_map in (leader_map, follower_map):
        topics.update(t for k in _OPTIONAL_KEYS for t in ([role_map.get(k)] if k != "command"
                                                           else role_map[k]) if t)
    streams, present = _read_streams(path, topics, cfg["time"] == "header", progress)
    if not present:
        raise IngestError(path, "empty bag: no topics")
    for role in ("leader", "follower"):
        for key in ("twist", "reference", "imu"):
            topic = cfg[role].get(key)
            if topic and f"{role}.{key}" in explicit:
                _require(streams, present, topic, f"{role} {key}", path)

    def optional(role: str, key: str) -> Stream | None:
        topic = cfg[role].get(key)
        return streams.get(topic) if topic else None

    leader = _state(_require(streams, present, leader_map["state"], "leader state", path),
                    optional("leader", "twist"), cfg, path)
    follower = _state(_require(streams, present, follower_map["state"], "follower state", path),
                      optional("follower", "twist"), cfg, path)
    cmd_stream = _command_topic(follower_map, streams, present, path, "follower", True)
    assert cmd_stream is not None
    cmd = _command(cmd_stream, cfg, path)
    leader_cmd_stream = _command_topic(leader_map, streams, present, path, "leader",
                                       "leader.command" in explicit)
    leader_cmd = _command(leader_cmd_stream, cfg, path) if leader_cmd_stream else None
    imu = optional("follower", "imu")

    # Common window of every stream used; the follower state's stamps are the time base.
    spans = [leader["t"], follower["t"], cmd["t"]] + ([imu.t_s] if imu else []) + \
        ([leader_cmd["t"]] if leader_cmd else [])
    start = max(float(s[0]) for s in spans)
    end = min(float(s[-1]) for s in spans)
    t_f = follower["t"]
    inside = (t_f >= start) & (t_f <= end)
    keep = inside & (bracket_gap_s(leader["t"], t_f) <= cfg["max_gap_s"]) & \
        (t_f - resample_hold(cmd["t"], cmd["t"], t_f) <= cfg["max_gap_s"])
    n_keep = int(keep.sum())
    longest = max(float(s[-1] - s[0]) for s in spans)
    if n_keep < 2 or (end - start) < 0.5 * longest:
        raise IngestError(path, f"topics of different lengths: the follower state, leader state "
                                f"and command overlap for {max(end - start, 0):.2f} s of "
                                f"{longest:.2f} s")
    t = t_f[keep]
    rot_f = follower["rot"][keep]

    f_mass, f_assumed = _mass(cfg, "follower", mass_kg, path, cmd["kind"] == "attitude-thrust")
    l_mass, l_assumed = _mass(cfg, "leader", mass_kg, path, bool(
        leader_cmd and leader_cmd["kind"] == "attitude-thrust"))
    cmd_accel, thrust_n = _command_accel(cmd, t, rot_f, f_mass,
                                         _hover(cfg, "follower", cmd, path))
    if imu is not None:
        if imu.msgtype not in IMU_TYPES:
            raise IngestError(path, f"topic {imu.topic} is {imu.msgtype}; the IMU topic must "
                                    f"be one of {', '.join(IMU_TYPES)}")
        where_imu = f"{path}: {imu.topic}"
        if imu.msgtype == PX4_LOCAL_POSITION:  # NED kinematic acceleration, gravity removed
            check_finite({"ax/ay/az": imu.values[:, 6:9]}, where_imu, row_name="message")
            obs = resample_linear(imu.t_s, imu.values[:, 6:9], t)
        else:
            _, body = _frames(cfg, imu.msgtype)
            force = imu.values @ body.T
            check_finite({"linear_acceleration": force}, where_imu, row_name="message")
            check_specific_force(force, where_imu, "linear_acceleration", down_axis=E3,
                                 frame="the body frame already flipped? (set frame in the "
                                       "mapping)")
            obs = specific_force_to_accel(rot_f, resample_linear(imu.t_s, force, t))
        obs_source = f"imu {imu.topic}"
    else:
        obs = differentiate(follower["t"], follower["vel"])[keep]
        obs_source = "differentiated follower velocity"

    extra: dict[str, np.ndarray] = {}
    if leader_cmd is not None:
        leader_rot = quat_to_rotmat(resample_quat(leader["t"], leader["quat"], t))
        extra["leader_thrust_n"] = _command_accel(leader_cmd, t, leader_rot, l_mass,
                                                  _hover(cfg, "leader", leader_cmd, path))[1]
    ref = optional("follower", "reference")
    if ref is not None and ref.msgtype == "freyja_msgs/msg/ReferenceState":
        vals = ref.values
        if np.all(np.isfinite(vals)) and ref.t_s[0] <= t[-1]:
            held = resample_hold(ref.t_s, vals, t)
            extra.update({"follower_ref_pos_m": held[:, 0:3], "follower_ref_vel_mps": held[:, 3:6],
                          "follower_ref_accel_mps2": held[:, 6:9]})
    lat = {role: float(np.median(s.bag_t_s - s.t_s)) for role, s in
           (("leader", streams[leader_map["state"]]), ("follower", streams[follower_map["state"]]))}
    if abs(lat["leader"] - lat["follower"]) > 0.1:
        warnings.warn(ingest_warning(
            path, f"leader and follower stamps reach the bag {lat['leader']:.3f} s and "
            f"{lat['follower']:.3f} s late: their clocks may not agree"), stacklevel=2)
    if f_assumed:
        warnings.warn(ingest_warning(
            path, f"no follower mass: assuming {DEFAULT_MASS_KG:g} kg for follower_thrust_n "
            "(set follower.mass_kg or --mass-kg)"), stacklevel=2)
    meta = {
        "name": path.stem if path.is_file() else path.name,
        "source": SOURCE,
        "frame": "NED",
        "label_basis": "thrust" if cmd["kind"] == "thrust-setpoint" else "command",
        "command_topic": cmd_stream.topic,
        "command_type": cmd_stream.msgtype,
        "command_kind": cmd["kind"],
        "obs_accel_source": obs_source,
        "leader_mass_kg": l_mass,
        "follower_mass_kg": f_mass,
        "mass_assumed": f_assumed or l_assumed,
        "source_frame": cfg["frame"],
        "time": cfg["time"],
        "file": str(path),
        "t_origin_s": float(t[0]) + streams[follower_map["state"]].origin_s,
        "dropped_samples": int(inside.sum() - n_keep),
        "stamp_latency_s": lat,
        "mapping": {"leader": leader_map, "follower": follower_map},
        "gravity_mps2": GRAVITY_MPS2,
    }
    return FlightLog(
        t_s=t - t[0],
        leader_pos_m=resample_linear(leader["t"], leader["pos"], t),
        leader_vel_mps=resample_linear(leader["t"], leader["vel"], t),
        leader_quat=resample_quat(leader["t"], leader["quat"], t),
        follower_pos_m=follower["pos"][keep],
        follower_vel_mps=follower["vel"][keep],
        follower_quat=follower["quat"][keep],
        follower_cmd_accel_mps2=cmd_accel,
        follower_thrust_n=thrust_n,
        follower_obs_accel_mps2=obs,
        meta=meta,
        extra=extra,
    )


def _hover(cfg: dict[str, Any], role: str, cmd: dict[str, Any], path: Path) -> float | None:
    """The role's hover thrust, required by a PX4 thrust set point."""
    if cmd["kind"] != "thrust-setpoint":
        return None
    hover = cfg[role].get("hover_thrust")
    if hover is None:
        raise IngestError(path, f"the {role}'s PX4 thrust set point needs its hover thrust: set "
                                f"{role}.hover_thrust (e.g. MPC_THR_HOVER) in the mapping")
    return float(hover)


def _command_accel(cmd: dict[str, Any], t: np.ndarray, rot: np.ndarray,
                   mass_kg: float, hover_thrust: float | None = None
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Commanded acceleration (NED) and collective thrust (N) at times ``t``.

    ``rot`` is the vehicle's attitude at ``t``: an attitude-thrust command takes its heading, a
    PX4 thrust set point (body FRD, normalised) its direction.
    """
    if cmd["kind"] == "accel":
        accel = resample_hold(cmd["t"], cmd["accel"], t)
        return accel, mass_kg * np.linalg.norm(GRAVITY_MPS2 * E3 - accel, axis=1)
    if cmd["kind"] == "thrust-setpoint":
        assert hover_thrust is not None
        xyz = resample_hold(cmd["t"], cmd["xyz"], t)
        per_unit = GRAVITY_MPS2 / hover_thrust
        accel = GRAVITY_MPS2 * E3 + np.einsum("tij,tj->ti", rot, xyz) * per_unit
        return accel, mass_kg * np.linalg.norm(xyz, axis=1) * per_unit
    rpt = resample_hold(cmd["t"], cmd["rpt"], t)
    # Freyja's roll and pitch are relative to the current heading: R = Rz(yaw) Ry(pitch) Rx(roll).
    heading = np.arctan2(rot[:, 1, 0], rot[:, 0, 0])
    rot_cmd = euler_to_rotmat(rpt[:, 0], rpt[:, 1], heading)
    return thrust_accel(rot_cmd, rpt[:, 2], mass_kg), rpt[:, 2]
