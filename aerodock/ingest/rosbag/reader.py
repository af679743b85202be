"""Reading one ROS 2 bag (``.db3``, ``.mcap`` or a bag folder) into a FlightLog.

Only the mapped topics are deserialised, each message straight into a few numbers
(:data:`~aerodock.ingest.rosbag.messages.EXTRACT`; no message objects are kept), so memory
grows only with the arrays returned. The follower state's stamps are the time base: every other
topic is resampled onto those of its samples that all topics cover.

The checks run in a fixed order, so that a bag with several problems always draws the same
message: the mapping, the bag and its stamps, the topics the mapping names explicitly, the
states, the commands, the common window, the masses, then the accelerations.
"""

from __future__ import annotations

import warnings
from array import array
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from aerodock.flightlog import FlightLog
from aerodock.geometry import GRAVITY_MPS2, quat_to_rotmat
from aerodock.ingest.common import (
    bracket_gap_s,
    check_bag_folder,
    check_mass,
    check_regular_input,
    check_time,
    check_time_unit,
    differentiate,
    resample_hold,
    resample_linear,
    resample_quat,
)
from aerodock.ingest.errors import IngestError, ingest_warning
from aerodock.ingest.rosbag.mapping import RoleTopics, TopicMapping
from aerodock.ingest.rosbag.messages import (
    EXTRACT,
    REFERENCE_STATE,
    CommandSamples,
    StateSamples,
    Stream,
    command_accel,
    decode_command,
    decode_state,
    observed_accel,
    stamp_ns,
    typestore_for,
)

SOURCE = "rosbag"
DEFAULT_MASS_KG = 1.0


# --------------------------------------------------------------------------------------------
# The bag's topics
# --------------------------------------------------------------------------------------------


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
        """Append one message: its bag time, header stamp (None: it has none) and numbers."""
        self.bag_ns.append(bag_ns)
        if stamp_ns is None:
            self.has_stamps = False
        else:
            self.stamp_ns.append(stamp_ns)
        self.width = len(row)
        self.values.extend(row)


@dataclass(frozen=True)
class _Stamps:
    """One topic's times in ns: the ones used (header or bag), the bag's, and their name."""

    used_ns: np.ndarray
    bag_ns: np.ndarray
    name: str


@dataclass(frozen=True)
class BagTopics:
    """The mapped topics read from a bag (by name) and the names of all its topics."""

    path: Path
    streams: dict[str, Stream]
    present: list[str]

    def require(self, topic: str, what: str) -> Stream:
        """The topic's stream; an IngestError naming the bag's topics if it has none."""
        if topic not in self.streams:
            listed = ", ".join(self.present[:8]) + (" ..." if len(self.present) > 8 else "")
            if topic in self.present:
                raise IngestError(self.path, f"topic {topic} ({what}) has no messages")
            raise IngestError(self.path, f"missing topic {topic} ({what}); the bag has: "
                                         f"{listed or 'none'}")
        return self.streams[topic]

    def optional(self, topic: str) -> Stream | None:
        """The topic's stream, or None if the topic is not mapped or not in the bag."""
        return self.streams.get(topic) if topic else None

    def command(self, role: RoleTopics, required: bool) -> Stream | None:
        """The first of the role's command topics that the bag holds (or an error if
        ``required``, else None)."""
        for topic in role.command:
            if topic in self.streams:
                return self.streams[topic]
        if required:
            self.require(role.command[0] if len(role.command) == 1
                         else " or ".join(role.command), f"{role.role} command")
        return None


def _reader_class(path: Path) -> Any:
    """rosbags' Reader class; an IngestError if rosbags is missing or ``path`` cannot be a bag."""
    try:
        from rosbags.rosbag2 import Reader
    except ImportError:  # pragma: no cover - the ingest extra is not installed
        raise IngestError(path, "reading ROS 2 bags needs rosbags: pip install "
                                "'aerodock[ingest]'") from None
    if not path.exists():
        raise IngestError(path, "file not found")
    if path.is_dir():
        check_bag_folder(path)
    else:
        check_regular_input(path, "bag file")
    if path.is_file() and path.stat().st_size == 0:
        raise IngestError(path, "empty file")
    return Reader


def _read_columns(path: Path, topics: set[str], use_header: bool,
                  progress: Callable[[int, int], None] | None
                  ) -> tuple[dict[str, _Column], list[str]]:
    """Every message of the mapped ``topics`` as numbers, and the names of all the bag's topics."""
    reader_class = _reader_class(path)
    from rosbags.rosbag2.errors import ReaderError

    raw: dict[str, _Column] = {}
    try:
        with reader_class(path) as reader:
            present = sorted({c.topic for c in reader.connections})
            wanted = [c for c in reader.connections if c.topic in topics]
            store = typestore_for(wanted)
            total = sum(int(getattr(c, "msgcount", 0) or 0) for c in wanted)
            done = 0
            for conn, bag_ns, data in reader.messages(connections=wanted):
                if conn.msgtype not in store.fielddefs:
                    raise IngestError(path, f"topic {conn.topic}: unknown message type "
                                            f"{conn.msgtype} and no definition in the bag")
                msg = store.deserialize_cdr(data, conn.msgtype)
                extract = EXTRACT.get(conn.msgtype)
                column = raw.setdefault(conn.topic, _Column(conn.msgtype))
                column.add(bag_ns, stamp_ns(msg) if use_header else None,
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
    return raw, present


def _stamps(path: Path, topic: str, column: _Column) -> _Stamps:
    """A topic's header stamps, or its bag times where messages have no header."""
    bag_arr = np.frombuffer(column.bag_ns, dtype=np.int64)
    if column.has_stamps and len(column.stamp_ns) == len(column.bag_ns):
        stamps = np.frombuffer(column.stamp_ns, dtype=np.int64)
        name = f"{topic} header.stamp"
        if np.all(stamps == 0):
            raise IngestError(path, f"{name} is zero in every message: set time = "
                                    "\"bag\" in the mapping")
    else:
        stamps, name = bag_arr, f"{topic} bag time"
    return _Stamps(stamps, bag_arr, name)


def _to_streams(path: Path, raw: dict[str, _Column]) -> dict[str, Stream]:
    """Columns as Streams of float seconds from a common origin, their stamps checked."""
    stamps = {topic: _stamps(path, topic, column) for topic, column in raw.items()}
    # Stamps are ~1.7e18 ns: subtract a common integer origin before going to float seconds.
    origin = min((int(s.used_ns[0]) for s in stamps.values() if len(s.used_ns)), default=0)
    streams: dict[str, Stream] = {}
    for topic, s in stamps.items():
        rel = (s.used_ns - origin).astype(float)
        check_time(rel, str(path), column=s.name, row_name="message")
        check_time_unit(rel, "ns", str(path), column=s.name)
        column = raw[topic]
        values = np.frombuffer(column.values, dtype=float).reshape(len(s.bag_ns), -1) \
            if column.width > 0 else np.zeros((len(s.bag_ns), 0))
        streams[topic] = Stream(topic, column.msgtype, rel * 1e-9, (s.bag_ns - origin) * 1e-9,
                                values, origin * 1e-9)
    return streams


def _read_topics(path: Path, topic_map: TopicMapping,
                 progress: Callable[[int, int], None] | None) -> BagTopics:
    """The mapped topics of the bag; the topics the user named explicitly must be there."""
    raw, present = _read_columns(path, topic_map.topics(), topic_map.time == "header", progress)
    bag = BagTopics(path, _to_streams(path, raw), present)
    if not present:
        raise IngestError(path, "empty bag: no topics")
    for role in (topic_map.leader, topic_map.follower):
        for key in ("twist", "reference", "imu"):
            topic = getattr(role, key)
            if topic and f"{role.role}.{key}" in topic_map.explicit:
                bag.require(topic, f"{role.role} {key}")
    return bag


# --------------------------------------------------------------------------------------------
# Reading
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Window:
    """The follower-state samples kept: inside every topic's span, no long gap around them."""

    t: np.ndarray
    keep: np.ndarray
    n_dropped: int


def _common_window(path: Path, leader: StateSamples, follower: StateSamples,
                   cmd: CommandSamples, others: list[np.ndarray], max_gap_s: float) -> _Window:
    """Common window of every stream used (``others``: the IMU's and the leader command's
    times); the follower state's stamps are the time base."""
    spans = [leader.t_s, follower.t_s, cmd.t_s] + others
    start = max(float(s[0]) for s in spans)
    end = min(float(s[-1]) for s in spans)
    t_f = follower.t_s
    inside = (t_f >= start) & (t_f <= end)
    keep = inside & (bracket_gap_s(leader.t_s, t_f) <= max_gap_s) & \
        (t_f - resample_hold(cmd.t_s, cmd.t_s, t_f) <= max_gap_s)
    n_keep = int(keep.sum())
    longest = max(float(s[-1] - s[0]) for s in spans)
    if n_keep < 2 or (end - start) < 0.5 * longest:
        raise IngestError(path, f"topics of different lengths: the follower state, leader state "
                                f"and command overlap for {max(end - start, 0):.2f} s of "
                                f"{longest:.2f} s")
    return _Window(t_f[keep], keep, int(inside.sum() - n_keep))


def _mass(role: RoleTopics, option: float | None, path: Path,
          needed: bool) -> tuple[float, bool]:
    """The role's mass (``--mass-kg``, else the mapping's) and whether it was assumed."""
    if option is not None:
        return check_mass(option, path, "--mass-kg"), False
    if role.mass_kg is not None:
        return float(role.mass_kg), False
    if needed:
        raise IngestError(path, f"the {role.role}'s attitude-thrust command needs its mass: set "
                                f"{role.role}.mass_kg in the mapping or pass --mass-kg")
    return DEFAULT_MASS_KG, True


def _hover(role: RoleTopics, cmd: CommandSamples, path: Path) -> float | None:
    """The role's hover thrust, required by a PX4 thrust set point."""
    if cmd.kind != "thrust-setpoint":
        return None
    if role.hover_thrust is None:
        raise IngestError(path, f"the {role.role}'s PX4 thrust set point needs its hover "
                                f"thrust: set {role.role}.hover_thrust (e.g. MPC_THR_HOVER) "
                                "in the mapping")
    return float(role.hover_thrust)


def _extras(bag: BagTopics, topic_map: TopicMapping, leader: StateSamples,
            leader_cmd: CommandSamples | None, leader_mass_kg: float,
            t: np.ndarray) -> dict[str, np.ndarray]:
    """The leader's thrust (if it has a command topic) and the follower's reference."""
    extra: dict[str, np.ndarray] = {}
    if leader_cmd is not None:
        leader_rot = quat_to_rotmat(resample_quat(leader.t_s, leader.quat, t))
        extra["leader_thrust_n"] = command_accel(
            leader_cmd, t, leader_rot, leader_mass_kg,
            _hover(topic_map.leader, leader_cmd, bag.path))[1]
    ref = bag.optional(topic_map.follower.reference)
    if ref is not None and ref.msgtype == REFERENCE_STATE:
        vals = ref.values
        if np.all(np.isfinite(vals)) and ref.t_s[0] <= t[-1]:
            held = resample_hold(ref.t_s, vals, t)
            extra.update({"follower_ref_pos_m": held[:, 0:3], "follower_ref_vel_mps": held[:, 3:6],
                          "follower_ref_accel_mps2": held[:, 6:9]})
    return extra


def _stamp_latency(bag: BagTopics, topic_map: TopicMapping) -> dict[str, float]:
    """How late each vehicle's state stamps reach the bag (median bag time - stamp), s."""
    return {role.role: float(np.median(bag.streams[role.state].bag_t_s
                                       - bag.streams[role.state].t_s))
            for role in (topic_map.leader, topic_map.follower)}


@dataclass(frozen=True)
class _Masses:
    """Both vehicles' masses, kg, and whether they were assumed (:data:`DEFAULT_MASS_KG`)."""

    leader_kg: float
    follower_kg: float
    leader_assumed: bool
    follower_assumed: bool


def _masses(topic_map: TopicMapping, option: float | None, cmd: CommandSamples,
            leader_cmd: CommandSamples | None, path: Path) -> _Masses:
    """The masses (follower first: its error comes first); an attitude-thrust command needs one."""
    f_mass, f_assumed = _mass(topic_map.follower, option, path, cmd.kind == "attitude-thrust")
    l_mass, l_assumed = _mass(topic_map.leader, option, path, bool(
        leader_cmd and leader_cmd.kind == "attitude-thrust"))
    return _Masses(l_mass, f_mass, l_assumed, f_assumed)


def _warn(path: Path, lat: dict[str, float], masses: _Masses) -> None:
    """Warn of clocks that may not agree and of an assumed follower mass."""
    # stacklevel 3: the caller of read_rosbag (read_rosbag -> here)
    if abs(lat["leader"] - lat["follower"]) > 0.1:
        warnings.warn(ingest_warning(
            path, f"leader and follower stamps reach the bag {lat['leader']:.3f} s and "
            f"{lat['follower']:.3f} s late: their clocks may not agree"), stacklevel=3)
    if masses.follower_assumed:
        warnings.warn(ingest_warning(
            path, f"no follower mass: assuming {DEFAULT_MASS_KG:g} kg for follower_thrust_n "
            "(set follower.mass_kg or --mass-kg)"), stacklevel=3)


def _meta(path: Path, bag: BagTopics, topic_map: TopicMapping, cmd_stream: Stream,
          cmd: CommandSamples, obs_source: str, masses: _Masses, window: _Window,
          lat: dict[str, float]) -> dict[str, Any]:
    """The FlightLog's ``meta``: where the numbers came from and how they were read."""
    return {
        "name": path.stem if path.is_file() else path.name,
        "source": SOURCE,
        "frame": "NED",
        "label_basis": "thrust" if cmd.kind == "thrust-setpoint" else "command",
        "command_topic": cmd_stream.topic,
        "command_type": cmd_stream.msgtype,
        "command_kind": cmd.kind,
        "obs_accel_source": obs_source,
        "leader_mass_kg": masses.leader_kg,
        "follower_mass_kg": masses.follower_kg,
        "mass_assumed": masses.follower_assumed or masses.leader_assumed,
        "source_frame": topic_map.frame,
        "time": topic_map.time,
        "file": str(path),
        "t_origin_s": float(window.t[0]) + bag.streams[topic_map.follower.state].origin_s,
        "dropped_samples": window.n_dropped,
        "stamp_latency_s": lat,
        "mapping": topic_map.as_dict(),
        "gravity_mps2": GRAVITY_MPS2,
    }


def read_rosbag(path: Path, *, mapping: Mapping[str, Any] | str | Path | None = None,
                mass_kg: float | None = None,
                progress: Callable[[int, int], None] | None = None) -> FlightLog:
    """Read one ROS 2 bag (a ``.db3``/``.mcap`` file or a bag folder) into a FlightLog.

    Args:
        path: The bag.
        mapping: Topic mapping (dict or TOML file) over
            :data:`~aerodock.ingest.rosbag.mapping.DEFAULT_MAPPING`.
        mass_kg: Mass of both vehicles, overriding the mapping.
        progress: Called as ``progress(messages_read, messages_to_read)`` while reading.

    Raises:
        IngestError: unreadable or empty bag, missing topics, unsupported message types, NaNs,
            bad stamps (duplicated, non-monotonic, zero, wrong unit), too little overlap.
    """
    path = Path(path)
    topic_map = TopicMapping.load(mapping)
    bag = _read_topics(path, topic_map, progress)
    lead, fol, frame = topic_map.leader, topic_map.follower, topic_map.frame
    # decode_state warns with a stacklevel counted from here: call it from this function.
    leader = decode_state(bag.require(lead.state, "leader state"), bag.optional(lead.twist),
                          frame, topic_map.odom_twist, path)
    follower = decode_state(bag.require(fol.state, "follower state"), bag.optional(fol.twist),
                            frame, topic_map.odom_twist, path)
    cmd_stream = bag.command(fol, required=True)
    assert cmd_stream is not None
    cmd = decode_command(cmd_stream, frame, path)
    leader_cmd_stream = bag.command(lead, required="leader.command" in topic_map.explicit)
    leader_cmd = decode_command(leader_cmd_stream, frame, path) if leader_cmd_stream else None
    imu = bag.optional(fol.imu)
    window = _common_window(path, leader, follower, cmd, ([imu.t_s] if imu else []) + (
        [leader_cmd.t_s] if leader_cmd else []), topic_map.max_gap_s)
    t, keep, rot_f = window.t, window.keep, follower.rot[window.keep]
    masses = _masses(topic_map, mass_kg, cmd, leader_cmd, path)
    cmd_accel, thrust_n = command_accel(cmd, t, rot_f, masses.follower_kg, _hover(fol, cmd, path))
    if imu is not None:
        obs, obs_source = observed_accel(imu, frame, t, rot_f, path), f"imu {imu.topic}"
    else:
        obs = differentiate(follower.t_s, follower.vel)[keep]
        obs_source = "differentiated follower velocity"
    extra = _extras(bag, topic_map, leader, leader_cmd, masses.leader_kg, t)
    lat = _stamp_latency(bag, topic_map)
    _warn(path, lat, masses)
    return FlightLog(
        t_s=t - t[0],
        leader_pos_m=resample_linear(leader.t_s, leader.pos, t),
        leader_vel_mps=resample_linear(leader.t_s, leader.vel, t),
        leader_quat=resample_quat(leader.t_s, leader.quat, t),
        follower_pos_m=follower.pos[keep], follower_vel_mps=follower.vel[keep],
        follower_quat=follower.quat[keep], follower_cmd_accel_mps2=cmd_accel,
        follower_thrust_n=thrust_n, follower_obs_accel_mps2=obs,
        meta=_meta(path, bag, topic_map, cmd_stream, cmd, obs_source, masses, window, lat),
        extra=extra,
    )
