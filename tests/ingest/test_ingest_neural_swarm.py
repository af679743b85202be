"""Neural-Swarm reader: the real shared flights, synthetic files, and bad input."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from ingest_helpers import NEURAL_SWARM_DIR, NS_HEADER, write_ns_file

from aerodock.flightlog import FlightLog
from aerodock.geometry import rotmat_to_quat
from aerodock.ingest import read_logs
from aerodock.ingest.errors import IngestError
from aerodock.ingest.neural_swarm import read_neural_swarm, read_vehicle_file


@pytest.fixture(scope="module")
def real_logs() -> list[FlightLog]:
    if not NEURAL_SWARM_DIR.is_dir():
        pytest.skip(f"shared data not found at {NEURAL_SWARM_DIR}")
    return read_logs("neural-swarm", [NEURAL_SWARM_DIR])


def _hover_far(log: FlightLog) -> np.ndarray:
    lateral = np.linalg.norm(log.follower_pos_m[:, :2] - log.leader_pos_m[:, :2], axis=1)
    return (np.linalg.norm(log.follower_vel_mps, axis=1) < 0.1) & (lateral > 0.2)


# --------------------------------------------------------------------------------------------
# Real data
# --------------------------------------------------------------------------------------------


def test_real_flights_are_paired_with_both_roles(real_logs: list[FlightLog]) -> None:
    assert len(real_logs) == 14  # 7 flights x 2 roles
    names = [log.name for log in real_logs]
    assert names[:2] == ["swap_ss_00_cf50", "swap_ss_00_cf51"]
    for first, second in zip(real_logs[::2], real_logs[1::2], strict=True):
        assert first.meta["flight_id"] == second.meta["flight_id"]
        assert (first.meta["follower_id"], first.meta["leader_id"]) == ("cf50", "cf51")
        assert (second.meta["follower_id"], second.meta["leader_id"]) == ("cf51", "cf50")
    for log in real_logs:
        assert log.meta["source"] == "neural-swarm"
        assert log.meta["frame"] == "NED"
        assert log.meta["label_basis"] == "thrust"
        assert log.meta["leader_mass_kg"] == log.meta["follower_mass_kg"] == 0.032
        assert log.meta["time_unit_detected"] == {"leader": "us", "follower": "us"}
        assert 18.0 < log.duration_s < 27.5
        assert np.median(np.diff(log.t_s)) == pytest.approx(0.0099, abs=0.0003)


def test_real_alignment_is_checked(real_logs: list[FlightLog]) -> None:
    for log in real_logs:
        assert abs(log.meta["clock_start_offset_s"]) < 0.01
        assert log.meta["clock_lag_correlation"] > 0.9
        assert abs(log.meta["clock_lag_estimate_s"]) <= 0.03
    # The leader of one role is the follower of the other, interpolated onto the other's clock.
    a, b = real_logs[0], real_logs[1]
    t_a = a.t_s + a.meta["t_origin_s"]
    t_b = b.t_s + b.meta["t_origin_s"]
    inside = (t_a > t_b[0]) & (t_a < t_b[-1])
    for k in range(3):
        ref = np.interp(t_a[inside], t_b, b.follower_pos_m[:, k])
        assert np.max(np.abs(a.leader_pos_m[inside, k] - ref)) < 0.01


def test_real_hover_frame_sanity(real_logs: list[FlightLog]) -> None:
    """NED: vehicles at negative z; hovering clear of the other, a_obs ~ 0, cmd ~ 0 + bias."""
    residual_bias = []
    for log in real_logs:
        assert np.all(log.follower_pos_m[:, 2] < -0.3)
        assert np.all(log.leader_pos_m[:, 2] < -0.3)
        hover = _hover_far(log)
        if hover.sum() < 50:
            continue
        obs = log.follower_obs_accel_mps2[hover].mean(axis=0)
        cmd = log.follower_cmd_accel_mps2[hover].mean(axis=0)
        assert np.all(np.abs(obs) < 0.2), obs
        assert np.all(np.abs(cmd[:2]) < 0.1), cmd
        assert -0.6 < cmd[2] < -0.2, cmd  # thrust slightly above weight: the known bias
        residual_bias.append((obs - cmd)[2])
    assert len(residual_bias) >= 10
    assert 0.2 < np.mean(residual_bias) < 0.5  # the dataset's 0.3-0.5 m/s² constant bias


def test_real_downwash_pushes_the_lower_vehicle_down(real_logs: list[FlightLog]) -> None:
    gains = []
    for log in real_logs:
        if log.meta["follower_id"] != "cf50":  # cf50 flies the lower layer
            continue
        dp = log.follower_pos_m - log.leader_pos_m
        below = (np.linalg.norm(dp[:, :2], axis=1) < 0.05) & (dp[:, 2] > 0.2) & (dp[:, 2] < 0.4)
        label_z = (log.follower_obs_accel_mps2 - log.follower_cmd_accel_mps2)[:, 2]
        far = _hover_far(log)
        if below.sum() >= 20 and far.sum() >= 20:
            gains.append(label_z[below].mean() - label_z[far].mean())
    assert len(gains) >= 5
    assert 2.0 < np.mean(gains) < 4.5  # about a quarter of the weight, downwards (+z NED)


def test_real_attitude_conversion_matches_motion(real_logs: list[FlightLog]) -> None:
    """Tilt (cmd) and measured horizontal acceleration agree in sign: frames are consistent."""
    for log in real_logs[::2]:
        for k in range(2):
            corr = np.corrcoef(log.follower_obs_accel_mps2[:, k],
                               log.follower_cmd_accel_mps2[:, k])[0, 1]
            assert corr > 0.6


def test_real_masses_from_options(neural_swarm_dir: Path) -> None:
    files = [neural_swarm_dir / "cf50_01.csv", neural_swarm_dir / "cf51_01.csv"]
    large = read_neural_swarm(files, vehicle="large")
    assert large[0].meta["follower_mass_kg"] == 0.067
    mixed = read_neural_swarm(files, vehicle="cf50=small,cf51=large")
    assert mixed[0].meta["follower_mass_kg"] == 0.032
    assert mixed[0].meta["leader_mass_kg"] == 0.067
    explicit = read_neural_swarm(files, mass_kg=0.05)
    assert explicit[1].meta["follower_mass_kg"] == 0.05
    # A lone file finds its partner in its folder.
    assert len(read_neural_swarm([files[0]])) == 2


# --------------------------------------------------------------------------------------------
# Synthetic files: conversion details
# --------------------------------------------------------------------------------------------


def _times_us(n: int = 300, t0: float = 9842.0) -> np.ndarray:
    return t0 + 9874.0 * np.arange(n)


def test_hover_file_gives_zero_accelerations(tmp_path: Path) -> None:
    write_ns_file(tmp_path / "cf1_00.csv", t_us=_times_us())
    write_ns_file(tmp_path / "cf2_00.csv", t_us=_times_us(), pos_zup=np.tile([0, 0.3, 0.8],
                                                                             (300, 1)))
    log = read_neural_swarm([tmp_path / "cf1_00.csv", tmp_path / "cf2_00.csv"])[0]
    np.testing.assert_allclose(log.follower_pos_m[0], [0, 0, -0.5])
    np.testing.assert_allclose(log.leader_pos_m[0], [0, -0.3, -0.8])
    np.testing.assert_allclose(log.follower_obs_accel_mps2, 0, atol=1e-12)
    np.testing.assert_allclose(log.follower_cmd_accel_mps2, 0, atol=1e-12)
    np.testing.assert_allclose(log.follower_thrust_n, 0.032 * 9.81)


def test_tilted_consistent_physics_gives_zero_residual(tmp_path: Path) -> None:
    """For any attitude, a_meas = R e3 T/m in z-up must give a_obs = cmd in NED."""
    rng = np.random.default_rng(0)
    n = 300
    q = rng.normal(size=(n, 4)) * [0.15, 0.15, 1.0, 1.0]  # xyzw, moderate tilt, any yaw
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    thrust = 0.032 * 9.81 * rng.uniform(0.8, 1.2, n)
    write_ns_file(tmp_path / "cf1_00.csv", t_us=_times_us(n), quat_xyzw=q, thrust_n=thrust)
    write_ns_file(tmp_path / "cf2_00.csv", t_us=_times_us(n))
    log = read_neural_swarm([tmp_path / "cf1_00.csv", tmp_path / "cf2_00.csv"])[0]
    np.testing.assert_allclose(log.follower_obs_accel_mps2, log.follower_cmd_accel_mps2,
                               atol=1e-9)
    assert np.abs(log.follower_cmd_accel_mps2[:, :2]).max() > 0.5  # really tilted
    # roll is kept, pitch and yaw change sign (rotation of pi about x): q -> (w, x, -y, -z)
    expected = q[:, [3, 0, 1, 2]] * [1, 1, -1, -1]
    expected *= np.where(expected[:, :1] < 0, -1, 1)
    np.testing.assert_allclose(log.follower_quat, expected, atol=1e-9)
    np.testing.assert_allclose(rotmat_to_quat(np.eye(3)), [1, 0, 0, 0])


def test_motor_torque_and_commands_are_kept(tmp_path: Path) -> None:
    """The logs' motor torque (body FLU) reaches the follower's FlightLog in FRD, its motor
    commands unchanged: what aerodock.identify.wake_torque reads."""
    n = 300
    torque = np.tile([1e-3, 2e-3, -3e-4], (n, 1))
    pwm = np.tile([0.61, 0.62, 0.63, 0.64], (n, 1))
    write_ns_file(tmp_path / "cf1_00.csv", t_us=_times_us(n), torque_flu=torque, pwm=pwm)
    write_ns_file(tmp_path / "cf2_00.csv", t_us=_times_us(n))
    log = read_neural_swarm([tmp_path / "cf1_00.csv", tmp_path / "cf2_00.csv"])[0]
    assert log.meta["follower_id"] == "cf1"
    np.testing.assert_allclose(log.extra["follower_motor_torque_nm"], [[1e-3, -2e-3, 3e-4]] * n)
    np.testing.assert_allclose(log.extra["follower_motor_pwm"], pwm)
    # the per-motor thrusts asked for (u1..u4) and the battery's voltage, as logged
    np.testing.assert_allclose(log.extra["follower_motor_thrust_n"],
                               0.032 * 9.81 / 4 * np.ones((n, 4)), rtol=1e-3)
    np.testing.assert_allclose(log.extra["follower_battery_v"], 3.7)


@pytest.mark.parametrize("scale, unit", [(1.0, "us"), (1e-3, "ms"), (1e-6, "s")])
def test_time_unit_is_detected(tmp_path: Path, scale: float, unit: str) -> None:
    path = write_ns_file(tmp_path / "cf1_00.csv", t_us=_times_us() * scale)
    track = read_vehicle_file(path)
    assert track.time_unit == unit
    np.testing.assert_allclose(track.t_s, _times_us() * 1e-6, rtol=1e-12)


# --------------------------------------------------------------------------------------------
# Bad input: one line naming the file and the problem
# --------------------------------------------------------------------------------------------


def _pair(tmp_path: Path, n_a: int = 300, n_b: int = 300, t0_b: float = 9700.0) -> list[Path]:
    return [write_ns_file(tmp_path / "cf1_00.csv", t_us=_times_us(n_a)),
            write_ns_file(tmp_path / "cf2_00.csv", t_us=_times_us(n_b, t0_b))]


def _expect_error(paths: list[Path], bad: Path, *phrases: str, **options: object) -> str:
    with pytest.raises(IngestError) as info:
        read_neural_swarm(paths, **options)  # type: ignore[arg-type]
    message = str(info.value)
    assert "\n" not in message
    assert str(bad) in message
    for phrase in phrases:
        assert phrase in message, message
    return message


def _rewrite(path: Path, edit) -> None:  # type: ignore[no-untyped-def]
    lines = path.read_text().splitlines()
    path.write_text("\n".join(edit(lines)) + "\n")


def test_missing_column(tmp_path: Path) -> None:
    paths = _pair(tmp_path)
    write_ns_file(paths[0], t_us=_times_us(), header=NS_HEADER.replace("az[m/s^2]", "azz"))
    _expect_error(paths, paths[0], "missing columns: az")


def test_missing_motor_thrust_in_newton(tmp_path: Path) -> None:
    paths = _pair(tmp_path)
    write_ns_file(paths[0], t_us=_times_us(), header=NS_HEADER.replace("u3[N]", "u3[X]"))
    _expect_error(paths, paths[0], "missing columns: u3[N]")


def test_nan_value(tmp_path: Path) -> None:
    paths = _pair(tmp_path)

    def put_nan(lines: list[str]) -> list[str]:
        fields = lines[11].split(",")
        fields[1] = "nan"
        lines[11] = ",".join(fields)
        return lines

    _rewrite(paths[1], put_nan)
    _expect_error(paths, paths[1], "NaN in column 'x[m]' at line 12")


def test_non_monotonic_time(tmp_path: Path) -> None:
    paths = _pair(tmp_path)
    _rewrite(paths[0], lambda ls: ls[:20] + [ls[22], ls[21], ls[20]] + ls[23:])
    _expect_error(paths, paths[0], "not monotonic", "line 22")


def test_duplicated_time(tmp_path: Path) -> None:
    paths = _pair(tmp_path)
    _rewrite(paths[0], lambda ls: ls[:30] + [ls[30]] + ls[30:])
    _expect_error(paths, paths[0], "duplicated time", "line 32")


def test_time_unit_that_fits_nothing(tmp_path: Path) -> None:
    paths = _pair(tmp_path)
    write_ns_file(paths[0], t_us=_times_us() * 0.03)  # 3.3 kHz if µs, 0.3 Hz if ms
    _expect_error(paths, paths[0], "cannot tell the unit")


def test_declared_ms_but_values_in_us(tmp_path: Path) -> None:
    paths = _pair(tmp_path)
    _expect_error(paths, paths[0], "looks like microseconds", "expected milliseconds",
                  time_unit="ms")


def test_files_of_different_lengths(tmp_path: Path) -> None:
    paths = _pair(tmp_path, n_b=90)
    _expect_error(paths, paths[0], "files of different lengths", "cf2_00.csv")


def test_clocks_that_do_not_agree(tmp_path: Path) -> None:
    paths = _pair(tmp_path, n_b=800, t0_b=5e6)
    _expect_error(paths, paths[0], "clocks do not agree")


def test_empty_file(tmp_path: Path) -> None:
    paths = _pair(tmp_path)
    paths[1].write_text("")
    _expect_error(paths, paths[1], "empty file")


def test_header_without_rows(tmp_path: Path) -> None:
    paths = _pair(tmp_path)
    paths[1].write_text(NS_HEADER + "\n")
    _expect_error(paths, paths[1], "no data rows")


def test_truncated_row(tmp_path: Path) -> None:
    paths = _pair(tmp_path)
    _rewrite(paths[0], lambda ls: ls[:-1] + [ls[-1].rsplit(",", 3)[0]])
    _expect_error(paths, paths[0], "line 301 has 27 fields, the header has 30")


def test_text_in_a_number_column(tmp_path: Path) -> None:
    paths = _pair(tmp_path)

    def put_text(lines: list[str]) -> list[str]:
        fields = lines[5].split(",")
        fields[2] = "abc"
        lines[5] = ",".join(fields)
        return lines

    _rewrite(paths[0], put_text)
    _expect_error(paths, paths[0], "line 6: column 'y[m]' holds 'abc', not a number")


def test_not_a_unit_quaternion(tmp_path: Path) -> None:
    paths = _pair(tmp_path)
    write_ns_file(paths[0], t_us=_times_us(), quat_xyzw=np.tile([0, 0, 0, 2.0], (300, 1)))
    _expect_error(paths, paths[0], "not a unit quaternion")


def test_no_partner_file(tmp_path: Path) -> None:
    path = write_ns_file(tmp_path / "cf1_03.csv", t_us=_times_us())
    _expect_error([path], path, "no partner file for flight 03")


def test_bad_file_name(tmp_path: Path) -> None:
    path = write_ns_file(tmp_path / "flight.csv", t_us=_times_us())
    _expect_error([path], path, "not a Neural-Swarm file name")


def test_unknown_vehicle_type(tmp_path: Path) -> None:
    paths = _pair(tmp_path)
    _expect_error(paths, paths[0], "unknown vehicle type 'medium'", vehicle="medium")


def test_option_of_another_format_is_rejected(tmp_path: Path) -> None:
    _pair(tmp_path)
    with pytest.raises(IngestError, match="option --single does not apply"):
        read_logs("neural-swarm", [tmp_path], single=True)
