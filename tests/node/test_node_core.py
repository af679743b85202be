"""The ROS-free core of ``aerodock node``: message frames, staleness, one prediction step."""

from __future__ import annotations

import numpy as np
import pytest
from node_helpers import random_model

from aerodock.geometry import euler_to_rotmat, rotmat_to_quat
from aerodock.learning.runtime import Predictor
from aerodock.node.core import (
    VehicleState,
    current_state,
    is_stale,
    model_inputs,
    odometry_fields,
    odometry_state,
    prediction_step,
    px4_odometry_state,
    to_output_frame,
)


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
