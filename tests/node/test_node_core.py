"""The ROS-free core of ``aerodock node``: message frames, staleness, one prediction step."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from node_helpers import random_model

from aerodock.geometry import euler_to_rotmat, rotmat_to_quat
from aerodock.learning.runtime import Predictor
from aerodock.node.core import (
    CURRENT_STATE,
    DEFAULT_PUBLISH_MODE,
    FOLLOWER_EVENT,
    MAX_ANGLE_RAD,
    MAX_POSITION_M,
    MAX_SPEED_MPS,
    ODOMETRY,
    PX4_ODOMETRY,
    QUAT_NORM_TOLERANCE,
    TICK_EVENT,
    InputMonitor,
    PublishMode,
    VehicleState,
    current_state,
    euler_attitude,
    implausible,
    is_stale,
    model_inputs,
    odometry_fields,
    odometry_state,
    output_frame_choice,
    output_trigger,
    prediction_step,
    px4_odometry_state,
    quaternion_attitude,
    stale_reasons,
    to_output_frame,
)
from aerodock.node.refusals import MAX_REFUSAL_KINDS, RECENT_REFUSALS, RefusalLog, refusal_kind


def _state(t: float = 0.0, p=(0.0, 0.0, -2.0), v=(0.1, 0.0, 0.0), rot=None) -> VehicleState:
    return VehicleState(np.array(p, float), np.array(v, float),
                        np.eye(3) if rot is None else rot, received_s=t, stamp_s=t)


def test_enu_odometry_becomes_ned():
    # ENU (REP-103): a vehicle 3 m up, 1 m east and 2 m north, its FLU body facing north
    # (yaw +90 deg about z-up), flying north at 1 m/s, which its body sees as +x.
    quat_facing_north = (np.cos(np.pi / 4), 0.0, 0.0, np.sin(np.pi / 4))
    s = odometry_state((1.0, 2.0, 3.0), quat_facing_north, (1.0, 0.0, 0.0), frame="enu",
                       twist="body", received_s=5.0, stamp_s=4.9)
    np.testing.assert_allclose(s.p_m, [2.0, 1.0, -3.0])  # north, east, down
    np.testing.assert_allclose(s.v_mps, [1.0, 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(s.R, np.eye(3), atol=1e-15)  # FRD facing north = NED
    assert (s.received_s, s.stamp_s) == (5.0, 4.9)
    world_twist = odometry_state((0, 0, 0), quat_facing_north, (0.0, 1.0, 0.0), frame="enu",
                                 twist="world", received_s=0.0)
    np.testing.assert_allclose(world_twist.v_mps, [1.0, 0.0, 0.0], atol=1e-15)


@pytest.mark.parametrize(("frame", "twist"), [("enu", "body"), ("enu", "world"), ("ned", "body")])
def test_odometry_round_trip(frame, twist):
    rot = euler_to_rotmat(0.2, -0.1, 2.5)
    s = _state(p=(0.3, -0.4, -1.2), v=(0.5, 0.2, -0.1), rot=rot)
    pos, quat, lin = odometry_fields(s, frame=frame, twist=twist)
    back = odometry_state(pos, quat, lin, frame=frame, twist=twist, received_s=0.0)
    np.testing.assert_allclose(back.p_m, s.p_m, atol=1e-14)
    np.testing.assert_allclose(back.v_mps, s.v_mps, atol=1e-14)
    np.testing.assert_allclose(back.R, rot, atol=1e-14)


def test_freyja_and_px4_states():
    s = current_state([1, 2, -3, 0.1, 0.2, 0.3, 0.0, 0.0, np.pi / 2, 0, 0, 0, 0], received_s=1.0)
    np.testing.assert_allclose(s.p_m, [1, 2, -3])
    np.testing.assert_allclose(s.R @ [1, 0, 0], [0, 1, 0], atol=1e-15)  # yaw 90: nose east
    with pytest.raises(ValueError, match="state_vector"):
        current_state([1, 2, 3], received_s=0.0)
    rot = euler_to_rotmat(0.0, 0.0, np.pi / 2)
    q = rotmat_to_quat(rot)
    body = px4_odometry_state([1, 2, -3], q, [1.0, 0.0, 0.0], 3, received_s=0.0,
                              timestamp_us=2_000_000)
    np.testing.assert_allclose(body.v_mps, [0.0, 1.0, 0.0], atol=1e-15)  # body x = east
    assert body.stamp_s == 2.0
    ned = px4_odometry_state([1, 2, -3], q, [1.0, 0.0, 0.0], 1, received_s=0.0)
    np.testing.assert_allclose(ned.v_mps, [1.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="velocity_frame"):
        px4_odometry_state([0, 0, 0], q, [0, 0, 0], 0, received_s=0.0)


def test_staleness_rule():
    lead, fol = _state(1.00), _state(1.02, p=(0, 0, -1.4))
    assert not is_stale(lead, fol, 1.04, 0.05)
    assert is_stale(lead, fol, 1.06, 0.05)  # the leader is 60 ms old
    assert is_stale(None, fol, 1.02, 0.05)
    assert is_stale(lead, None, 1.02, 0.05)
    nan = _state(1.02, p=(np.nan, 0, 0))
    assert is_stale(lead, nan, 1.03, 0.05)


class _Counting:
    def __init__(self, inner):
        self.inner, self.calls = inner, 0

    def predict_one(self, x, rot):
        self.calls += 1
        return self.inner.predict_one(x, rot)


def test_prediction_step_is_the_predictor_or_zero(tmp_path):
    pred = Predictor.load(random_model(tmp_path / "m"))
    lead = _state(1.0, rot=euler_to_rotmat(0.05, -0.03, 0.7))
    fol = _state(1.0, p=(0.2, -0.1, -1.4), v=(0.0, 0.3, 0.1))
    x, rot = model_inputs(lead, fol)
    want = pred.predict_one(x, rot)
    assert np.linalg.norm(want) > 0.1
    fresh = prediction_step(pred, lead, fol, 1.01, max_age_s=0.05)
    np.testing.assert_array_equal(fresh.f_ext_mps2, want)
    assert not fresh.stale and fresh.compute_s > 0
    assert fresh.leader_age_s == pytest.approx(0.01)
    enu = prediction_step(pred, lead, fol, 1.01, max_age_s=0.05, output_frame="enu")
    np.testing.assert_allclose(enu.f_ext_mps2, [want[1], want[0], -want[2]])
    np.testing.assert_allclose(to_output_frame(want, "ned"), want)
    # stale: zero, flagged, and the predictor is not even asked (no old value can leak out)
    counting = _Counting(pred)
    old = prediction_step(counting, lead, fol, 1.2, max_age_s=0.05)
    assert old.stale and counting.calls == 0
    np.testing.assert_array_equal(old.f_ext_mps2, np.zeros(3))
    missing = prediction_step(counting, None, fol, 1.0, max_age_s=0.05)
    assert missing.stale and np.isinf(missing.leader_age_s) and missing.leader_stamp_s is None


def test_non_finite_prediction_is_replaced_by_zero():
    class Broken:
        def predict_one(self, x, rot):
            return np.array([np.nan, 0.0, 1.0])

    out = prediction_step(Broken(), _state(1.0), _state(1.0, p=(0, 0, -1.4)), 1.0,
                          max_age_s=0.05)
    assert out.stale
    np.testing.assert_array_equal(out.f_ext_mps2, np.zeros(3))


def test_node_core_imports_without_ros():
    import subprocess
    import sys

    code = ("import sys\nimport aerodock.node.core, aerodock.cli.node\n"
            "assert 'rclpy' not in sys.modules\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == 0, proc.stderr


# --- freshness judged by the data ------------------------------------------------------------


def _fresh_pair(t: float = 1.0) -> tuple[VehicleState, VehicleState]:
    return _state(t, rot=euler_to_rotmat(0.05, -0.03, 0.7)), _state(t, p=(0.2, -0.1, -1.4),
                                                                      v=(0.0, 0.3, 0.1))


def _step(pred, lead, fol, faults=None, now=1.01):
    return prediction_step(pred, lead, fol, now, max_age_s=0.05, faults=faults)


def _with(state: VehicleState, **changes) -> VehicleState:
    from dataclasses import replace

    return replace(state, **changes)


def test_monitor_accepts_a_normal_stream():
    mon = InputMonitor()
    for i in range(5):
        assert mon.receive(_state(1.0 + 0.01 * i, p=(0.001 * i, 0.0, -2.0))) is None
    assert mon.verdict is None


@pytest.mark.parametrize(("stamps", "values_change", "want"), [
    ((2.0, 1.99), True, "stamp went backwards (2.0 -> 1.99)"),
    ((2.0, 2.0), True, "stamp frozen at 2.0"),
    ((2.0, 2.0), False, "repeated message (stamp 2.0 and values unchanged)"),
    ((2.0, 0.0), True, "stamp is zero"),
    ((None, None), False, "repeated message (same values)"),
])
def test_monitor_flags_bad_sequences(stamps, values_change, want):
    mon = InputMonitor()
    first = VehicleState(np.array([0.0, 0.0, -2.0]), np.array([0.1, 0.0, 0.0]), np.eye(3),
                         received_s=1.0, stamp_s=stamps[0])
    assert mon.receive(first) is None
    second = _with(first, received_s=1.01, stamp_s=stamps[1])
    if values_change:
        second = _with(second, p_m=first.p_m + 0.001)
    assert mon.receive(second) == want
    assert mon.verdict == want
    # the verdict holds until a good message arrives, then clears
    good = _with(first, received_s=1.02, stamp_s=None if stamps[0] is None else 2.01,
                 p_m=first.p_m + 0.002)
    assert mon.receive(good) is None and mon.verdict is None


def test_a_zero_stamp_is_refused_even_first():
    assert InputMonitor().receive(_state(0.0)) == "stamp is zero"  # _state stamps t: here 0


def test_monitor_verdict_makes_the_output_zero_with_the_reason(tmp_path):
    pred = _Counting(Predictor.load(random_model(tmp_path / "m")))
    lead, fol = _fresh_pair()
    assert not _step(pred, lead, fol).stale and pred.calls == 1
    # a relay repeats the follower's message: received 5 ms ago (fresh by receive time)
    mon = InputMonitor()
    mon.receive(_with(fol, received_s=0.99))
    verdict = mon.receive(_with(fol, received_s=1.005))
    out = _step(pred, lead, fol, faults={"leader": None, "follower": verdict})
    assert out.stale and pred.calls == 1
    np.testing.assert_array_equal(out.f_ext_mps2, np.zeros(3))
    assert out.reason == f"follower: {verdict}" and "repeated message" in out.reason


@pytest.mark.parametrize(("p", "v", "want"), [
    ((1e300, 0.0, 0.0), (0.1, 0.0, 0.0), "follower: position 1e+300 m beyond 10000 m"),
    ((0.0, 2e4, -2.0), (0.1, 0.0, 0.0), "follower: position 2e+04 m beyond 10000 m"),
    ((0.0, 0.0, -2.0), (0.0, -150.0, 0.0), "follower: velocity 150 m/s beyond 100 m/s"),
    ((0.0, np.nan, -2.0), (0.1, 0.0, 0.0), "follower: not finite"),
    ((0.0, 0.0, -2.0), (np.inf, 0.0, 0.0), "follower: not finite"),
])
def test_implausible_states_are_stale_with_a_reason(p, v, want, tmp_path, recwarn):
    pred = _Counting(Predictor.load(random_model(tmp_path / "m")))
    lead, _ = _fresh_pair()
    out = _step(pred, lead, _state(1.0, p=p, v=v))
    assert out.stale and out.reason == want and pred.calls == 0
    np.testing.assert_array_equal(out.f_ext_mps2, np.zeros(3))
    assert not recwarn.list  # no overflow or invalid-value warnings


def test_plausible_limits_are_accepted(tmp_path):
    assert MAX_POSITION_M == 1e4 and MAX_SPEED_MPS == 100.0
    edge = _state(1.0, p=(MAX_POSITION_M, -MAX_POSITION_M, -2.0), v=(MAX_SPEED_MPS, 0, 0))
    assert implausible(edge) is None
    assert implausible(_with(edge, v_mps=np.array([0.0, 0.0, -100.001]))) is not None


def test_every_reason_is_listed():
    lead, fol = _fresh_pair()
    reasons = stale_reasons(None, _with(fol, received_s=0.9), 1.0, 0.05,
                            faults={"follower": "stamp frozen at 1.0"})
    assert reasons == ["leader: missing", "follower: 100 ms old (max 50 ms)",
                       "follower: stamp frozen at 1.0"]
    assert stale_reasons(lead, fol, 1.01, 0.05, faults={"leader": None}) == []
    assert not is_stale(lead, fol, 1.01, 0.05)


@pytest.mark.parametrize(("quat", "why"), [
    ((np.nan, 0.0, 0.0, 0.0), "attitude quaternion not finite"),
    ((0.0, 0.0, 0.0, 0.0), "attitude quaternion is zero"),
    ((1e200, 1e200, 0.0, 0.0), "attitude quaternion norm 1.41e+200, not 1 (tolerance 0.01)"),
    ((1.5e308, -1.5e308, 0.0, 0.0), "attitude quaternion norm inf, not 1 (tolerance 0.01)"),
    ((1e-200, 0.0, 0.0, 0.0), "attitude quaternion norm 1e-200, not 1 (tolerance 0.01)"),
    ((0.0, 0.0, 2.0, 0.0), "attitude quaternion norm 2, not 1 (tolerance 0.01)"),
])
def test_quaternions_that_are_no_rotation_are_refused_without_numpy_warnings(quat, why):
    # (1e200, 1e200, 0, 0) overflowed the norm and was read as level; now every converter
    # that takes a quaternion refuses it with the reason, and the step publishes zero
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # any NumPy RuntimeWarning fails the test
        with np.errstate(all="warn"):  # even when the caller's NumPy would warn
            s = odometry_state((0, 0, 2), quat, (0.1, 0, 0), frame="enu", twist="body",
                               received_s=1.0, stamp_s=1.0)
            px4 = px4_odometry_state((0, 0, 0), quat, (1, 0, 0), 3, received_s=1.0,
                                     timestamp_us=1)
            reasons = [implausible(x) for x in (s, px4)]
            lead, _ = _fresh_pair()
            out = prediction_step(_Counting(None), lead, _with(s, received_s=1.0), 1.0,
                                  max_age_s=0.05)
    assert reasons == [why, why]
    assert out.stale and out.reason == f"follower: {why}" and not out.f_ext_mps2.any()
    assert not np.isfinite(s.R).any()  # no rotation kept that anything could use


def test_a_unit_quaternion_within_the_tolerance_is_a_rotation():
    rot = euler_to_rotmat(0.3, -0.2, 1.1)
    q = rotmat_to_quat(rot)
    for scale in (1.0 - QUAT_NORM_TOLERANCE, 1.0 + 0.99 * QUAT_NORM_TOLERANCE):
        got, why = quaternion_attitude(q * scale)
        assert why is None
        np.testing.assert_allclose(got, rot, atol=1e-14)  # normalised, not scaled
    assert quaternion_attitude(q * (1.0 + 1.01 * QUAT_NORM_TOLERANCE))[1] is not None


@pytest.mark.parametrize(("angles", "why"), [
    ((1e300, 0.0, 0.0), "roll 1e+300 rad beyond 6.28 rad (one turn)"),
    ((0.0, -7.0, 0.0), "pitch -7 rad beyond 6.28 rad (one turn)"),
    ((0.0, 0.0, 90.0), "yaw 90 rad beyond 6.28 rad (one turn)"),  # degrees sent as radians
    ((np.nan, 0.0, 0.0), "roll not finite"),
    ((0.0, 0.0, -np.inf), "yaw not finite"),
])
def test_implausible_euler_angles_are_refused(angles, why, recwarn):
    # a roll of 1e300 rad was accepted (its sine is finite, and meaningless)
    s = current_state([0, 0, -2, 0, 0, 0, *angles], received_s=1.0, stamp_s=1.0)
    assert implausible(s) == why and s.fault == why
    assert MAX_ANGLE_RAD == pytest.approx(2 * np.pi)
    edge = current_state([0, 0, -2, 0, 0, 0, MAX_ANGLE_RAD, -MAX_ANGLE_RAD, np.pi],
                         received_s=1.0)
    assert implausible(edge) is None
    np.testing.assert_allclose(edge.R, euler_attitude(0.0, 0.0, np.pi)[0], atol=1e-12)
    assert not recwarn.list


def test_nan_poses_in_the_cli_process_print_nothing(tmp_path):
    # A fresh interpreter with NumPy's default error state (warn): the converters and the step
    # for NaN, zero-quaternion and 1e300 inputs write nothing to stdout or stderr.
    import subprocess
    import sys

    code = (
        "import numpy as np\n"
        "from aerodock.node.core import odometry_state, prediction_step, px4_odometry_state\n"
        "class P:\n"
        "    def predict_one(self, x, r):\n"
        "        return np.tanh(x[:3] @ r * 1e300)\n"
        "lead = odometry_state((0, 0, 2), (1, 0, 0, 0), (0, 0, 0), frame='enu', twist='body',\n"
        "                      received_s=1.0, stamp_s=1.0)\n"
        "for q, p in (((0, 0, 0, 0), (0, 0, 1)), ((np.nan,) * 4, (0, 0, 1)),\n"
        "             ((1, 0, 0, 0), (np.nan, 0, 1)), ((1, 0, 0, 0), (1e300, 1e300, 1))):\n"
        "    fol = odometry_state(p, q, (1, 0, 0), frame='enu', twist='body', received_s=1.0,\n"
        "                         stamp_s=1.0)\n"
        "    fol2 = px4_odometry_state(p, q, (1, 0, 0), 3, received_s=1.0, timestamp_us=5)\n"
        "    for f in (fol, fol2):\n"
        "        out = prediction_step(P(), lead, f, 1.0, max_age_s=0.05)\n"
        "        assert out.stale and not out.f_ext_mps2.any(), out\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert (proc.stdout, proc.stderr) == ("", "")


@pytest.mark.parametrize(("requested", "frame", "follower_type", "want", "rule"), [
    ("enu", "ned", CURRENT_STATE, "enu", "--output-frame enu"),  # --output-frame wins
    ("ned", "enu", None, "ned", "--output-frame ned"),
    # Odometry: ENU by default (REP 103; the mapping's default frame), a NED mapping's NED
    (None, "enu", ODOMETRY, "enu", "nav_msgs/msg/Odometry input: the mapping's frame (enu;"),
    (None, "ned", ODOMETRY, "ned", "nav_msgs/msg/Odometry input: the mapping's frame (ned;"),
    (None, "enu", CURRENT_STATE, "ned", "freyja_msgs/msg/CurrentState input: NED"),
    (None, "enu", PX4_ODOMETRY, "ned", "px4_msgs/msg/VehicleOdometry input: NED"),
    # the type not known yet (to be found on the graph): undecided, whatever the mapping says
    (None, "enu", None, None, "the follower's state type is not known yet"),
    (None, "ned", None, None, "the follower's state type is not known yet"),
])
def test_output_frame_follows_the_follower_type(requested, frame, follower_type, want, rule):
    got, why = output_frame_choice(requested, frame, follower_type)
    assert got == want and why.startswith(rule)


def test_refusal_log_counts_by_kind_and_keeps_the_last_few():
    log = RefusalLog()
    assert log.values() == {"refused_total": "0", "refused_recent": ""}
    for k in range(40):
        log.record("follower", f"stamp frozen at {1.0 + k * 0.01!r}")
    log.record("leader", "attitude quaternion norm 1.41e+200, not 1 (tolerance 0.01)")
    values = log.values()
    assert values["refused_total"] == "41"
    assert values["refused follower: stamp frozen at #"] == "40"
    assert values["refused leader: attitude quaternion norm #, not # (tolerance #)"] == "1"
    recent = values["refused_recent"].split(" | ")
    assert len(recent) == RECENT_REFUSALS and recent[-1].startswith("leader: attitude")
    assert recent[0] == f"follower: stamp frozen at {1.0 + 36 * 0.01!r}"
    assert refusal_kind("stamp went backwards (12.31 -> -1e-05)") == "stamp went backwards (# -> #)"


def test_refusal_log_stays_bounded_whatever_the_reasons():
    log = RefusalLog()
    for k in range(3 * MAX_REFUSAL_KINDS):
        log.record("leader", f"unusable message (reason number {chr(65 + k % 26) * (k + 1)})")
    log.record("follower", "x" * 10_000)
    assert len(log.counts) == MAX_REFUSAL_KINDS + 1  # the kinds, and "other"
    assert log.counts["other"] == 2 * MAX_REFUSAL_KINDS + 1
    assert sum(log.counts.values()) == log.total == 3 * MAX_REFUSAL_KINDS + 1
    assert all(len(text) <= 200 for text in log.recent)
    assert all(len(key) <= 220 for key in log.values())


def test_mapping_reports_an_explicit_frame(tmp_path):
    from aerodock.ingest.rosbag import load_mapping

    path = tmp_path / "m.toml"
    path.write_text('frame = "enu"\n[leader]\nstate = "/a"\n')
    merged, explicit = load_mapping(path)
    assert "frame" in explicit and "leader.state" in explicit
    assert "frame" not in load_mapping(None)[1]


@pytest.mark.parametrize(("mode", "event", "now", "last", "want"), [
    # on-follower: every follower message publishes, whatever the timer did
    ("on-follower", FOLLOWER_EVENT, 1.0, None, "follower"),
    ("on-follower", FOLLOWER_EVENT, 1.0, 0.999, "follower"),
    # the watchdog: a tick publishes only when no follower-triggered output went out within
    # the last 1.5 periods (the period: 0.01 s here)
    ("on-follower", TICK_EVENT, 1.0, None, "watchdog"),
    ("on-follower", TICK_EVENT, 1.0, 0.995, None),
    ("on-follower", TICK_EVENT, 1.0, 0.99, None),  # one period: a message a little late
    ("on-follower", TICK_EVENT, 1.0, 0.985, "watchdog"),
    ("on-follower", TICK_EVENT, 1.0, 0.5, "watchdog"),
    # timer: ticks only, follower messages never publish
    ("timer", TICK_EVENT, 1.0, None, "timer"),
    ("timer", TICK_EVENT, 1.0, 0.999, "timer"),
    ("timer", FOLLOWER_EVENT, 1.0, None, None),
])
def test_output_trigger(mode, event, now, last, want):
    assert output_trigger(mode, event, now, last, 0.01) == want


def test_output_trigger_refuses_unknown_modes_and_events():
    with pytest.raises(ValueError):
        output_trigger("sometimes", TICK_EVENT, 1.0, None, 0.01)
    with pytest.raises(ValueError, match="event"):
        output_trigger(PublishMode.TIMER, "leader message", 1.0, None, 0.01)
    assert DEFAULT_PUBLISH_MODE is PublishMode.ON_FOLLOWER


# --- a leader-aware model's wake scales from the flown vehicles -------------------------------


def test_configured_wake_scales_are_the_vehicles_hovering(tmp_path):
    """``node --config``: a so2-leader model gets the configured leader's (hovering) and
    follower's scales, as a simulated mission builds them; other kinds get None."""
    from aerodock.config import load_config
    from aerodock.downwash import BodyState
    from aerodock.learning.features import GRAVITY_MPS2, wake_scales
    from aerodock.node.core import configured_wake_scales

    plain = Predictor.load(random_model(tmp_path / "so2"))
    aware = Predictor.load(random_model(tmp_path / "leader", kind="so2-leader"))
    default = load_config()
    large = load_config(Path(__file__).parents[2] / "examples" / "large_leader.toml")
    assert configured_wake_scales(plain, default.leader, default.vehicle) is None
    got = configured_wake_scales(aware, large.leader, large.vehicle)
    lead, fol = large.leader, large.vehicle
    want = wake_scales(lead.mass_kg * GRAVITY_MPS2, lead.rotor_radius_m, lead.n_rotors,
                       fol.mass_kg, fol.rotor_radius_m, fol.n_rotors)[0, :3]
    np.testing.assert_array_equal(got, want)  # the three a so2-leader model reads
    # the mission's own scales for a leader at hover thrust, the same rotors
    aware.set_rotor_geometry(lead.rotor_radius_m, lead.n_rotors, fol.rotor_radius_m,
                             fol.n_rotors)
    z = np.zeros((1, 3))
    bodies = (BodyState(z, z, np.eye(3)[None], np.array([lead.mass_kg * GRAVITY_MPS2]),
                        np.array([lead.mass_kg])),
              BodyState(z, z, np.eye(3)[None], np.array([fol.mass_kg * GRAVITY_MPS2]),
                        np.array([fol.mass_kg])))
    np.testing.assert_allclose(aware.wake_scales_for_bodies(*bodies)[0, :3], got, rtol=1e-12)
    # a leader of twice the mass on larger rotors: other scales than the default pair's
    small = configured_wake_scales(aware, default.leader, default.vehicle)
    assert got[1] > small[1] and not np.allclose(got, small)
    # and the step flies them
    lead_s = _state(1.0, rot=euler_to_rotmat(0.05, -0.03, 0.7))
    fol_s = _state(1.0, p=(0.2, -0.1, -1.4), v=(0.0, 0.3, 0.1))
    x, rot = model_inputs(lead_s, fol_s)
    for scales in (got, small):
        out = prediction_step(aware, lead_s, fol_s, 1.01, max_age_s=0.05, wake_scales=scales)
        np.testing.assert_array_equal(out.f_ext_mps2, aware.predict_one(x, rot, scales))
    assert not np.allclose(
        prediction_step(aware, lead_s, fol_s, 1.01, max_age_s=0.05, wake_scales=got).f_ext_mps2,
        prediction_step(aware, lead_s, fol_s, 1.01, max_age_s=0.05, wake_scales=small).f_ext_mps2)


def test_node_refuses_a_leader_aware_model_without_scales(tmp_path):
    """No recorded training scales and no --config: one line, exit 2, before ROS starts."""
    from cli_process import aerodock

    model = random_model(tmp_path / "leader", kind="so2-leader")
    res = aerodock("node", "--model", model, "--duration", "0.1", timeout_s=120)
    assert res.returncode == 2
    assert "needs the vehicles' wake scales" in res.stderr and "--config" in res.stderr
    assert "Traceback" not in res.stderr


def test_help_says_where_ros_arguments_go_and_the_frame_rule(capsys, tmp_path):
    from aerodock.cli.app import run

    assert run(["node", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "Usage: aerodock node [OPTIONS] [--ros-args ...]" in text
    assert "ROS's own arguments go last, after --ros-args" in text
    assert "nav_msgs/Odometry: the mapping's frame, ENU by default (REP 103)" in " ".join(
        text.replace("│", " ").split())
    # words before --ros-args that the command does not know are refused, before any ROS
    model = random_model(tmp_path / "m")
    assert run(["node", "--model", str(model), "--rat", "5", "--ros-args", "-r", "a:=b"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: no such option: '--rat'") and err.count("\n") == 1
