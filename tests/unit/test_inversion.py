"""Inversion map: round trip, hover, sign conventions and saturation."""

from __future__ import annotations

import numpy as np
import pytest

from aerodock.control.inversion import accel_to_attitude_thrust, attitude_thrust_to_accel
from aerodock.geometry import euler_to_rotmat

G = 9.81
TILT_MAX = np.deg2rad(35.0)


def tilt_of(roll: np.ndarray, pitch: np.ndarray) -> np.ndarray:
    """Angle between the body z axis and the world z axis."""
    return np.arccos(np.clip(np.cos(roll) * np.cos(pitch), -1.0, 1.0))


def test_hover():
    n = 4
    mass = np.array([0.5, 0.7, 1.0, 2.0])
    yaw = np.array([0.0, 1.0, -2.0, 3.0])
    roll, pitch, thrust = accel_to_attitude_thrust(np.zeros((n, 3)), yaw, mass, G, TILT_MAX,
                                                   2.0 * mass * G)
    np.testing.assert_allclose(thrust, mass * G, rtol=1e-12)
    np.testing.assert_allclose(roll, 0.0, atol=1e-12)
    np.testing.assert_allclose(pitch, 0.0, atol=1e-12)


def test_round_trip_within_limits():
    rng = np.random.default_rng(0)
    n = 2000
    mass = rng.uniform(0.4, 2.0, n)
    thrust_max = 2.0 * mass * G
    yaw = rng.uniform(-np.pi, np.pi, n)
    accel = np.column_stack([rng.uniform(-6, 6, (n, 2)), rng.uniform(-8, 8, n)])
    f = mass[:, None] * (np.array([0.0, 0.0, G]) - accel)
    inside = (np.linalg.norm(f[:, :2], axis=1) < 0.999 * f[:, 2] * np.tan(TILT_MAX)) & (
        np.linalg.norm(f, axis=1) < 0.999 * thrust_max
    )
    assert inside.sum() > 500  # the test exercises a substantial set
    accel, mass, yaw, thrust_max = accel[inside], mass[inside], yaw[inside], thrust_max[inside]
    roll, pitch, thrust = accel_to_attitude_thrust(accel, yaw, mass, G, TILT_MAX, thrust_max)
    back = attitude_thrust_to_accel(roll, pitch, yaw, thrust, mass, G)
    np.testing.assert_allclose(back, accel, atol=1e-9)
    # The requested yaw is the yaw of the resulting attitude (up to wrap).
    rot = euler_to_rotmat(roll, pitch, yaw)
    heading = np.arctan2(rot[:, 1, 0], rot[:, 0, 0])
    np.testing.assert_allclose(np.cos(heading - yaw), 1.0, atol=1e-9)


def test_scalar_mass_and_thrust_limit_broadcast():
    accel = np.array([[1.0, -2.0, 0.5], [0.0, 0.0, -3.0]])
    yaw = np.array([0.3, -1.2])
    out_scalar = accel_to_attitude_thrust(accel, yaw, 0.7, G, TILT_MAX, 2 * 0.7 * G)
    out_vector = accel_to_attitude_thrust(accel, yaw, np.full(2, 0.7), G, TILT_MAX,
                                          np.full(2, 2 * 0.7 * G))
    for a, b in zip(out_scalar, out_vector, strict=True):
        np.testing.assert_allclose(a, b, atol=1e-15)


def test_sign_conventions():
    """NED: nose-up pitch accelerates backwards (south at yaw 0), right roll goes east."""
    mass = 1.0
    acc_north = accel_to_attitude_thrust(np.array([[2.0, 0.0, 0.0]]), np.zeros(1), mass, G,
                                         TILT_MAX, 30.0)
    assert acc_north[1][0] < 0.0 and abs(acc_north[0][0]) < 1e-12  # nose down
    acc_east = accel_to_attitude_thrust(np.array([[0.0, 2.0, 0.0]]), np.zeros(1), mass, G,
                                        TILT_MAX, 30.0)
    assert acc_east[0][0] > 0.0 and abs(acc_east[1][0]) < 1e-12  # right wing down
    climb = accel_to_attitude_thrust(np.array([[0.0, 0.0, -2.0]]), np.zeros(1), mass, G,
                                     TILT_MAX, 30.0)
    assert climb[2][0] == pytest.approx(mass * (G + 2.0))  # climbing (up = -z) needs more thrust


def test_saturation_finite_and_within_limits():
    mass = 0.7
    thrust_max = 2.0 * mass * G
    accel = np.array(
        [
            [50.0, 0.0, 0.0],  # tilt limited
            [-30.0, 40.0, 2.0],  # tilt limited
            [0.0, 0.0, G],  # exactly free fall
            [5.0, -3.0, 2.0 * G],  # downward faster than g: impossible
            [0.0, 0.0, -3.0 * G],  # climb beyond thrust limit
            [8.0, 8.0, -0.9 * G],  # tilt and thrust limited
            [0.0, 0.0, 0.0],
        ]
    )
    n = len(accel)
    yaw = np.linspace(-3.0, 3.0, n)
    roll, pitch, thrust = accel_to_attitude_thrust(accel, yaw, mass, G, TILT_MAX, thrust_max)
    assert np.all(np.isfinite(roll)) and np.all(np.isfinite(pitch)) and np.all(np.isfinite(thrust))
    assert np.all(tilt_of(roll, pitch) <= TILT_MAX + 1e-12)
    assert np.all((thrust >= 0.0) & (thrust <= thrust_max * (1 + 1e-12)))
    achieved = attitude_thrust_to_accel(roll, pitch, yaw, thrust, mass, G)

    # Tilt-limited only: at the tilt limit, vertical kept, horizontal direction kept.
    for i in (0, 1):
        assert tilt_of(roll[i], pitch[i]) == pytest.approx(TILT_MAX, abs=1e-9)
        assert achieved[i, 2] == pytest.approx(accel[i, 2], abs=1e-9)
        h_want, h_got = accel[i, :2], achieved[i, :2]
        assert h_want[0] * h_got[1] - h_want[1] * h_got[0] == pytest.approx(0.0, abs=1e-9)
        assert h_want @ h_got > 0.0
    # Impossible downward accelerations: level, no thrust (free fall).
    for i in (2, 3):
        assert thrust[i] == 0.0 and roll[i] == 0.0 and pitch[i] == 0.0
        np.testing.assert_allclose(achieved[i], [0.0, 0.0, G], atol=1e-12)
    # Vertical beyond the thrust limit: level at full thrust.
    assert thrust[4] == pytest.approx(thrust_max)
    assert tilt_of(roll[4], pitch[4]) == pytest.approx(0.0, abs=1e-12)
    # Thrust limited with a horizontal demand: full thrust, vertical kept, some horizontal left.
    assert thrust[5] == pytest.approx(thrust_max)
    assert achieved[5, 2] == pytest.approx(accel[5, 2], abs=1e-9)
    assert 0.0 < np.linalg.norm(achieved[5, :2]) < np.linalg.norm(accel[5, :2])


def test_bad_tilt_limit_raises():
    with pytest.raises(ValueError):
        accel_to_attitude_thrust(np.zeros((1, 3)), np.zeros(1), 1.0, G, np.pi / 2, 20.0)
