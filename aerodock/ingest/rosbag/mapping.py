"""The topic mapping of a ROS 2 bag (also the ROS node's): which topic carries what.

A mapping is a TOML file or a dict; every key is optional and defaults to
:data:`DEFAULT_MAPPING`, which matches a Freyja-like setup with the paper's vehicle names (leader
``alpha``, follower ``bravo``)::

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
    # hover_thrust = 0.5                   # a PX4 thrust set point's hover thrust

:func:`load_mapping` gives the merged mapping as a dict (what the ROS node takes);
:meth:`TopicMapping.load` the same as typed records (what the bag reader takes).
"""

from __future__ import annotations

import copy
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from aerodock.fileio import MAX_TOML_BYTES, InputError, read_input_text
from aerodock.ingest.common import check_hover_thrust, check_mass
from aerodock.ingest.errors import IngestError

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
OPTIONAL_TOPIC_KEYS = ("twist", "reference", "imu", "command")
ROLES = ("leader", "follower")


def load_mapping(
    mapping: Mapping[str, Any] | str | Path | None,
) -> tuple[dict[str, Any], set[str]]:
    """The default mapping overridden by ``mapping`` (a dict or a TOML file).

    Returns:
        ``(mapping, explicit)``: the merged mapping, and the names the user set: ``"role.key"``
        for a role's keys, the bare name for a top-level option (``"frame"``).

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
        user = _read_toml(mapping, where)
    merged, explicit = _merge(user, where)
    _check_options(merged, where)
    for role in ROLES:
        _check_role(merged[role], role, where)
    if not merged["follower"]["command"]:
        raise IngestError(where, "follower.command (the commanded acceleration or attitude-"
                                 "thrust topic) is required")
    return merged, explicit


def _read_toml(path: str | Path, where: str) -> dict[str, Any]:
    try:
        return tomllib.loads(read_input_text(path, "mapping file", MAX_TOML_BYTES))
    except FileNotFoundError:
        raise IngestError(where, "mapping file not found") from None
    except InputError as err:
        raise IngestError(where, err.reason) from None
    except (OSError, UnicodeDecodeError) as err:
        raise IngestError(where, f"cannot read mapping file ({err})") from None
    except tomllib.TOMLDecodeError as err:
        raise IngestError(where, f"invalid TOML ({err})") from None
    except RecursionError:
        raise IngestError(where, "invalid TOML (nested too deeply)") from None


def _merge(user: dict[str, Any], where: str) -> tuple[dict[str, Any], set[str]]:
    """The default mapping with the user's values in place; unknown keys are refused."""
    merged = copy.deepcopy(DEFAULT_MAPPING)
    explicit: set[str] = set()
    for key, value in user.items():
        if key not in DEFAULT_MAPPING:
            raise IngestError(where, f"unknown key {key!r} (known: {', '.join(DEFAULT_MAPPING)})")
        if key in ROLES:
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
            explicit.add(key)
    return merged, explicit


def _check_options(merged: dict[str, Any], where: str) -> None:
    """Normalise and check the top-level options in place (``frame``, ``time``, ...)."""
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


def _check_role(entries: dict[str, Any], role: str, where: str) -> None:
    """Normalise and check one role's table in place (command becomes a list of topics)."""
    for key, value in entries.items():
        if key == "mass_kg":
            if value is not None:
                entries[key] = check_mass(value, where, f"{role}.mass_kg")
        elif key == "hover_thrust":
            if value is not None and (isinstance(value, bool) or not isinstance(
                    value, int | float) or not check_hover_thrust(float(value))):
                raise IngestError(where, f"{role}.hover_thrust = {value!r}: expected the "
                                         "normalised hover thrust, 0.05-0.95")
        elif key == "command":
            topics = [value] if isinstance(value, str) else value
            if not isinstance(topics, list) or not all(isinstance(t, str) for t in topics):
                raise IngestError(where, f"{role}.command must be a topic or a list of them")
            entries[key] = [t for t in topics if t]
        elif not isinstance(value, str):
            raise IngestError(where, f"{role}.{key} must be a topic name (a string)")
    if not entries["state"]:
        raise IngestError(where, f"{role}.state (the {role}'s state topic) is required")


@dataclass(frozen=True)
class RoleTopics:
    """One vehicle's entries of a topic mapping (``""``: no such topic).

    Attributes:
        role: ``"leader"`` or ``"follower"``.
        state: its state topic.
        twist: a TwistStamped topic giving a PoseStamped state's velocity.
        command: command topics, the first present in the bag is used.
        reference: the follower's reference topic (a leader has none).
        imu: the follower's IMU topic (a leader has none).
        mass_kg: its mass, if the mapping gives it.
        hover_thrust: its normalised hover thrust (PX4 thrust set points), if given.
    """

    role: str
    state: str
    twist: str
    command: tuple[str, ...]
    reference: str
    imu: str
    mass_kg: float | None
    hover_thrust: float | None

    def topics(self) -> list[str]:
        """Every topic this role names (the state first)."""
        return [t for t in (self.state, self.twist, *self.command, self.reference, self.imu) if t]

    def as_dict(self) -> dict[str, Any]:
        """The role's table as :func:`load_mapping` gives it (recorded in a FlightLog's meta)."""
        return {key: list(self.command) if key == "command" else getattr(self, key)
                for key in DEFAULT_MAPPING[self.role]}


@dataclass(frozen=True)
class TopicMapping:
    """A checked topic mapping: the options and each vehicle's topics.

    Attributes:
        frame: ``"enu"`` or ``"ned"``, the world and body frames of standard ROS messages.
        time: ``"header"`` (header stamps) or ``"bag"`` (the bag's receive times).
        odom_twist: ``"body"`` or ``"world"``, the frame of an Odometry message's twist.
        max_gap_s: samples where the leader or the command has a longer gap are dropped.
        leader: the leader's topics.
        follower: the follower's topics.
        explicit: the ``"role.key"`` names the user set (their topics must be in the bag), and
            the top-level options the user set (``"frame"``).
    """

    frame: str
    time: str
    odom_twist: str
    max_gap_s: float
    leader: RoleTopics
    follower: RoleTopics
    explicit: frozenset[str]

    @classmethod
    def load(cls, mapping: Mapping[str, Any] | str | Path | None) -> TopicMapping:
        """The default mapping overridden by ``mapping`` (see :func:`load_mapping`).

        Raises:
            IngestError: unreadable TOML, unknown keys, or values of the wrong kind.
        """
        merged, explicit = load_mapping(mapping)
        roles = {role: RoleTopics(
            role=role, state=merged[role]["state"], twist=merged[role]["twist"],
            command=tuple(merged[role]["command"]), reference=merged[role].get("reference", ""),
            imu=merged[role].get("imu", ""), mass_kg=merged[role]["mass_kg"],
            hover_thrust=merged[role]["hover_thrust"],
        ) for role in ROLES}
        return cls(frame=merged["frame"], time=merged["time"], odom_twist=merged["odom_twist"],
                   max_gap_s=merged["max_gap_s"], leader=roles["leader"],
                   follower=roles["follower"], explicit=frozenset(explicit))

    def topics(self) -> set[str]:
        """Every topic the mapping names (the ones the reader deserialises)."""
        return set(self.leader.topics()) | set(self.follower.topics())

    def as_dict(self) -> dict[str, Any]:
        """Both roles' tables (what a FlightLog's ``meta["mapping"]`` records)."""
        return {"leader": self.leader.as_dict(), "follower": self.follower.as_dict()}
