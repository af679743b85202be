"""What makes ``aerodock node`` publish: each follower message (``on-follower``), the watchdog
when they stop, the timer alone (``timer``); in which frame (Odometry found on the graph: ENU;
nothing before the follower's type is known); what it does with garbage (refused, counted on
the diagnostics, the count bounded).

The node runs in this process with a client node on one executor, on a localhost ROS domain of
this test run; the client sends one state at a time and waits for what comes back (lock step),
so nothing here depends on how fast the machine is: no timing is asserted.
"""

from __future__ import annotations

import time

import numpy as np
import pytest
from node_helpers import orbit_log, random_model

pytest.importorskip("rclpy")
pytest.importorskip("nav_msgs.msg")
pytest.importorskip("diagnostic_msgs.msg")

from aerodock.geometry import quat_to_rotmat  # noqa: E402
from aerodock.ingest.rosbag import load_mapping  # noqa: E402
from aerodock.learning.runtime import Predictor  # noqa: E402
from aerodock.node.core import (  # noqa: E402
    ODOMETRY,
    PublishMode,
    VehicleState,
    model_inputs,
    to_output_frame,
)
from aerodock.node.replay import (  # noqa: E402
    LOCALHOST_ENV,
    free_domain_id,
    odometry_message,
    stamp_of,
    write_mapping,
)
from aerodock.node.ros import NodeSettings, make_node  # noqa: E402

LEADER, FOLLOWER = "/alpha/odom", "/bravo/odom"
MAX_AGE_S = 5.0  # lock step on a loaded machine: never stale for age
WAIT_S = 60.0  # generous: a failure to answer, not slowness, is what fails


class Harness:
    """The node under test and a client that sends states and records the node's outputs."""

    def __init__(self, tmp_path, publish: PublishMode, rate_hz: float, *,
                 state_types: dict[str, str] | None = None, mapping_text: str | None = None
                 ) -> None:
        import rclpy
        from diagnostic_msgs.msg import DiagnosticArray
        from geometry_msgs.msg import Vector3Stamped
        from nav_msgs.msg import Odometry
        from rclpy.executors import SingleThreadedExecutor

        self.predictor = Predictor.load(random_model(tmp_path / "model"))
        path = write_mapping(tmp_path / "mapping.toml", LEADER, FOLLOWER)
        if mapping_text is not None:
            path.write_text(mapping_text)
        mapping, _ = load_mapping(path)
        settings = NodeSettings(
            mapping=mapping, rate_hz=rate_hz, publish=publish, max_age_s=MAX_AGE_S,
            state_types={LEADER: ODOMETRY, FOLLOWER: ODOMETRY} if state_types is None
            else state_types)
        self.node = make_node(self.predictor, settings, node_name="aerodock_under_test")
        self.client = rclpy.create_node("aerodock_test_client")
        self.odometry = Odometry
        self.pubs = {"leader": self.client.create_publisher(Odometry, LEADER, 10),
                     "follower": self.client.create_publisher(Odometry, FOLLOWER, 10)}
        self.vectors: dict[float, np.ndarray] = {}
        self.diagnostics: dict[float, dict[str, str]] = {}
        self.order: list[float] = []  # output stamps as the diagnostics arrived
        self.frame_ids: set[str] = set()

        def on_output(msg):
            self.vectors[_stamp(msg)] = np.array([msg.vector.x, msg.vector.y, msg.vector.z])
            self.frame_ids.add(msg.header.frame_id)

        def on_diag(msg):
            self.diagnostics[_stamp(msg)] = {kv.key: kv.value for kv in msg.status[0].values}
            self.order.append(_stamp(msg))

        self.client.create_subscription(Vector3Stamped, "/aerodock/f_ext", on_output, 1000)
        self.client.create_subscription(DiagnosticArray, "/aerodock/diagnostics", on_diag, 1000)
        self.executor = SingleThreadedExecutor()
        self.executor.add_node(self.node)
        self.executor.add_node(self.client)
        # matched both ways: the node hears the client, the client hears the node's outputs
        self.spin_until(lambda: all(p.get_subscription_count() > 0 for p in self.pubs.values())
                        and self.node.pub.get_subscription_count() > 0
                        and self.node.diag_pub.get_subscription_count() > 0, "discovery")

    def spin_until(self, done, what: str) -> None:
        deadline = time.monotonic() + WAIT_S
        while not done():
            if time.monotonic() > deadline:
                raise AssertionError(f"no {what} within {WAIT_S:g} s")
            self.executor.spin_once(timeout_sec=0.01)

    def outputs(self) -> list[tuple[float, np.ndarray, dict[str, str]]]:
        """``(stamp, f_ext, diagnostics)`` of every output both halves of which arrived."""
        return [(s, self.vectors[s], self.diagnostics[s]) for s in self.order
                if s in self.vectors]

    def send(self, role: str, state: VehicleState, quat_wxyz=None) -> None:
        """Send ``state`` as ENU Odometry (``quat_wxyz``: this attitude instead, as is)."""
        msg = odometry_message(self.odometry, state, state.stamp_s, "enu", "body")
        if quat_wxyz is not None:
            o = msg.pose.pose.orientation
            o.w, o.x, o.y, o.z = (float(v) for v in quat_wxyz)
        self.pubs[role].publish(msg)

    def close(self) -> None:
        self.executor.shutdown()
        self.node.destroy_node()
        self.client.destroy_node()


def _stamp(msg) -> float:
    return msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9


def _stamp_value(text: str) -> float | None:
    """A diagnostics stamp (``repr`` of a float, ``"None"`` before any state) as a number."""
    return None if text == "None" else float(text)


def _states(n: int, t0_s: float = 1000.0) -> list[dict[str, VehicleState]]:
    """``n`` samples of a flight as NED states stamped ``t0_s + 0.01 i`` (as sent)."""
    log = orbit_log(0.01 * n)
    rot_l, rot_f = quat_to_rotmat(log.leader_quat), quat_to_rotmat(log.follower_quat)
    return [{"leader": VehicleState(log.leader_pos_m[i], log.leader_vel_mps[i], rot_l[i], 0.0,
                                    stamp_of(t0_s + 0.01 * i)),
             "follower": VehicleState(log.follower_pos_m[i], log.follower_vel_mps[i], rot_f[i],
                                      0.0, stamp_of(t0_s + 0.01 * i))}
            for i in range(n)]


@pytest.fixture
def ros(monkeypatch):
    import rclpy

    for key, value in LOCALHOST_ENV.items():
        monkeypatch.setenv(key, value)
    monkeypatch.setenv("ROS_DOMAIN_ID", str(free_domain_id()))
    rclpy.init()
    harnesses: list[Harness] = []
    yield harnesses
    for harness in harnesses:
        harness.close()
    rclpy.shutdown()


def _want(harness: Harness, sample: dict[str, VehicleState]) -> np.ndarray:
    return to_output_frame(harness.predictor.predict_one(*model_inputs(sample["leader"],
                                                                       sample["follower"])), "enu")


def _send_pair(harness: Harness, sample: dict[str, VehicleState]) -> None:
    """The leader's state, taken in by the node, then the follower's."""
    harness.send("leader", sample["leader"])
    harness.spin_until(lambda: (harness.node.states["leader"] is not None and
                                harness.node.states["leader"].stamp_s
                                == sample["leader"].stamp_s), "leader state taken in")
    harness.send("follower", sample["follower"])


def test_each_follower_message_is_answered_with_its_own_prediction(ros, tmp_path):
    # a slow watchdog (5 Hz): the answers cannot be its ticks
    harness = Harness(tmp_path, PublishMode.ON_FOLLOWER, rate_hz=5.0)
    ros.append(harness)
    samples = _states(12)
    for sample in samples:
        stamp = sample["follower"].stamp_s
        _send_pair(harness, sample)
        harness.spin_until(lambda s=stamp: any(
            v["trigger"] == "follower" and _stamp_value(v["follower_stamp"]) == s
            for _, _, v in harness.outputs()), f"answer to the follower message {stamp!r}")
    answers = [(f, v) for _, f, v in harness.outputs() if v["trigger"] == "follower"]
    # exactly one answer per message, in order, each computed from that message (and the
    # leader state sent with it)
    assert [_stamp_value(v["follower_stamp"]) for _, v in answers] == [
        s["follower"].stamp_s for s in samples]
    for (f_ext, values), sample in zip(answers, samples, strict=True):
        assert _stamp_value(values["leader_stamp"]) == sample["leader"].stamp_s
        assert values["stale"] == "false" and values["stale_reason"] == ""
        np.testing.assert_allclose(f_ext, _want(harness, sample), rtol=0, atol=1e-12)
        assert np.isfinite(float(values["queue_ms"]))  # the message's wait is measured
    assert np.median([np.linalg.norm(f) for f, _ in answers]) > 0.1  # not trivially zero
    assert all(v["trigger"] in ("follower", "watchdog") for _, _, v in harness.outputs())


def test_the_watchdog_publishes_when_follower_messages_stop(ros, tmp_path):
    harness = Harness(tmp_path, PublishMode.ON_FOLLOWER, rate_hz=20.0)
    ros.append(harness)
    samples = _states(3)
    for sample in samples:
        _send_pair(harness, sample)
    last = samples[-1]
    harness.spin_until(lambda: any(_stamp_value(v["follower_stamp"]) == last["follower"].stamp_s
                                   and v["trigger"] == "follower"
                                   for _, _, v in harness.outputs()), "answer to the last message")
    seen = set(harness.order)

    def after_last():
        return [(f, v) for s, f, v in harness.outputs() if s not in seen]

    # nothing more is sent: the watchdog keeps publishing, from the newest states
    harness.spin_until(lambda: len(after_last()) >= 3, "3 outputs after the last message")
    for f_ext, values in after_last():
        assert values["trigger"] == "watchdog"
        assert _stamp_value(values["follower_stamp"]) == last["follower"].stamp_s
        assert values["stale"] == "false"  # within MAX_AGE_S: the newest prediction, not zero
        np.testing.assert_allclose(f_ext, _want(harness, last), rtol=0, atol=1e-12)
        assert values["queue_ms"] == "nan"


def test_timer_mode_publishes_on_ticks_only(ros, tmp_path):
    harness = Harness(tmp_path, PublishMode.TIMER, rate_hz=20.0)
    ros.append(harness)
    sample = _states(1)[0]
    _send_pair(harness, sample)
    stamp = sample["follower"].stamp_s
    harness.spin_until(lambda: any(_stamp_value(v["follower_stamp"]) == stamp
                                   for _, _, v in harness.outputs()), "a tick using the state")
    assert {v["trigger"] for _, _, v in harness.outputs()} == {"timer"}
    f_ext, values = next((f, v) for _, f, v in harness.outputs()
                         if _stamp_value(v["follower_stamp"]) == stamp)
    np.testing.assert_allclose(f_ext, _want(harness, sample), rtol=0, atol=1e-12)


def test_odometry_found_on_the_graph_is_published_in_enu(ros, tmp_path):
    # The audit's case: Odometry topics in a mapping that does not say `frame`, their type found
    # on the graph (no --state-type). The frame was decided at start as NED; now it is decided
    # when the follower's type is found: ENU (REP 103), the diagnostics saying so.
    mapping = f'[leader]\nstate = "{LEADER}"\n\n[follower]\nstate = "{FOLLOWER}"\n'
    harness = Harness(tmp_path, PublishMode.ON_FOLLOWER, rate_hz=5.0, state_types={},
                      mapping_text=mapping)
    ros.append(harness)
    sample = _states(1)[0]
    _send_pair(harness, sample)
    stamp = sample["follower"].stamp_s
    harness.spin_until(lambda: any(_stamp_value(v["follower_stamp"]) == stamp
                                   for _, _, v in harness.outputs()), "the answer")
    f_ext, values = next((f, v) for _, f, v in harness.outputs()
                         if _stamp_value(v["follower_stamp"]) == stamp)
    np.testing.assert_allclose(f_ext, _want(harness, sample), rtol=0, atol=1e-12)  # ENU
    assert harness.frame_ids == {"map"}  # every f_ext, from the first one
    assert {v["output_frame"] for _, _, v in harness.outputs()} == {"enu"}
    assert values["output_frame_rule"].startswith("nav_msgs/msg/Odometry input")


def test_no_f_ext_before_the_follower_type_is_known(ros, tmp_path):
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray
    from geometry_msgs.msg import Vector3Stamped
    from rclpy.executors import SingleThreadedExecutor

    mapping, _ = load_mapping(write_mapping(tmp_path / "m.toml", "/nobody/a", "/nobody/b"))
    node = make_node(Predictor.load(random_model(tmp_path / "model")),
                     NodeSettings(mapping=mapping, rate_hz=20.0), node_name="aerodock_undecided")
    client = rclpy.create_node("aerodock_undecided_client")
    seen: dict[str, list] = {"f_ext": [], "diagnostics": []}
    client.create_subscription(Vector3Stamped, "/aerodock/f_ext",
                               lambda m: seen["f_ext"].append(m), 100)
    client.create_subscription(DiagnosticArray, "/aerodock/diagnostics",
                               lambda m: seen["diagnostics"].append(m.status[0]), 100)
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    executor.add_node(client)
    try:
        deadline = time.monotonic() + WAIT_S
        while len(seen["diagnostics"]) < 3:
            assert time.monotonic() < deadline, "no diagnostics"
            executor.spin_once(timeout_sec=0.01)
    finally:
        executor.shutdown()
        node.destroy_node()
        client.destroy_node()
    assert seen["f_ext"] == [] and node.tick == 0
    for status in seen["diagnostics"]:
        values = {kv.key: kv.value for kv in status.values}
        assert values["output_frame"] == "undecided" and values["stale"] == "true"
        assert status.message.startswith("publishing no f_ext: the follower's state type")


def test_garbage_is_refused_with_its_reason_and_counted_within_bounds(ros, tmp_path):
    from aerodock.node.refusals import MAX_REFUSAL_KINDS, RECENT_REFUSALS

    harness = Harness(tmp_path, PublishMode.ON_FOLLOWER, rate_hz=5.0)
    ros.append(harness)
    samples = _states(31)
    _send_pair(harness, samples[0])
    garbage = [((1e200, 1e200, 0.0, 0.0), "attitude quaternion norm 1.41e+200"),
               ((0.0, 0.0, 0.0, 0.0), "attitude quaternion is zero"),
               ((1.5e308, 1.5e308, 0.0, 0.0), "attitude quaternion norm inf"),
               ((0.0, 3.0, 0.0, 0.0), "attitude quaternion norm 3")]
    for k, sample in enumerate(samples[1:]):
        quat, why = garbage[k % len(garbage)]
        stamp = sample["follower"].stamp_s
        harness.send("follower", sample["follower"], quat_wxyz=quat)
        harness.spin_until(lambda s=stamp: any(_stamp_value(v["follower_stamp"]) == s
                                               for _, _, v in harness.outputs()),
                           f"the answer to garbage {k}")
        f_ext, values = next((f, v) for _, f, v in harness.outputs()
                             if _stamp_value(v["follower_stamp"]) == stamp)
        assert values["stale"] == "true" and not f_ext.any()  # zero, never read as level
        assert values["stale_reason"].startswith(f"follower: {why}"), values["stale_reason"]
        assert values["refused_total"] == str(k + 1)
    refused = {key: int(v) for key, v in values.items() if key.startswith("refused ")}
    # counted by kind, the numbers left out: 30 messages, two kinds
    assert refused == {"refused follower: attitude quaternion is zero": 8,
                       "refused follower: attitude quaternion norm #, not # (tolerance #)": 22}
    assert len(refused) <= MAX_REFUSAL_KINDS + 1
    recent = values["refused_recent"].split(" | ")
    assert len(recent) == RECENT_REFUSALS and recent[-1].startswith("follower: attitude")
    assert harness.node.refusals.total == 30 and len(harness.node.refusals.recent) == 5
