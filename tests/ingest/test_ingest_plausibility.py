"""Data that reads fine but means something else stops with an error naming the likely cause;
PX4 logs of older releases and other vehicles (issues 12 and 13)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from ingest_helpers import (
    DISTURBANCE,
    MASS_KG,
    G,
    synthetic_flight,
    ulog_topics,
    write_ns_file,
    write_ulog,
)

from aerodock.flightlog import FlightLog
from aerodock.geometry import rotmat_to_quat
from aerodock.ingest.csv_generic import read_csv, write_csv
from aerodock.ingest.errors import IngestError, IngestWarning
from aerodock.ingest.neural_swarm import read_neural_swarm
from aerodock.ingest.ulog import read_ulog


def _one_line_error(call, *phrases: str) -> str:  # type: ignore[no-untyped-def]
    with pytest.raises(IngestError) as info, warnings.catch_warnings():
        warnings.simplefilter("ignore", IngestWarning)
        call()
    message = str(info.value)
    assert "\n" not in message
    for phrase in phrases:
        assert phrase in message, message
    return message


# -- Neural-Swarm --------------------------------------------------------------------------------

def _times_us(n: int = 300) -> np.ndarray:
    return 9842.0 + 9874.0 * np.arange(n)


def _ns_pair(tmp_path: Path, **follower: object) -> list[Path]:
    return [write_ns_file(tmp_path / "cf1_00.csv", t_us=_times_us(), **follower),  # type: ignore[arg-type]
            write_ns_file(tmp_path / "cf2_00.csv", t_us=_times_us(),
                          pos_zup=np.tile([0, 0.3, 0.8], (300, 1)))]


def test_neural_swarm_z_already_down(tmp_path: Path) -> None:
    # a z-down export: altitude negative, the hover accelerometer reads -g along z
    paths = _ns_pair(tmp_path, pos_zup=np.tile([0, 0, -0.5], (300, 1)),
                     accel_zup=np.tile([0, 0, -G], (300, 1)))
    _one_line_error(lambda: read_neural_swarm(paths), "cf1_00.csv", "z already down")


def test_neural_swarm_accelerations_in_g(tmp_path: Path) -> None:
    paths = _ns_pair(tmp_path, accel_zup=np.tile([0, 0, 1.0], (300, 1)))
    _one_line_error(lambda: read_neural_swarm(paths), "in g, not m/s^2")


def test_neural_swarm_positions_in_mm(tmp_path: Path) -> None:
    t = _times_us() * 1e-6
    pos_mm = np.column_stack([300 * np.sin(t), 300 * np.cos(t), np.full(300, 500.0)])
    paths = _ns_pair(tmp_path, pos_zup=pos_mm)
    _one_line_error(lambda: read_neural_swarm(paths), "positions in mm")


def test_neural_swarm_quaternion_in_wxyz_order(tmp_path: Path) -> None:
    # a level vehicle's (w, x, y, z) = (1, 0, 0, 0) in the qx, qy, qz, qw columns
    paths = _ns_pair(tmp_path, quat_xyzw=np.tile([1.0, 0, 0, 0], (300, 1)),
                     accel_zup=np.tile([0, 0, G], (300, 1)))
    _one_line_error(lambda: read_neural_swarm(paths), "upside down", "w, x, y, z order")


# -- generic CSV -----------------------------------------------------------------------------

def _log(t: np.ndarray) -> FlightLog:
    fl = synthetic_flight(t)
    return FlightLog(
        t_s=t, leader_pos_m=fl["leader_p"], leader_vel_mps=fl["leader_v"],
        leader_quat=rotmat_to_quat(fl["leader_R"]), follower_pos_m=fl["p"],
        follower_vel_mps=fl["v"], follower_quat=fl["quat"], follower_cmd_accel_mps2=fl["u"],
        follower_thrust_n=fl["thrust_n"], follower_obs_accel_mps2=fl["a"],
        meta={"name": "loop", "leader_mass_kg": MASS_KG, "follower_mass_kg": MASS_KG})


def test_csv_1khz_with_time_in_ms(tmp_path: Path) -> None:
    t = np.arange(2000) * 1e-3  # 1 kHz
    log = _log(t)
    path = write_csv(log, tmp_path / "fast.csv")
    assert read_csv(path).n_samples == 2000  # fine in seconds
    log.t_s[:] = t * 1e3  # the same file with its time in ms: 1 Hz if read as s
    path = write_csv(log, tmp_path / "ms.csv")
    _one_line_error(lambda: read_csv(path), "ms.csv", "looks like milliseconds")


def test_csv_positions_in_mm(tmp_path: Path) -> None:
    log = _log(np.arange(400) * 0.01)
    log.follower_pos_m[:] *= 1000.0
    path = write_csv(log, tmp_path / "mm.csv")
    _one_line_error(lambda: read_csv(path), "follower positions change", "in mm")


def test_csv_quaternion_upside_down(tmp_path: Path) -> None:
    log = _log(np.arange(400) * 0.01)
    log.leader_quat[:] = [0.0, 1.0, 0.0, 0.0]  # pi about x: body z up
    path = write_csv(log, tmp_path / "flipped.csv")
    _one_line_error(lambda: read_csv(path), "leader attitude is upside down", "x, y, z, w order")


# -- PX4 ULog ------------------------------------------------------------------------------

def _follower(tmp_path: Path, edit=None, params=None, name: str = "bravo.ulg") -> Path:  # type: ignore[no-untyped-def]
    t = 10.0 + np.arange(600) * 0.01
    topics = ulog_topics(t, synthetic_flight(t))
    if edit:
        edit(topics, t)
    return write_ulog(tmp_path / name, topics,
                      {"MPC_THR_HOVER": 0.5} if params is None else params)


def _read_single(path: Path, **options: object) -> FlightLog:
    return read_ulog([path], single=True, mass_kg=MASS_KG, **options)[0]  # type: ignore[arg-type]


def test_ulog_old_scalar_thrust(tmp_path: Path) -> None:
    """PX4 <= 1.10: vehicle_rates_setpoint has a scalar thrust, no thrust vector topic."""
    def old(topics: dict, t: np.ndarray) -> None:  # type: ignore[type-arg]
        xyz = topics.pop("vehicle_thrust_setpoint")["xyz"]
        topics["vehicle_rates_setpoint"] = {"timestamp": topics["vehicle_attitude"]["timestamp"],
                                            "roll": np.zeros(len(t)), "thrust": -xyz[:, 2]}

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IngestWarning)
        log = _read_single(_follower(tmp_path, old))
    assert log.meta["thrust_topic"] == "vehicle_rates_setpoint.thrust"
    label = log.follower_obs_accel_mps2 - log.follower_cmd_accel_mps2
    np.testing.assert_allclose(label, np.tile(DISTURBANCE, (600, 1)), atol=1e-4)


def test_ulog_nan_row_in_hover_thrust_estimate(tmp_path: Path) -> None:
    def estimate(topics: dict, t: np.ndarray) -> None:  # type: ignore[type-arg]
        stamps = topics["vehicle_local_position"]["timestamp"][::10]
        hover = np.full(len(stamps), 0.25)
        hover[3] = np.nan
        topics["hover_thrust_estimate"] = {"timestamp": stamps, "hover_thrust": hover}

    with pytest.warns(IngestWarning, match="1 of 60 rows are NaN"):
        log = _read_single(_follower(tmp_path, estimate))
    assert log.meta["thrust_model"] == "hover_thrust from hover_thrust_estimate"
    assert np.all(np.isfinite(log.follower_cmd_accel_mps2))


def test_ulog_implausible_hover_thrust(tmp_path: Path) -> None:
    def tiny(topics: dict, t: np.ndarray) -> None:  # type: ignore[type-arg]
        stamps = topics["vehicle_local_position"]["timestamp"][::10]
        topics["hover_thrust_estimate"] = {"timestamp": stamps,
                                           "hover_thrust": np.full(len(stamps), 1e-30)}

    path = _follower(tmp_path, tiny, params={"MPC_THR_HOVER": 1e-30})
    _one_line_error(lambda: _read_single(path), "no plausible hover thrust")
    ok = _follower(tmp_path, name="ok.ulg")
    _one_line_error(lambda: _read_single(ok, hover_thrust=1e-30), "hover thrust 1e-30 is "
                                                                    "implausible")


def test_ulog_warns_when_not_a_multirotor(tmp_path: Path) -> None:
    def fixed_wing(topics: dict, t: np.ndarray) -> None:  # type: ignore[type-arg]
        topics["vehicle_status"] = {"timestamp": topics["vehicle_attitude"]["timestamp"][::50],
                                    "vehicle_type": np.full(12, 2.0)}

    with pytest.warns(IngestWarning, match=r"not a multirotor \(fixed wing\)"):
        log = _read_single(_follower(tmp_path, fixed_wing))
    assert log.n_samples == 600
    with warnings.catch_warnings():
        warnings.simplefilter("error", IngestWarning)
        quad = _read_single(_follower(tmp_path, name="quad.ulg",
                                      params={"MPC_THR_HOVER": 0.5, "MAV_TYPE": 2.0}))
    assert quad.n_samples == 600


def test_ulog_accelerometer_in_g(tmp_path: Path) -> None:
    def in_g(topics: dict, t: np.ndarray) -> None:  # type: ignore[type-arg]
        topics["vehicle_acceleration"]["xyz"] = topics["vehicle_acceleration"]["xyz"] / G

    path = _follower(tmp_path, in_g)
    _one_line_error(lambda: _read_single(path), "vehicle_acceleration", "in g, not m/s^2")


# -- CSV syntax ----------------------------------------------------------------------------

def test_csv_quoted_header_and_byte_order_mark(tmp_path: Path) -> None:
    log = _log(np.arange(300) * 0.01)
    plain = write_csv(log, tmp_path / "plain.csv")
    lines = plain.read_text().splitlines()
    header = ",".join(f'"{name}"' for name in lines[1].split(","))
    body = [",".join(f'"{v}"' if k % 3 == 0 else v for k, v in enumerate(line.split(",")))
            for line in lines[2:]]
    quoted = tmp_path / "quoted.csv"
    quoted.write_bytes(b"\xef\xbb\xbf" + "\r\n".join([lines[0], header, *body]).encode() + b"\r\n")
    back = read_csv(quoted)
    want = read_csv(plain)
    np.testing.assert_array_equal(back.follower_pos_m, want.follower_pos_m)
    np.testing.assert_array_equal(back.t_s, want.t_s)
    assert back.meta["leader_mass_kg"] == MASS_KG  # the meta comment after the BOM still counts
    # a BOM before a header that starts the file (no comment line)
    bare = tmp_path / "bare.csv"
    bare.write_bytes(b"\xef\xbb\xbf" + "\n".join([header, *body]).encode())
    assert read_csv(bare, mass_kg=MASS_KG).n_samples == 300


def test_ulog_with_the_topic_layout_of_pyulogs_old_sample(tmp_path: Path) -> None:
    """The layout of pyulog's test/sample.ulg (PX4 of 2017, per its sample_info.txt): no
    vehicle_acceleration nor thrust vector, vehicle_local_position at 10 Hz without ax/ay/az,
    vehicle_attitude and vehicle_rates_setpoint (scalar thrust) at 100 Hz, the accelerometer in
    sensor_combined, vehicle_status.is_rotary_wing. (The binary file itself is not on PyPI.)"""
    t100 = 10.0 + np.arange(1000) * 0.01
    fl = synthetic_flight(t100)
    full = ulog_topics(t100, fl)
    lp = {k: v[::10] for k, v in full["vehicle_local_position"].items()
          if k not in ("ax", "ay", "az")}
    thrust = -full["vehicle_thrust_setpoint"]["xyz"][:, 2]
    topics = {
        "vehicle_local_position": lp,
        "vehicle_attitude": full["vehicle_attitude"],
        "vehicle_rates_setpoint": {"timestamp": full["vehicle_attitude"]["timestamp"],
                                   "roll": np.zeros(1000), "pitch": np.zeros(1000),
                                   "yaw": np.zeros(1000), "thrust": thrust},
        "sensor_combined": {"timestamp": full["vehicle_acceleration"]["timestamp"],
                            "accelerometer_m_s2": full["vehicle_acceleration"]["xyz"]},
        "vehicle_status": {"timestamp": full["vehicle_attitude"]["timestamp"][::100],
                           "is_rotary_wing": np.ones(10)},
    }
    path = write_ulog(tmp_path / "old.ulg", topics, {"MPC_THR_HOVER": 0.5})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IngestWarning)
        log = _read_single(path)
    assert log.meta["thrust_topic"] == "vehicle_rates_setpoint.thrust"
    assert log.meta["obs_accel_source"] == "sensor_combined"
    assert log.meta["vehicle_type"] == "rotary wing"
    assert 95 <= log.n_samples <= 100  # the 10 Hz local position is the time base
    label = log.follower_obs_accel_mps2 - log.follower_cmd_accel_mps2
    np.testing.assert_allclose(label, np.tile(DISTURBANCE, (log.n_samples, 1)), atol=1e-4)
