"""Replay a FlightLog as ROS 2 state messages and record what ``aerodock node`` publishes.

Used by the end-to-end test and :mod:`aerodock.bench.node` (needs the ``aerodock[ros]`` extra).
The node runs in its own process (``aerodock node``, started by :func:`start_node`); this side
publishes both vehicles' states as ``nav_msgs/Odometry`` in the mapping's frame (the leader's
first, then the follower's), stamped with the wall clock when sent, and records every f_ext and
diagnostics message it gets back with its receive time, and the f_ext messages' DDS source and
reception times (where a latency tail comes from: :mod:`aerodock.bench.node`). One executor
with this side's node added once serves the whole replay (``rclpy.spin_once(node)`` would add
and remove the node on every call, costing this side time inside the measurement).
Everything stays on this machine (``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``)
and on a ROS domain of its own (:func:`free_domain_id`).
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from aerodock.flightlog import FlightLog
from aerodock.geometry import quat_to_rotmat
from aerodock.node.core import VehicleState, odometry_fields

LOCALHOST_ENV = {"ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}


def free_domain_id() -> int:
    """A ROS domain id for one run (1-100, from the process id: parallel runs do not meet)."""
    return 1 + os.getpid() % 100


def ros_env(domain_id: int) -> dict[str, str]:
    """The environment for a localhost-only ROS 2 process on ``domain_id``."""
    return {**os.environ, **LOCALHOST_ENV, "ROS_DOMAIN_ID": str(domain_id)}


def write_mapping(path: Path, leader_topic: str, follower_topic: str, *, frame: str = "enu",
                  twist: str = "body") -> Path:
    """A topic mapping TOML for an Odometry replay (the bag reader's format)."""
    path.write_text(
        f'frame = "{frame}"\nodom_twist = "{twist}"\n\n'
        f'[leader]\nstate = "{leader_topic}"\n\n[follower]\nstate = "{follower_topic}"\n'
    )
    return path


def start_node(model: Path, mapping: Path, domain_id: int, *, rate_hz: float = 100.0,
               publish: str | None = None, max_age_s: float = 0.05, duration_s: float = 30.0,
               output_topic: str = "/aerodock/f_ext",
               diagnostics_topic: str = "/aerodock/diagnostics") -> subprocess.Popen:
    """Start ``aerodock node`` in a subprocess (it stops by itself after ``duration_s``).

    ``publish``: its ``--publish`` mode (None: the node's default).
    """
    cmd = [sys.executable, "-c", "from aerodock.cli import main; main()", "node", "--model",
           str(model), "--mapping",
           str(mapping), "--rate", str(rate_hz), "--max-age", str(max_age_s), "--duration",
           str(duration_s), "--output-topic", output_topic, "--diagnostics-topic",
           diagnostics_topic]
    if publish is not None:
        cmd += ["--publish", publish]
    return subprocess.Popen(cmd, env=ros_env(domain_id), stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


@dataclass
class ReplayRecord:
    """What was sent and what came back.

    Attributes:
        sent: ``{"leader": {stamp_s: VehicleState}, "follower": {...}}`` (NED states as in the
            log, keyed by the stamp they were sent with).
        outputs: rows ``(receive_s, stamp_s, fx, fy, fz)`` of the f_ext messages.
        diagnostics: ``(receive_s, stamp_s, values)`` of the diagnostics messages.
        frame_ids: the f_ext messages' ``header.frame_id`` values.
        send_times_s: wall times of the follower messages sent.
        output_dds_s: f_ext stamp -> ``(source, reception)``: the DDS source time (the node's
            write) and reception time (this side's DDS layer) of that f_ext message, wall s
            (NaN when the middleware does not give them).
        published_s: follower stamp -> wall time when its ``publish`` call returned.
    """

    sent: dict[str, dict[float, VehicleState]] = field(
        default_factory=lambda: {"leader": {}, "follower": {}})
    outputs: list[tuple[float, float, float, float, float]] = field(default_factory=list)
    diagnostics: list[tuple[float, float, dict[str, str]]] = field(default_factory=list)
    frame_ids: set[str] = field(default_factory=set)
    send_times_s: list[float] = field(default_factory=list)
    output_dds_s: dict[float, tuple[float, float]] = field(default_factory=dict)
    published_s: dict[float, float] = field(default_factory=dict)

    def output_array(self) -> np.ndarray:
        """Outputs as an ``(n, 5)`` array (receive, stamp, fx, fy, fz)."""
        return np.asarray(self.outputs, dtype=float).reshape(-1, 5)


def _stamp(msg: Any) -> float:
    return msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9


def replay(log: FlightLog, domain_id: int, *, leader_topic: str, follower_topic: str,
           frame: str = "enu", twist: str = "body", rate_hz: float | None = None,
           leader_gap_s: tuple[float, float] | None = None,
           output_topic: str = "/aerodock/f_ext",
           diagnostics_topic: str = "/aerodock/diagnostics",
           wait_for_node_s: float = 30.0, tail_s: float = 0.3,
           on_send: Callable[[str], None] | None = None) -> ReplayRecord:
    """Publish ``log``'s states at its own rate (or ``rate_hz``) and record the node's output.

    Args:
        log: the flight (NED).
        domain_id: ROS domain (the node's).
        leader_topic: leader state topic.
        follower_topic: follower state topic.
        frame: Odometry world frame (``"enu"`` or ``"ned"``).
        twist: Odometry twist frame (``"body"`` or ``"world"``).
        rate_hz: publish rate (default: the log's sample rate).
        leader_gap_s: ``(start, end)`` in log time during which the leader is not published.
        output_topic: the node's f_ext topic.
        diagnostics_topic: the node's diagnostics topic.
        wait_for_node_s: how long to wait for the node to subscribe and publish.
        tail_s: how long to keep listening after the last message.
        on_send: called with ``"start"`` just before the first message and ``"end"`` just
            after the last (the benchmark reads CPU accounting there).

    Raises:
        TimeoutError: the node did not show up on the graph in time.
    """
    os.environ.update(LOCALHOST_ENV)
    os.environ["ROS_DOMAIN_ID"] = str(domain_id)
    import rclpy
    from nav_msgs.msg import Odometry
    from rclpy.executors import SingleThreadedExecutor

    rec = ReplayRecord()
    rclpy.init()
    node = rclpy.create_node("aerodock_replay")
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    try:
        pubs = {"leader": node.create_publisher(Odometry, leader_topic, 10),
                "follower": node.create_publisher(Odometry, follower_topic, 10)}
        _subscribe_outputs(node, rec, output_topic, diagnostics_topic)
        _wait_for_node(executor, pubs, rec, wait_for_node_s, leader_topic, follower_topic)
        period = 1.0 / rate_hz if rate_hz else float(np.median(np.diff(log.t_s)))
        rots = quat_to_rotmat(log.leader_quat), quat_to_rotmat(log.follower_quat)
        if on_send:
            on_send("start")
        _send_log(executor, pubs, rec, log, rots, period, Odometry, frame=frame, twist=twist,
                  leader_gap_s=leader_gap_s)
        if on_send:
            on_send("end")
        end = time.monotonic() + tail_s
        while time.monotonic() < end:
            executor.spin_once(timeout_sec=0.01)
    finally:
        executor.remove_node(node)
        executor.shutdown()
        node.destroy_node()
        rclpy.shutdown()
    return rec


def _subscribe_outputs(node: Any, rec: ReplayRecord, output_topic: str,
                       diagnostics_topic: str) -> None:
    """Subscribe ``node`` to the node's f_ext and diagnostics topics, recording into ``rec``.

    Args:
        node: this side's rclpy node.
        rec: the record the callbacks append to (outputs, frame ids, DDS times, diagnostics).
        output_topic: the node's f_ext topic.
        diagnostics_topic: the node's diagnostics topic.
    """
    from diagnostic_msgs.msg import DiagnosticArray
    from geometry_msgs.msg import Vector3Stamped

    def on_output(msg: Any, info: Any) -> None:
        stamp = _stamp(msg)
        rec.outputs.append((time.time(), stamp, msg.vector.x, msg.vector.y, msg.vector.z))
        rec.frame_ids.add(msg.header.frame_id)
        rec.output_dds_s[stamp] = (_dds_time_s(info, "source_timestamp"),
                                   _dds_time_s(info, "received_timestamp"))

    def on_diag(msg: Any) -> None:
        for status in msg.status:
            rec.diagnostics.append((time.time(), _stamp(msg),
                                    {kv.key: kv.value for kv in status.values}))

    node.create_subscription(Vector3Stamped, output_topic, on_output, 100)
    node.create_subscription(DiagnosticArray, diagnostics_topic, on_diag, 100)


def _wait_for_node(executor: Any, pubs: dict[str, Any], rec: ReplayRecord,
                   wait_for_node_s: float, leader_topic: str, follower_topic: str) -> None:
    """Spin until the node subscribes to both state topics and publishes, then clear ``rec``.

    What came back while waiting (outputs, diagnostics, DDS times) is dropped: the record
    starts with the replay.

    Raises:
        TimeoutError: the node did not show up on the graph within ``wait_for_node_s``.
    """
    deadline = time.monotonic() + wait_for_node_s
    while not (all(p.get_subscription_count() > 0 for p in pubs.values()) and rec.outputs):
        if time.monotonic() > deadline:
            raise TimeoutError(f"aerodock node did not subscribe to {leader_topic} and "
                               f"{follower_topic} within {wait_for_node_s:g} s")
        executor.spin_once(timeout_sec=0.05)
    rec.outputs.clear()
    rec.diagnostics.clear()
    rec.output_dds_s.clear()


def _sample_messages(odometry_cls: Any, log: FlightLog, i: int, rot_l: np.ndarray,
                     rot_f: np.ndarray, *, frame: str, twist: str,
                     leader_gap_s: tuple[float, float] | None,
                     ) -> tuple[dict[str, VehicleState], dict[str, Any]]:
    """Sample ``i`` of ``log`` as states and unstamped Odometry messages, per role.

    Args:
        odometry_cls: ``nav_msgs/msg/Odometry``.
        log: the flight (NED).
        i: sample index.
        rot_l: the leader's rotation matrices, ``(n, 3, 3)``.
        rot_f: the follower's rotation matrices, ``(n, 3, 3)``.
        frame: Odometry world frame.
        twist: Odometry twist frame.
        leader_gap_s: ``(start, end)`` in log time during which the leader is left out.

    Returns:
        ``(states, messages)``, both keyed by role (``"leader"`` missing inside the gap).
    """
    t_log = float(log.t_s[i] - log.t_s[0])
    states = {"leader": (log.leader_pos_m[i], log.leader_vel_mps[i], rot_l[i]),
              "follower": (log.follower_pos_m[i], log.follower_vel_mps[i], rot_f[i])}
    if leader_gap_s and leader_gap_s[0] <= t_log < leader_gap_s[1]:
        del states["leader"]
    sample = {role: VehicleState(np.array(p, float), np.array(v, float), rot, 0.0)
              for role, (p, v, rot) in states.items()}
    msgs = {role: odometry_message(odometry_cls, state, 0.0, frame, twist)
            for role, state in sample.items()}
    return sample, msgs


def _send_log(executor: Any, pubs: dict[str, Any], rec: ReplayRecord, log: FlightLog,
              rots: tuple[np.ndarray, np.ndarray], period_s: float, odometry_cls: Any, *,
              frame: str, twist: str, leader_gap_s: tuple[float, float] | None) -> None:
    """Publish every sample of ``log`` every ``period_s``, recording what was sent in ``rec``.

    ``rots`` are the leader's and the follower's rotation matrices (computed by the caller,
    before the measured send window opens).

    Each sample's messages are built before its send time and stamped at it: the stamp is
    when the state is sent, not when this side's Python began building the messages. The
    executor is spun while waiting for the send time (so callbacks are served meanwhile).
    """
    rot_l, rot_f = rots
    start = time.monotonic()
    for i in range(log.n_samples):
        sample, msgs = _sample_messages(odometry_cls, log, i, rot_l, rot_f, frame=frame,
                                        twist=twist, leader_gap_s=leader_gap_s)
        target = start + i * period_s
        while (now := time.monotonic()) < target:
            executor.spin_once(timeout_sec=target - now)  # returns early for a callback
        stamp = stamp_of(time.time())
        for role, msg in msgs.items():
            set_stamp(msg.header, stamp)
            pubs[role].publish(msg)
            if role == "follower":
                rec.published_s[stamp] = time.time()
            rec.sent[role][stamp] = replace(sample[role], stamp_s=stamp)
        rec.send_times_s.append(stamp)


def _dds_time_s(info: Any, key: str) -> float:
    """A message info's DDS time (ns since the epoch) in s; NaN when the middleware gives 0."""
    ns = (info or {}).get(key, 0)
    return ns * 1e-9 if ns else float("nan")


def odometry_message(cls: Any, state: VehicleState, stamp_s: float, frame: str,
                     twist: str) -> Any:
    """A NED ``state`` as a ``cls`` (``nav_msgs/msg/Odometry``) in the mapping's frame."""
    pos, quat, lin = odometry_fields(state, frame=frame, twist=twist)
    msg = cls()
    set_stamp(msg.header, stamp_s)
    msg.header.frame_id = "map" if frame == "enu" else "map_ned"
    msg.child_frame_id = "base_link"
    p = msg.pose.pose
    p.position.x, p.position.y, p.position.z = (float(v) for v in pos)
    p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z = (float(v) for v in quat)
    t = msg.twist.twist.linear
    t.x, t.y, t.z = (float(v) for v in lin)
    return msg


def set_stamp(header: Any, stamp_s: float) -> None:
    """Set a ``std_msgs/Header``'s stamp to ``stamp_s`` (wall s), as :func:`stamp_of` reads it."""
    header.stamp.sec = int(stamp_s)
    header.stamp.nanosec = int(round((stamp_s - int(stamp_s)) * 1e9)) % 1_000_000_000


def stamp_of(msg_stamp_s: float) -> float:
    """A stamp as the node reports it (``sec + nanosec * 1e-9``, rounded like the message)."""
    sec = int(msg_stamp_s)
    nanosec = int(round((msg_stamp_s - sec) * 1e9)) % 1_000_000_000
    return sec + nanosec * 1e-9
