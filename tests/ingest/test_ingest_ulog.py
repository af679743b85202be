"""PX4 ULog reader: the real shared sample, minimal files built to the ULog spec, bad input."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from ingest_helpers import DISTURBANCE, MASS_KG, synthetic_flight, ulog_topics, write_ulog

from aerodock.geometry import quat_to_rotmat
from aerodock.ingest import read_logs
from aerodock.ingest.errors import IngestError, IngestWarning
from aerodock.ingest.ulog import read_ulog

pytest.importorskip("pyulog")


def test_real_sample_single(ulog_sample: Path) -> None:
    with pytest.warns(IngestWarning) as caught:
        logs = read_logs("ulog", [ulog_sample], single=True, mass_kg=1.5)
    notes = [str(w.message) for w in caught]
    assert any("horizontal position valid in only 0%" in n for n in notes)
    # the sample is a standard VTOL (MAV_TYPE 22) hovering as a multirotor: flagged
    assert any("not a multirotor (a VTOL, in multirotor mode in 100% of" in n for n in notes)
    assert logs[0].meta["vehicle_type"].startswith("a VTOL")
    assert len(logs) == 1
    log = logs[0]
    assert log.name == "sample_log_small"
    assert log.meta["source"] == "ulog"
    assert log.meta["label_basis"] == "thrust"
    assert log.meta["leader"] == "virtual"
    assert log.meta["thrust_topic"] == "vehicle_rates_setpoint.thrust_body"
    assert log.meta["thrust_model"] == "hover_thrust from MPC_THR_HOVER"
    assert log.meta["obs_accel_source"] == "vehicle_local_position.ax/ay/az"
    assert log.meta["follower_mass_kg"] == 1.5
    assert 600 < log.n_samples < 700
    assert 6.0 < log.duration_s < 6.6
    assert np.median(np.diff(log.t_s)) == pytest.approx(0.01, abs=0.002)
    # NED: the vehicle is above the ground (z < 0), almost level, almost still.
    assert np.all(log.follower_pos_m[:, 2] < 0)
    tilt = np.degrees(np.arccos(np.clip(quat_to_rotmat(log.follower_quat)[:, 2, 2], -1, 1)))
    assert tilt.max() < 15
    assert np.abs(log.follower_obs_accel_mps2).max() < 1.0
    # With no thrust set, the thrust-based command is free fall: g e3.
    idle = log.follower_thrust_n == 0
    assert idle.any()
    np.testing.assert_allclose(log.follower_cmd_accel_mps2[idle], [[0, 0, 9.81]] * idle.sum(),
                               atol=1e-12)
    # Landed samples (vehicle_land_detected) are marked as no label; in the air there is thrust.
    valid = log.extra["label_valid"]
    assert 0.1 < valid.mean() < 0.3
    assert log.meta["landed_fraction"] == pytest.approx(1 - valid.mean())
    assert np.all(log.follower_thrust_n[valid] > 1.0)
    # Virtual leader: still, 100 m above the follower's start.
    np.testing.assert_allclose(log.leader_pos_m - log.follower_pos_m[0], [[0, 0, -100]] * 634)
    np.testing.assert_array_equal(log.leader_vel_mps, 0)


def test_real_sample_needs_pairs_or_single(ulog_sample: Path) -> None:
    with pytest.raises(IngestError, match="give pairs .* or --single"):
        read_ulog([ulog_sample], mass_kg=1.0)


def _pair(tmp_path: Path, n_leader: int = 800, t0_leader: float = 10.0,
          edit_follower=None) -> list[Path]:  # type: ignore[no-untyped-def]
    t = 10.0 + np.arange(800) * 0.01
    fl = synthetic_flight(t)
    t_l = t0_leader + np.arange(n_leader) * 0.01
    leader = write_ulog(tmp_path / "alpha.ulg", ulog_topics(t_l, synthetic_flight(t_l),
                                                            role="leader"),
                        {"MPC_THR_HOVER": 0.5})
    topics = ulog_topics(t, fl)
    if edit_follower:
        edit_follower(topics)
    follower = write_ulog(tmp_path / "bravo.ulg", topics, {"MPC_THR_HOVER": 0.5})
    return [leader, follower]


def test_pair_built_to_the_spec(tmp_path: Path) -> None:
    paths = _pair(tmp_path)
    log = read_ulog(paths, mass_kg=MASS_KG)[0]
    fl = synthetic_flight(10.0 + np.arange(800) * 0.01)
    assert log.name == "bravo_with_alpha"
    assert log.meta["files"] == {"leader": str(paths[0]), "follower": str(paths[1])}
    assert log.meta["obs_accel_source"] == "vehicle_acceleration"
    np.testing.assert_allclose(log.follower_pos_m, fl["p"], atol=1e-6)
    np.testing.assert_allclose(log.leader_pos_m, fl["leader_p"], atol=1e-6)
    np.testing.assert_allclose(log.follower_thrust_n, fl["thrust_n"], rtol=1e-5)
    label = log.follower_obs_accel_mps2 - log.follower_cmd_accel_mps2
    np.testing.assert_allclose(label, np.tile(DISTURBANCE, (800, 1)), atol=1e-4)
    np.testing.assert_allclose(log.extra["leader_thrust_n"], MASS_KG * 9.81, rtol=1e-5)


def test_hover_thrust_option_and_estimate_topic(tmp_path: Path) -> None:
    def add_estimate(topics: dict) -> None:  # type: ignore[type-arg]
        stamps = topics["vehicle_local_position"]["timestamp"][::10]
        topics["hover_thrust_estimate"] = {"timestamp": stamps,
                                           "hover_thrust": np.full(len(stamps), 0.5)}

    paths = _pair(tmp_path, edit_follower=add_estimate)
    log = read_ulog(paths, mass_kg=MASS_KG)[0]
    assert log.meta["thrust_model"] == "hover_thrust from hover_thrust_estimate"
    other = read_ulog(paths, mass_kg=MASS_KG, hover_thrust=0.25)[0]
    assert other.meta["thrust_model"] == "hover_thrust from option"
    # Half the hover thrust: the same set point explains twice the acceleration.
    np.testing.assert_allclose(other.follower_thrust_n, 2 * log.follower_thrust_n, rtol=1e-9)


# --------------------------------------------------------------------------------------------
# Bad input
# --------------------------------------------------------------------------------------------


def _expect(paths: list[Path], bad: Path, *phrases: str, **options: object) -> None:
    with pytest.raises(IngestError) as info, warnings.catch_warnings():
        warnings.simplefilter("ignore", IngestWarning)
        read_ulog(paths, **{"mass_kg": MASS_KG, **options})  # type: ignore[arg-type]
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"{bad}: ")
    for phrase in phrases:
        assert phrase in message, message


def test_missing_topic(tmp_path: Path) -> None:
    paths = _pair(tmp_path, edit_follower=lambda tp: tp.pop("vehicle_attitude"))
    _expect(paths, paths[1], "missing topic vehicle_attitude")


def test_missing_thrust_topic(tmp_path: Path) -> None:
    paths = _pair(tmp_path, edit_follower=lambda tp: tp.pop("vehicle_thrust_setpoint"))
    _expect(paths, paths[1], "missing topic: no thrust setpoint")


def test_nan(tmp_path: Path) -> None:
    def put_nan(topics: dict) -> None:  # type: ignore[type-arg]
        topics["vehicle_local_position"]["z"] = topics["vehicle_local_position"]["z"].copy()
        topics["vehicle_local_position"]["z"][17] = np.nan

    paths = _pair(tmp_path, edit_follower=put_nan)
    _expect(paths, paths[1], "NaN in column 'vehicle_local_position.z' at sample 17")


def _edit_stamps(edit):  # type: ignore[no-untyped-def]
    def apply(topics: dict) -> None:  # type: ignore[type-arg]
        for fields in topics.values():
            fields["timestamp"] = edit(fields["timestamp"].copy())
    return apply


def test_non_monotonic_time(tmp_path: Path) -> None:
    def swap(s: np.ndarray) -> np.ndarray:
        s[[50, 51]] = s[[51, 50]]
        return s

    paths = _pair(tmp_path, edit_follower=_edit_stamps(swap))
    _expect(paths, paths[1], "timestamp' is not monotonic", "sample 51")


def test_duplicated_time(tmp_path: Path) -> None:
    def dup(s: np.ndarray) -> np.ndarray:
        s[60] = s[59]
        return s

    paths = _pair(tmp_path, edit_follower=_edit_stamps(dup))
    _expect(paths, paths[1], "duplicated time", "sample 60")


def test_time_in_milliseconds(tmp_path: Path) -> None:
    paths = _pair(tmp_path, edit_follower=_edit_stamps(lambda s: s // 1000))
    _expect(paths, paths[1], "looks like milliseconds, expected microseconds")


def test_files_of_different_lengths(tmp_path: Path) -> None:
    paths = _pair(tmp_path, n_leader=200)
    _expect(paths, paths[1], "files of different lengths", "alpha.ulg")


def test_empty_file(tmp_path: Path) -> None:
    paths = _pair(tmp_path)
    paths[0].write_bytes(b"")
    _expect(paths, paths[0], "empty file")


def test_not_a_ulog_file(tmp_path: Path) -> None:
    paths = _pair(tmp_path)
    paths[1].write_bytes(b"this is not a ulog file at all")
    _expect(paths, paths[1], "not a readable ULog file")


def test_no_hover_thrust(tmp_path: Path) -> None:
    t = 10.0 + np.arange(100) * 0.01
    path = write_ulog(tmp_path / "solo.ulg", ulog_topics(t, synthetic_flight(t)))
    _expect([path], path, "no plausible hover thrust", single=True)
