"""Shared reader pieces: time checks, unit detection, frames, resampling, the clock check."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from aerodock.geometry import (
    E3,
    euler_to_rotmat,
    quat_to_rotmat,
    rotmat_to_euler,
    specific_force_to_accel,
    thrust_accel,
)
from aerodock.ingest.common import (
    ENU_TO_NED,
    FLIP_YZ,
    bracket_gap_s,
    check_time,
    check_time_unit,
    convert_rotations,
    detect_time_unit,
    estimate_lag_s,
    resample_quat,
)
from aerodock.ingest.errors import IngestError


@pytest.mark.parametrize("unit, scale", [("s", 1.0), ("ms", 1e3), ("us", 1e6), ("ns", 1e9)])
def test_detect_time_unit(unit: str, scale: float) -> None:
    t = np.arange(100) * 0.0101 * scale
    assert detect_time_unit(t, "f.csv") == unit


def test_check_time_unit_names_the_likely_unit() -> None:
    t_ms = np.arange(100) * 10.0
    with pytest.raises(IngestError, match="looks like milliseconds, expected seconds"):
        check_time_unit(t_ms, "s", "f.csv", column="t_s")
    check_time_unit(t_ms / 1000, "s", "f.csv", column="t_s")


@pytest.mark.parametrize("t, phrase", [
    ([], "empty: no samples"),
    ([0.0], "only 1 samples"),
    ([0.0, np.nan, 2.0], "NaN in column 'time' at sample 1"),
    ([0.0, 1.0, 1.0, 2.0], "duplicated time in column 'time' at sample 2"),
    ([0.0, 2.0, 1.0], "not monotonic: goes back from 2 to 1 at sample 2"),
])
def test_check_time(t: list[float], phrase: str) -> None:
    with pytest.raises(IngestError) as info:
        check_time(np.array(t), "f.csv")
    assert str(info.value).startswith("f.csv: ")
    assert phrase in str(info.value)


def test_enu_flu_to_ned_frd() -> None:
    """A level vehicle facing east in ENU (yaw 0) faces east in NED (yaw +90 deg)."""
    rot = convert_rotations(ENU_TO_NED, np.eye(3)[None], FLIP_YZ)[0]
    roll, pitch, yaw = rotmat_to_euler(rot)
    assert (roll, pitch) == pytest.approx((0.0, 0.0))
    assert yaw == pytest.approx(np.pi / 2)
    assert np.linalg.det(ENU_TO_NED) == pytest.approx(1.0)


@settings(max_examples=50, deadline=None)
@given(st.floats(-1.0, 1.0), st.floats(-1.0, 1.0), st.floats(-3.0, 3.0),
       st.floats(0.5, 20.0))
def test_thrust_and_specific_force_agree(roll: float, pitch: float, yaw: float,
                                         thrust_per_kg: float) -> None:
    """An accelerometer on a vehicle pushed only by its thrust reads -T/m along body z."""
    rot = euler_to_rotmat(np.array([roll]), np.array([pitch]), np.array([yaw]))
    accel = thrust_accel(rot, np.array([thrust_per_kg]), 1.0)
    observed = specific_force_to_accel(rot, np.array([[0.0, 0.0, -thrust_per_kg]]))
    np.testing.assert_allclose(observed, accel, atol=1e-12)
    level = thrust_accel(np.eye(3)[None], np.array([9.81]), 1.0)
    np.testing.assert_allclose(level, [[0, 0, 0]], atol=1e-12)
    np.testing.assert_allclose(specific_force_to_accel(np.eye(3)[None], -9.81 * E3[None]), 0,
                               atol=1e-12)


def test_resample_quat_handles_sign_flips() -> None:
    t = np.arange(10.0)
    yaw = 0.1 * t
    q = np.stack([np.cos(yaw / 2), 0 * t, 0 * t, np.sin(yaw / 2)], axis=1)
    q[1::2] *= -1  # the same rotations, alternating signs
    out = resample_quat(t, q, t[:-1] + 0.5)
    np.testing.assert_allclose(quat_to_rotmat(out), euler_to_rotmat(0 * t[:-1], 0 * t[:-1],
                                                                    yaw[:-1] + 0.05), atol=1e-3)


def test_estimate_lag_sign() -> None:
    t = np.arange(0, 20, 0.01)
    a = np.sin(t) + np.sin(3.1 * t)
    lag, corr = estimate_lag_s(t, a, t, np.sin(t - 0.12) + np.sin(3.1 * (t - 0.12)))
    assert lag == pytest.approx(0.12, abs=0.011)
    assert corr > 0.95


def test_bracket_gap() -> None:
    src = np.array([0.0, 0.01, 0.02, 0.5, 0.51])
    gaps = bracket_gap_s(src, np.array([0.005, 0.01, 0.3, 0.505]))
    np.testing.assert_allclose(gaps, [0.01, 0.0, 0.48, 0.01])
