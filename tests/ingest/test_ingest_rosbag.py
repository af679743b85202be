"""ROS 2 bag reader: bags written with rosbags' Writer (db3 and mcap), mappings, bad input."""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from ingest_helpers import (
    BAG_T0_NS,
    DISTURBANCE,
    MASS_KG,
    BagTopics,
    RosMessages,
    freyja_topics,
    synthetic_flight,
    write_bag,
)

from aerodock.geometry import quat_to_rotmat, rotmat_to_quat
from aerodock.ingest import read_logs
from aerodock.ingest.common import ENU_TO_NED, FLIP_YZ
from aerodock.ingest.errors import IngestError, IngestWarning
from aerodock.ingest.rosbag import load_mapping, read_rosbag

pytest.importorskip("rosbags")

N = 400


@pytest.fixture(scope="module")
def ros() -> RosMessages:
    return RosMessages()


def _truth(n: int = N) -> dict[str, np.ndarray]:
    return synthetic_flight(np.arange(n) * 0.01)


def _read(path: Path, **kwargs: Any) -> Any:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IngestWarning)
        return read_rosbag(path, **kwargs)


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_default_mapping_freyja_bag(tmp_path: Path, ros: RosMessages, storage: str) -> None:
    bag = write_bag(tmp_path / "flight", freyja_topics(ros), storage, ros)
    with pytest.warns(IngestWarning, match="no follower mass"):
        log = read_rosbag(bag)
    fl = _truth()
    assert log.name == "flight"
    assert log.meta["source"] == "rosbag"
    assert log.meta["label_basis"] == "command"
    assert log.meta["command_topic"] == "/bravo/controller_debug"
    assert log.meta["obs_accel_source"] == "differentiated follower velocity"
    assert log.n_samples == N
    np.testing.assert_allclose(log.t_s, np.arange(N) * 0.01, atol=1e-9)
    np.testing.assert_allclose(log.follower_pos_m, fl["p"], atol=1e-12)
    np.testing.assert_allclose(log.leader_pos_m, fl["leader_p"], atol=1e-12)
    np.testing.assert_allclose(log.follower_quat, fl["quat"], atol=1e-9)
    np.testing.assert_allclose(log.follower_cmd_accel_mps2, fl["u"], atol=1e-5)  # float32
    label = log.follower_obs_accel_mps2 - log.follower_cmd_accel_mps2
    np.testing.assert_allclose(label[1:-1], np.tile(DISTURBANCE, (N - 2, 1)), atol=2e-3)
    np.testing.assert_allclose(log.extra["follower_ref_pos_m"], fl["p"], atol=1e-12)
    # The raw storage file inside the bag folder reads the same.
    raw = next(p for p in bag.iterdir() if p.suffix in (".db3", ".mcap"))
    np.testing.assert_array_equal(_read(raw).follower_pos_m, log.follower_pos_m)


def test_attitude_thrust_command(tmp_path: Path, ros: RosMessages) -> None:
    bag = write_bag(tmp_path / "rpyt", freyja_topics(ros, with_rpyt=True), "mcap", ros)
    mapping = {"follower": {"command": "/bravo/rpyt_command", "mass_kg": MASS_KG}}
    log = read_rosbag(bag, mapping=mapping)
    fl = _truth()
    assert log.meta["command_kind"] == "attitude-thrust"
    np.testing.assert_allclose(log.follower_cmd_accel_mps2, fl["u"], atol=1e-9)
    np.testing.assert_allclose(log.follower_thrust_n, fl["thrust_n"], atol=1e-9)
    with pytest.raises(IngestError, match="attitude-thrust command needs its mass"):
        read_rosbag(bag, mapping={"follower": {"command": "/bravo/rpyt_command"}})


def _enu_topics(ros: RosMessages, n: int = N) -> BagTopics:
    """Standard messages in REP-103 ENU / FLU: Odometry (body twist), Vector3Stamped, Imu."""
    fl = _truth(n)
    ns = [BAG_T0_NS + i * 10_000_000 for i in range(n)]
    m, c = ENU_TO_NED, FLIP_YZ  # both are their own inverse
    rot_enu = m @ fl["R"] @ c
    q_enu = rotmat_to_quat(rot_enu)
    v_body = np.einsum("tji,tj->ti", rot_enu, fl["v"] @ m)  # R^T v, FLU body
    force = np.einsum("tji,tj->ti", fl["R"], fl["a"] - [0, 0, 9.81]) @ c  # FLU specific force
    return {
        "/alpha/odom": ("nav_msgs/msg/Odometry", [
            (ns[i], ros.odometry(ns[i], fl["leader_p"][i] @ m, rotmat_to_quat(m @ c),
                                 np.zeros(3))) for i in range(n)]),
        "/bravo/odom": ("nav_msgs/msg/Odometry", [
            (ns[i], ros.odometry(ns[i], fl["p"][i] @ m, q_enu[i], v_body[i]))
            for i in range(n)]),
        "/bravo/accel_cmd": ("geometry_msgs/msg/Vector3Stamped", [
            (ns[i], ros.vector3_stamped(ns[i], fl["u"][i] @ m)) for i in range(n)]),
        "/bravo/imu": ("sensor_msgs/msg/Imu", [
            (ns[i], ros.imu(ns[i], q_enu[i], force[i])) for i in range(n)]),
    }


ENU_MAPPING = {"leader": {"state": "/alpha/odom"},
               "follower": {"state": "/bravo/odom", "command": "/bravo/accel_cmd",
                            "imu": "/bravo/imu", "mass_kg": MASS_KG}}


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_enu_standard_messages_with_imu(tmp_path: Path, ros: RosMessages, storage: str) -> None:
    bag = write_bag(tmp_path / "enu", _enu_topics(ros), storage, ros)
    log = read_rosbag(bag, mapping=ENU_MAPPING)
    fl = _truth()
    np.testing.assert_allclose(log.follower_pos_m, fl["p"], atol=1e-12)
    np.testing.assert_allclose(log.follower_vel_mps, fl["v"], atol=1e-12)
    np.testing.assert_allclose(quat_to_rotmat(log.follower_quat), fl["R"], atol=1e-9)
    np.testing.assert_allclose(quat_to_rotmat(log.leader_quat), fl["leader_R"], atol=1e-9)
    np.testing.assert_allclose(log.follower_cmd_accel_mps2, fl["u"], atol=1e-12)
    np.testing.assert_allclose(log.follower_obs_accel_mps2, fl["a"], atol=1e-9)
    np.testing.assert_allclose(log.follower_thrust_n, fl["thrust_n"], atol=1e-9)
    assert log.meta["obs_accel_source"] == "imu /bravo/imu"


def test_pose_with_twist_in_ned_and_bag_time(tmp_path: Path, ros: RosMessages) -> None:
    fl = _truth()
    ns = [BAG_T0_NS + i * 10_000_000 for i in range(N)]
    topics: BagTopics = {
        "/a/pose": ("geometry_msgs/msg/PoseStamped", [
            (ns[i], ros.pose_stamped(0, fl["leader_p"][i], np.array([1.0, 0, 0, 0])))
            for i in range(N)]),
        "/b/pose": ("geometry_msgs/msg/PoseStamped", [
            (ns[i], ros.pose_stamped(0, fl["p"][i], fl["quat"][i])) for i in range(N)]),
        "/b/vel": ("geometry_msgs/msg/TwistStamped", [
            (ns[i], ros.twist_stamped(0, fl["v"][i])) for i in range(N)]),
        "/b/cmd": ("geometry_msgs/msg/Vector3Stamped", [
            (ns[i], ros.vector3_stamped(0, fl["u"][i])) for i in range(N)]),
    }
    bag = write_bag(tmp_path / "ned", topics, "mcap", ros)
    mapping = {"frame": "ned", "time": "bag", "leader": {"state": "/a/pose"},
               "follower": {"state": "/b/pose", "twist": "/b/vel", "command": "/b/cmd"}}
    log = read_rosbag(bag, mapping=mapping, mass_kg=MASS_KG)
    np.testing.assert_allclose(log.follower_vel_mps, fl["v"], atol=1e-12)
    np.testing.assert_allclose(log.follower_cmd_accel_mps2, fl["u"], atol=1e-12)
    # Header stamps left at zero are an error unless the mapping says to use the bag time.
    with pytest.raises(IngestError, match="zero in every message: set time = \"bag\""):
        _read(bag, mapping={**mapping, "time": "header"})


def test_mapping_from_toml_and_folder_of_bags(tmp_path: Path, ros: RosMessages) -> None:
    bags = tmp_path / "bags"
    bags.mkdir()
    write_bag(bags / "b_second", _enu_topics(ros, 200), "sqlite3", ros)
    write_bag(bags / "a_first", _enu_topics(ros, 150), "mcap", ros)
    toml = tmp_path / "map.toml"
    toml.write_text('[leader]\nstate = "/alpha/odom"\n\n[follower]\nstate = "/bravo/odom"\n'
                    'command = "/bravo/accel_cmd"\nimu = "/bravo/imu"\nmass_kg = 0.7\n')
    done = []
    logs = read_logs("rosbag", [bags], mapping=toml, progress=lambda i, n: done.append((i, n)))
    assert [log.name for log in logs] == ["a_first", "b_second"]
    assert [log.n_samples for log in logs] == [150, 200]
    assert (1, 2) in done and done[-1] == (2, 2)  # per file, with finer steps inside a bag
    assert all(a[0] <= b[0] for a, b in zip(done, done[1:])) and len(done) > 2


def test_default_mapping_documented_values() -> None:
    mapping, explicit = load_mapping(None)
    assert mapping["frame"] == "enu"
    assert mapping["leader"]["state"] == "/alpha/current_state"
    assert mapping["follower"]["command"] == ["/bravo/controller_debug", "/bravo/rpyt_command"]
    assert explicit == set()


# --------------------------------------------------------------------------------------------
# Bad input
# --------------------------------------------------------------------------------------------


def _expect(bag: Path, *phrases: str, **kwargs: Any) -> None:
    with pytest.raises(IngestError) as info:
        _read(bag, **kwargs)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(str(bag)), message
    for phrase in phrases:
        assert phrase in message, message


def _freyja_bag(tmp_path: Path, ros: RosMessages, edit=None, n: int = 150,  # type: ignore[no-untyped-def]
                **kwargs: Any) -> Path:
    topics = freyja_topics(ros, n, **kwargs)
    if edit:
        edit(topics)
    return write_bag(tmp_path / "bad", topics, "mcap", ros)


def test_missing_topic(tmp_path: Path, ros: RosMessages) -> None:
    bag = _freyja_bag(tmp_path, ros, edit=lambda t: t.pop("/bravo/controller_debug"))
    _expect(bag, "missing topic /bravo/controller_debug or /bravo/rpyt_command (follower command)",
            "/alpha/current_state")


def test_missing_explicit_optional_topic(tmp_path: Path, ros: RosMessages) -> None:
    bag = _freyja_bag(tmp_path, ros)
    _expect(bag, "missing topic /bravo/imu (follower imu)",
            mapping={"follower": {"imu": "/bravo/imu"}})


def test_topic_without_messages(tmp_path: Path, ros: RosMessages) -> None:
    bag = _freyja_bag(tmp_path, ros, edit=lambda t: t["/alpha/current_state"][1].clear())
    _expect(bag, "topic /alpha/current_state (leader state) has no messages")


def test_nan(tmp_path: Path, ros: RosMessages) -> None:
    def put_nan(topics: BagTopics) -> None:
        topics["/bravo/current_state"][1][5][1].state_vector[1] = np.nan

    _expect(_freyja_bag(tmp_path, ros, edit=put_nan),
            "/bravo/current_state: NaN in column 'state_vector' at message 5")


def _restamp(topic: str, change) -> Any:  # type: ignore[no-untyped-def]
    def edit(topics: BagTopics) -> None:
        msgs = topics[topic][1]
        stamps = change(np.array([m.header.stamp.sec * 10**9 + m.header.stamp.nanosec
                                  for _, m in msgs], dtype=np.int64))
        for (_, msg), stamp in zip(msgs, stamps, strict=True):
            msg.header.stamp.sec, msg.header.stamp.nanosec = int(stamp // 10**9), int(
                stamp % 10**9)
    return edit


def test_non_monotonic_stamps(tmp_path: Path, ros: RosMessages) -> None:
    def swap(s: np.ndarray) -> np.ndarray:
        s[[20, 21]] = s[[21, 20]]
        return s

    bag = _freyja_bag(tmp_path, ros, edit=_restamp("/bravo/current_state", swap))
    _expect(bag, "'/bravo/current_state header.stamp' is not monotonic", "message 21")


def test_duplicated_stamps(tmp_path: Path, ros: RosMessages) -> None:
    def dup(s: np.ndarray) -> np.ndarray:
        s[30] = s[29]
        return s

    bag = _freyja_bag(tmp_path, ros, edit=_restamp("/alpha/current_state", dup))
    _expect(bag, "duplicated time in column '/alpha/current_state header.stamp' at message 30")


def test_microseconds_in_the_nanosecond_field(tmp_path: Path, ros: RosMessages) -> None:
    bag = _freyja_bag(tmp_path, ros, edit=_restamp("/bravo/current_state", lambda s: s // 1000))
    _expect(bag, "looks like microseconds, expected nanoseconds")


def test_topics_of_different_lengths(tmp_path: Path, ros: RosMessages) -> None:
    bag = _freyja_bag(tmp_path, ros, n=300, leader_n=50)
    _expect(bag, "topics of different lengths")


def test_empty_file(tmp_path: Path) -> None:
    bag = tmp_path / "empty.mcap"
    bag.write_bytes(b"")
    _expect(bag, "empty file")


def test_not_a_bag(tmp_path: Path) -> None:
    bag = tmp_path / "junk.db3"
    bag.write_bytes(b"SQLite format 3\x00" + b"\x00" * 100)
    _expect(bag, "ROS 2 bag")


def test_unsupported_state_type(tmp_path: Path, ros: RosMessages) -> None:
    bag = _freyja_bag(tmp_path, ros)
    _expect(bag, "a state topic must be one of",
            mapping={"leader": {"state": "/bravo/controller_debug"}})


def test_bad_mapping(tmp_path: Path) -> None:
    toml = tmp_path / "map.toml"
    toml.write_text('[follower]\nstaet = "/x"\n')
    with pytest.raises(IngestError, match=r"map.toml: unknown key follower.'staet'"):
        load_mapping(toml)
    toml.write_text('frame = "xyz"\n')
    with pytest.raises(IngestError, match="frame = 'xyz'; use enu or ned"):
        load_mapping(toml)


# -- PX4 (px4_msgs) ------------------------------------------------------------------------

@pytest.mark.parametrize("velocity_frame", [1, 3])
def test_px4_bag_known_trajectory_in_ned(tmp_path: Path, ros: RosMessages,
                                         velocity_frame: int) -> None:
    from ingest_helpers import PX4_MAPPING, px4_topics

    topics = px4_topics(ros, follower_velocity_frame=velocity_frame)
    bag = write_bag(tmp_path / "px4", topics, ros=ros)
    log = read_rosbag(bag, mapping=PX4_MAPPING)
    fl = synthetic_flight(np.arange(N) * 0.01)
    assert log.n_samples == N and log.meta["label_basis"] == "thrust"
    # NED as sent: z negative (1.3-1.5 m above ground), north/east unchanged, attitude FRD->NED
    np.testing.assert_allclose(log.follower_pos_m, fl["p"], atol=1e-6)
    assert np.all(log.follower_pos_m[:, 2] < -1.2)
    np.testing.assert_allclose(log.leader_pos_m, fl["leader_p"], atol=1e-6)
    np.testing.assert_allclose(log.follower_vel_mps, fl["v"], atol=1e-5)
    np.testing.assert_allclose(quat_to_rotmat(log.follower_quat), fl["R"], atol=1e-6)
    np.testing.assert_allclose(log.follower_cmd_accel_mps2, fl["u"], atol=1e-4)
    label = log.follower_obs_accel_mps2 - log.follower_cmd_accel_mps2
    np.testing.assert_allclose(label, np.tile(DISTURBANCE, (N, 1)), atol=1e-4)
    np.testing.assert_allclose(log.follower_thrust_n, fl["thrust_n"], rtol=1e-5)


def test_px4_thrust_setpoint_needs_the_hover_thrust(tmp_path: Path, ros: RosMessages) -> None:
    from ingest_helpers import PX4_MAPPING, px4_topics

    bag = write_bag(tmp_path / "px4", px4_topics(ros, n=100), ros=ros)
    mapping = {**PX4_MAPPING, "follower": {**PX4_MAPPING["follower"], "hover_thrust": None}}
    _expect(bag, "needs its hover thrust", "follower.hover_thrust", mapping=mapping)
    bad = {**PX4_MAPPING, "follower": {**PX4_MAPPING["follower"], "hover_thrust": 1e-30}}
    with pytest.raises(IngestError, match="hover_thrust = 1e-30"):
        read_rosbag(bag, mapping=bad)


def test_only_mapped_topics_are_read_with_progress(tmp_path: Path, ros: RosMessages) -> None:
    """An unmapped topic of a type nobody can decode is never deserialised; progress counts
    the mapped messages."""
    from rosbags.rosbag2 import StoragePlugin, Writer

    topics = freyja_topics(ros, n=150)
    bag = tmp_path / "extra"
    with Writer(bag, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        conns = {t: writer.add_connection(t, mt, typestore=ros.store)
                 for t, (mt, _) in topics.items()}
        junk = writer.add_connection("/camera/raw", "vendor_msgs/msg/Blob", msgdef="uint8 x",
                                     rihs01="RIHS01_" + "0" * 64)
        for topic, (mt, msgs) in topics.items():
            for ns, msg in msgs:
                writer.write(conns[topic], ns, ros.store.serialize_cdr(msg, mt))
        for k in range(500):
            writer.write(junk, BAG_T0_NS + k * 10**6, b"\x00\x01\x00\x00garbage")
    calls: list[tuple[int, int]] = []
    log = read_rosbag(bag, mass_kg=0.7,
                      progress=lambda done, total: calls.append((done, total)))
    assert log.n_samples > 100
    assert calls and calls[-1][0] == calls[-1][1] == 4 * 150
    assert all(a[0] <= b[0] for a, b in zip(calls, calls[1:]))


def test_memory_grows_only_with_the_returned_arrays(tmp_path: Path, ros: RosMessages) -> None:
    """Peak memory per extra sample stays within a small multiple of what the FlightLog holds
    per sample (the intermediate float arrays of the conversion). Keeping the deserialised
    message objects, as this reader once did, costs about 16x."""
    import gc
    import tracemalloc

    def peak_and_size(n: int) -> tuple[int, int]:
        bag = write_bag(tmp_path / f"b{n}", freyja_topics(ros, n=n), ros=ros)
        read_rosbag(bag, mass_kg=0.7)  # warm caches (typestore, imports)
        peaks = []
        # tracemalloc counts every thread's allocations: a thread an earlier test left running
        # in this process only adds, so the least of three reads is the reader's own peak.
        for _ in range(3):
            gc.collect()
            tracemalloc.start()
            log = read_rosbag(bag, mass_kg=0.7)
            peaks.append(tracemalloc.get_traced_memory()[1])
            tracemalloc.stop()
        peak = min(peaks)
        size = sum(np.asarray(getattr(log, f)).nbytes for f in (
            "t_s", "leader_pos_m", "leader_vel_mps", "leader_quat", "follower_pos_m",
            "follower_vel_mps", "follower_quat", "follower_cmd_accel_mps2", "follower_thrust_n",
            "follower_obs_accel_mps2")) + sum(v.nbytes for v in log.extra.values())
        return peak, size

    small, large = peak_and_size(500), peak_and_size(2000)
    ratio = (large[0] - small[0]) / (large[1] - small[1])
    assert ratio < 12.0, f"peak memory grows {ratio:.1f}x as fast as the returned arrays"
