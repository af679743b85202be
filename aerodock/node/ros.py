"""The ``rclpy`` node of ``aerodock node`` (needs the ``aerodock[ros]`` extra).

It subscribes to the leader's and the follower's state topics of the topic mapping (the same
TOML as the bag reader, :mod:`aerodock.ingest.rosbag`), finds each topic's type on the ROS graph
(``nav_msgs/msg/Odometry``, ``freyja_msgs/msg/CurrentState`` or ``px4_msgs/msg/VehicleOdometry``),
and publishes, on each follower state message with a ``rate_hz`` watchdog (``on-follower``) or
at ``rate_hz`` (``timer``; :class:`aerodock.node.core.PublishMode`):

- ``f_ext`` (``geometry_msgs/msg/Vector3Stamped``): the predicted downwash acceleration on the
  follower, m/s², in the consumer's world frame (NED for Freyja and PX4, the mapping's frame for
  Odometry: ENU by default, REP 103), stamped with the node's clock when published; zero when
  the inputs are stale; none before the follower's state type is known (the frame is then
  undecided);
- diagnostics (``diagnostic_msgs/msg/DiagnosticArray``, one status named ``aerodock f_ext``):
  ``trigger`` (``follower``, ``timer`` or ``watchdog``: :func:`aerodock.node.core.output_trigger`),
  ``latency_ms`` (the trigger, message callback or tick, to the output's stamp, taken just
  before it is published), ``queue_ms`` (for a
  follower-triggered output: the message's wait in the node, from its DDS reception to its
  callback; ``nan`` otherwise), ``compute_ms`` (predictor), ``leader_age_ms``,
  ``follower_age_ms`` (since each state was received), ``stale`` (``true``/``false``),
  ``stale_reason`` (why, ``""`` when fresh), ``leader_stamp``, ``follower_stamp`` (the states'
  own stamps, s), ``tick`` (the output's sequence number), ``output_frame`` (``ned``, ``enu``
  or ``undecided``) and ``output_frame_rule`` (why), and the refused messages
  (:class:`aerodock.node.refusals.RefusalLog`: ``refused_total``, ``refused_recent``, a
  ``refused <role>: <kind>`` count per kind, bounded). The level is OK, or STALE when the output
  is zero for unusable inputs (the status message is then the reason) or not published.

Each vehicle's messages pass an :class:`aerodock.node.core.InputMonitor` (stamps that are zero,
go backwards or freeze; a message repeated by a relay); a message refused (by the monitor, the
plausibility rules or its converter) is counted in a :class:`aerodock.node.refusals.RefusalLog`. The
output frame and its ``frame_id`` are decided once, when the follower's state type is known
(:func:`aerodock.node.core.output_frame_choice`): at start with ``--state-type`` or
``--output-frame``, else when the type is found on the graph; no f_ext goes out before, so the
frame never changes while the node runs.

ROS's own arguments (``--ros-args``: remapping, parameters such as ``use_sim_time``, the log
level) go to ``rclpy.init``; :func:`ros_args_error` checks them first.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from aerodock.node.core import (
    CURRENT_STATE,
    DEFAULT_MAX_AGE_S,
    DEFAULT_PUBLISH_MODE,
    DEFAULT_RATE_HZ,
    FOLLOWER_EVENT,
    ODOMETRY,
    PX4_ODOMETRY,
    STATE_TYPES,
    TICK_EVENT,
    TRIGGER_FOLLOWER,
    UNDECIDED,
    InputMonitor,
    PublishMode,
    StepResult,
    VehicleState,
    current_state,
    implausible,
    odometry_state,
    output_frame_choice,
    output_trigger,
    prediction_step,
    px4_odometry_state,
)
from aerodock.node.refusals import RefusalLog

STATUS_NAME = "aerodock f_ext"
STATE_QUEUE_DEPTH = 1
"""State messages kept per topic while the node is busy: the newest only. Only the newest
state matters to a controller; with the sensor-data default (5), a node kept off the CPU for
tens of milliseconds answered each queued state in turn, the newest last (docs/deploy.md)."""


@dataclass
class NodeSettings:
    """What the node subscribes to and publishes.

    Attributes:
        mapping: merged topic mapping (:func:`aerodock.ingest.rosbag.load_mapping`).
        rate_hz: output rate (``timer``), the watchdog's rate (``on-follower``).
        publish: what triggers an output (:class:`aerodock.node.core.PublishMode`).
        max_age_s: oldest accepted input (older: zero output, stale flag).
        output_topic: f_ext topic.
        diagnostics_topic: diagnostics topic.
        output_frame: ``"ned"``, ``"enu"``, or ``None``: automatic, decided once the follower's
            type is known by :func:`aerodock.node.core.output_frame_choice`.
        state_types: topic -> ROS type name, for topics whose type is not to be discovered.
        frame_ids: output ``header.frame_id`` per output frame.
        wake_scales: a leader-aware model's wake scales (k,) for the flown vehicles
            (:func:`aerodock.node.core.configured_wake_scales`); None: the model file's
            training scales.
    """

    mapping: dict[str, Any]
    rate_hz: float = DEFAULT_RATE_HZ
    publish: PublishMode = DEFAULT_PUBLISH_MODE
    max_age_s: float = DEFAULT_MAX_AGE_S
    output_topic: str = "/aerodock/f_ext"
    diagnostics_topic: str = "/aerodock/diagnostics"
    output_frame: str | None = None
    state_types: dict[str, str] = field(default_factory=dict)
    frame_ids: dict[str, str] = field(default_factory=lambda: {"ned": "map_ned", "enu": "map"})
    wake_scales: tuple[float, ...] | None = None


def message_class(type_name: str) -> Any:
    """The Python class of a ROS message type name such as ``nav_msgs/msg/Odometry``.

    Raises:
        RuntimeError: the message package is not installed.
    """
    package, _, name = type_name.partition("/msg/")
    try:
        module = __import__(f"{package}.msg", fromlist=[name])
        return getattr(module, name)
    except (ImportError, AttributeError):
        hint = {"freyja_msgs": "build Freyja's freyja_msgs in your ROS 2 workspace and source it",
                "px4_msgs": "build PX4's px4_msgs in your ROS 2 workspace and source it"}.get(
            package, f"pip install ros-{package.replace('_', '-')}")
        raise RuntimeError(f"message type {type_name} is not available ({hint})") from None


def _stamp_s(msg: Any) -> float | None:
    header = getattr(msg, "header", None)
    if header is None:
        return None
    return header.stamp.sec + header.stamp.nanosec * 1e-9


def state_from_message(type_name: str, msg: Any, mapping: dict[str, Any],
                       received_s: float) -> VehicleState:
    """A received state message as a NED :class:`VehicleState` (see :mod:`aerodock.node.core`)."""
    if type_name == ODOMETRY:
        pose, lin = msg.pose.pose, msg.twist.twist.linear
        o = pose.orientation
        return odometry_state(
            (pose.position.x, pose.position.y, pose.position.z), (o.w, o.x, o.y, o.z),
            (lin.x, lin.y, lin.z), frame=mapping["frame"], twist=mapping["odom_twist"],
            received_s=received_s, stamp_s=_stamp_s(msg))
    if type_name == CURRENT_STATE:
        return current_state(msg.state_vector, received_s=received_s, stamp_s=_stamp_s(msg))
    if type_name == PX4_ODOMETRY:
        return px4_odometry_state(msg.position, msg.q, msg.velocity, int(msg.velocity_frame),
                                  received_s=received_s, timestamp_us=int(msg.timestamp))
    raise ValueError(f"state type {type_name} is not one of {', '.join(STATE_TYPES)}")


NODE_NAME = "aerodock_f_ext"
"""The node's ROS 2 name (relative topic names expand in its namespace)."""


def topic_name_error(name: str, node_name: str = NODE_NAME) -> str | None:
    """Why ROS 2 would refuse ``name`` as a topic of the node (``None``: it takes it).

    rclpy's own rules, checked before the node starts: the name as given (empty, a token that
    starts with a digit, characters other than alphanumerics, ``_``, ``/``, ``~``, ``{}``), then
    fully expanded in the node's namespace (a repeated or trailing ``/``, an unknown
    substitution)."""
    from rclpy.exceptions import InvalidTopicNameException
    from rclpy.expand_topic_name import expand_topic_name
    from rclpy.validate_full_topic_name import validate_full_topic_name
    from rclpy.validate_topic_name import validate_topic_name

    try:
        validate_topic_name(name)
        validate_full_topic_name(expand_topic_name(name, node_name, "/"))
    except (InvalidTopicNameException, ValueError) as err:
        return str(err).splitlines()[0].rstrip(":").split(", at /")[0]
    return None


def make_node(predictor: Any, settings: NodeSettings, *, node_name: str = NODE_NAME,
              warnings_to_log: list[str] | None = None) -> Any:
    """Build the node (``rclpy.init`` must have been called). See the module docstring.

    The ``Node`` subclass is made here because rclpy is imported only when a node is built
    (the ``aerodock[ros]`` extra); its behaviour is :class:`_PredictorNodeMixin`'s.
    """
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
    from geometry_msgs.msg import Vector3Stamped
    from rclpy.node import Node
    from rclpy.qos import HistoryPolicy, QoSProfile, qos_profile_sensor_data

    class PredictorNode(_PredictorNodeMixin, Node):
        """Subscribes to both vehicles' states and publishes f_ext (see the module docstring)."""

        def __init__(self) -> None:
            super().__init__(node_name)
            self.predictor = predictor
            self.settings = settings
            self._node_name = node_name
            self._f_ext_type = Vector3Stamped
            self._diag_types = (DiagnosticArray, DiagnosticStatus, KeyValue)
            self.wake_scales = (None if settings.wake_scales is None
                                else np.asarray(settings.wake_scales, dtype=float))
            self.states: dict[str, VehicleState | None] = {"leader": None, "follower": None}
            self.topics = {role: settings.mapping[role]["state"]
                           for role in ("leader", "follower")}
            self.types: dict[str, str] = {}
            self.monitors = {role: InputMonitor() for role in self.topics}
            self.output_frame: str | None = None
            self.frame_rule = ""
            self.frame_id = ""
            self._decide_frame(settings.state_types.get(self.topics["follower"]))
            self.publish_mode = PublishMode(settings.publish)
            self.period_s = 1.0 / settings.rate_hz
            self.last_follower_output_s: float | None = None
            self.tick = 0  # outputs published
            self.refusals = RefusalLog()
            self.pub = self.create_publisher(Vector3Stamped, settings.output_topic, 10)
            self.diag_pub = self.create_publisher(DiagnosticArray, settings.diagnostics_topic, 10)
            # best effort as sensor data (PX4 publishes so), keeping only the newest message:
            # a state superseded while the node waited for a CPU is not worth answering
            self._qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=STATE_QUEUE_DEPTH,
                                   reliability=qos_profile_sensor_data.reliability,
                                   durability=qos_profile_sensor_data.durability)
            self._subs: list[Any] = []
            for note in warnings_to_log or []:
                self.get_logger().warning(note)
            self._connect()
            self.timer = self.create_timer(1.0 / settings.rate_hz, self._on_tick)
            if len(self.types) < 2:
                self.graph_timer = self.create_timer(0.1, self._connect)

    return PredictorNode()


class _PredictorNodeMixin:
    """The behaviour of :func:`make_node`'s node, mixed into ``rclpy.node.Node`` there.

    Its attributes are set by the node's ``__init__`` (in :func:`make_node`); the methods use
    ``Node``'s own (``get_logger``, ``create_subscription``, ``get_clock``, ...).
    """

    predictor: Any
    settings: NodeSettings
    states: dict[str, VehicleState | None]
    topics: dict[str, str]
    types: dict[str, str]
    monitors: dict[str, InputMonitor]
    output_frame: str | None
    frame_rule: str
    frame_id: str
    publish_mode: PublishMode
    period_s: float
    last_follower_output_s: float | None
    tick: int
    refusals: RefusalLog
    wake_scales: np.ndarray | None
    pub: Any
    diag_pub: Any
    _node_name: str
    _f_ext_type: Any
    _diag_types: tuple[Any, Any, Any]
    _qos: Any
    _subs: list[Any]

    def _decide_frame(self, follower_type: str | None) -> None:
        """Fix the output frame once it can be decided (see the module docstring)."""
        if self.output_frame is not None:
            return
        frame, self.frame_rule = output_frame_choice(
            self.settings.output_frame, self.settings.mapping["frame"], follower_type)
        if frame is not None:
            self.output_frame = frame
            self.frame_id = self.settings.frame_ids[frame]
            self.get_logger().info(f"f_ext in {frame.upper()} ({self.frame_id}): "
                                   f"{self.frame_rule}")

    def _connect(self) -> None:
        """Subscribe to the state topics whose type is known or now on the graph."""
        graph = dict(self.get_topic_names_and_types())
        for role, topic in self.topics.items():
            if role in self.types:
                continue
            type_name = self.settings.state_types.get(topic)
            if type_name is None:
                found = [t for t in graph.get(topic, []) if t in STATE_TYPES]
                if not found:
                    continue
                type_name = found[0]
            cls = message_class(type_name)
            self.types[role] = type_name
            self._subs.append(self.create_subscription(
                cls, topic, self._callback(role, type_name), self._qos))
            self.get_logger().info(f"{role} state: {topic} ({type_name})")
            if role == "follower":
                self._decide_frame(type_name)
        if len(self.types) == 2 and hasattr(self, "graph_timer"):
            self.graph_timer.cancel()

    def _callback(self, role: str, type_name: str) -> Any:
        mapping = self.settings.mapping

        def on_state(msg: Any, info: Any) -> None:
            received, received_wall = time.monotonic(), time.time()
            try:
                state = state_from_message(type_name, msg, mapping, received)
            except ValueError as err:  # a message we cannot use: the input goes stale
                why: str | None = f"unusable message ({err})"
                self.monitors[role].verdict = why
            else:
                why = self.monitors[role].receive(state) or implausible(state)
                self.states[role] = state
            if why:
                self.refusals.record(role, why)
            if role != "follower":
                return
            trigger = output_trigger(self.publish_mode, FOLLOWER_EVENT, received,
                                     self.last_follower_output_s, self.period_s)
            if trigger is not None:
                dds_ns = info.get("received_timestamp", 0) if info else 0
                queue_s = received_wall - dds_ns * 1e-9 if dds_ns else float("nan")
                self._publish(trigger, received, queue_s)

        return on_state

    def _on_tick(self) -> None:
        now = time.monotonic()
        trigger = output_trigger(self.publish_mode, TICK_EVENT, now,
                                 self.last_follower_output_s, self.period_s)
        if trigger is not None:
            self._publish(trigger, now, float("nan"))

    def _publish(self, trigger: str, start: float, queue_s: float) -> None:
        """One :func:`prediction_step` on the newest states, published with diagnostics
        (the diagnostics only, while the output frame is undecided)."""
        result = prediction_step(self.predictor, self.states["leader"],
                                 self.states["follower"], start,
                                 max_age_s=self.settings.max_age_s,
                                 output_frame=self.output_frame or "ned",
                                 faults={r: m.verdict for r, m in self.monitors.items()},
                                 wake_scales=self.wake_scales)
        stamp = self.get_clock().now().to_msg()
        latency_ms = (time.monotonic() - start) * 1e3  # trigger to the output's stamp
        if self.output_frame is None:
            self.diag_pub.publish(self._diagnostics(result, stamp, latency_ms, trigger,
                                                    queue_s))
            return
        out = self._f_ext_type()
        out.header.stamp = stamp
        out.header.frame_id = self.frame_id
        out.vector.x, out.vector.y, out.vector.z = (float(v) for v in result.f_ext_mps2)
        self.pub.publish(out)
        if trigger == TRIGGER_FOLLOWER:
            self.last_follower_output_s = time.monotonic()
        self.diag_pub.publish(self._diagnostics(result, stamp, latency_ms, trigger, queue_s))
        self.tick += 1

    def _diagnostics(self, result: StepResult, stamp: Any, latency_ms: float, trigger: str,
                     queue_s: float) -> Any:
        diagnostic_array, diagnostic_status, key_value = self._diag_types
        status = diagnostic_status()
        status.name = STATUS_NAME
        status.hardware_id = self._node_name
        status.level = diagnostic_status.STALE if result.stale else diagnostic_status.OK
        status.message = (f"publishing zero: {result.reason}" if result.stale else "ok")
        if self.output_frame is None:
            status.level = diagnostic_status.STALE
            status.message = f"publishing no f_ext: {self.frame_rule}"
        values = _diagnostic_values(result, latency_ms, trigger, queue_s, tick=self.tick,
                                    output_frame=self.output_frame, frame_rule=self.frame_rule,
                                    refusals=self.refusals)
        status.values = [key_value(key=k, value=v) for k, v in values.items()]
        array = diagnostic_array()
        array.header.stamp = stamp
        array.status = [status]
        return array


def _diagnostic_values(result: StepResult, latency_ms: float, trigger: str, queue_s: float, *,
                       tick: int, output_frame: str | None, frame_rule: str,
                       refusals: RefusalLog) -> dict[str, str]:
    """The diagnostics status's key-value pairs for one output (see the module docstring).

    Args:
        result: the prediction step.
        latency_ms: trigger to the output's stamp, ms.
        trigger: what triggered the output.
        queue_s: the follower message's wait in the node, s (NaN: not follower-triggered).
        tick: outputs published before this one.
        output_frame: ``"ned"``, ``"enu"`` or None (undecided).
        frame_rule: why that output frame.
        refusals: the node's refused messages.

    Returns:
        key -> value, in the order they are published.
    """
    def ms(value: float) -> str:
        return "inf" if not np.isfinite(value) else f"{value * 1e3:.4f}"

    return {
        "trigger": trigger,
        "latency_ms": f"{latency_ms:.4f}",
        "queue_ms": f"{queue_s * 1e3:.4f}",
        "compute_ms": ms(result.compute_s),
        "leader_age_ms": ms(result.leader_age_s),
        "follower_age_ms": ms(result.follower_age_s),
        "stale": "true" if result.stale else "false",
        "stale_reason": result.reason,
        "leader_stamp": repr(result.leader_stamp_s),
        "follower_stamp": repr(result.follower_stamp_s),
        "tick": str(tick),
        "output_frame": output_frame or UNDECIDED,
        "output_frame_rule": frame_rule,
        **refusals.values(),
    }


def ros_args_error(ros_args: list[str]) -> str | None:
    """Why rclpy would refuse ``ros_args`` (``--ros-args`` and what follows it), or None.

    They are parsed by rcl in a context of its own, its error log silenced, so that a refusal
    (an unknown flag, a remap or parameter rule rcl cannot parse) is one line of ours.
    """
    import rclpy.logging
    from rclpy.context import Context

    quiet, unset = rclpy.logging.LoggingSeverity.FATAL, rclpy.logging.LoggingSeverity.UNSET
    rclpy.logging.set_logger_level("rcl", quiet)
    context = Context()
    try:
        context.init([NODE_NAME, *ros_args], initialize_logging=False)
    except Exception as err:  # noqa: BLE001 - rclpy's pybind11 errors have no common base
        text = str(err).removeprefix("failed to initialize rcl: ").split(". Error:")[0]
        if type(err).__name__ == "UnknownROSArgsError":
            text = f"unknown ROS arguments {text}"
        return text.split(", at /")[0]
    finally:
        rclpy.logging.set_logger_level("rcl", unset)
        context.try_shutdown()
    return None


def run_node(predictor: Any, settings: NodeSettings, *, duration_s: float | None = None,
             warnings_to_log: list[str] | None = None, ros_args: list[str] | None = None) -> int:
    """Run the node until interrupted (or for ``duration_s``); returns the number of outputs.

    ``ros_args``: ``--ros-args ...`` for ``rclpy.init`` (remapping, parameters, log level;
    check them with :func:`ros_args_error` first).
    """
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    rclpy.init(args=[NODE_NAME, *(ros_args or [])])
    node = make_node(predictor, settings, warnings_to_log=warnings_to_log)
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    end = None if duration_s is None else time.monotonic() + duration_s
    try:
        while rclpy.ok() and (end is None or time.monotonic() < end):
            executor.spin_once(timeout_sec=0.05)
    except KeyboardInterrupt:
        pass
    finally:
        outputs = node.tick
        executor.remove_node(node)
        node.destroy_node()
        if rclpy.ok():
            rclpy.shutdown()
    return outputs
