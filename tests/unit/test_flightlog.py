"""FlightLog: on-disk round trip, validation and safe, atomic writes."""

from __future__ import annotations

import numpy as np
import pytest

from aerodock.flightlog import FlightLog, FlightLogError, load_flightlogs, save_flightlogs


def make_log(n=50, name="f"):
    t = np.arange(n) * 0.01
    z3 = np.zeros((n, 3))
    q = np.tile([1.0, 0, 0, 0], (n, 1))
    return FlightLog(t, z3, z3, q, z3 + 1, z3, q, z3, np.full(n, 6.9), z3,
                     meta={"name": name, "follower_mass_kg": 0.7},
                     extra={"true_field_mean_mps2": z3 + 2})


def test_round_trip(tmp_path):
    logs = [make_log(name="a"), make_log(30, name="b")]
    path = save_flightlogs(tmp_path / "logs.npz", logs)
    back = load_flightlogs(path)
    assert [lg.name for lg in back] == ["a", "b"]
    assert back[1].n_samples == 30
    assert np.array_equal(back[0].follower_pos_m, logs[0].follower_pos_m)
    assert np.array_equal(back[0].extra["true_field_mean_mps2"], logs[0].extra[
        "true_field_mean_mps2"])
    assert back[0].meta["follower_mass_kg"] == 0.7


def test_validation():
    log = make_log()
    with pytest.raises(FlightLogError, match="not strictly increasing"):
        FlightLog(log.t_s[::-1], *[getattr(log, f) for f in (
            "leader_pos_m", "leader_vel_mps", "leader_quat", "follower_pos_m",
            "follower_vel_mps", "follower_quat", "follower_cmd_accel_mps2", "follower_thrust_n",
            "follower_obs_accel_mps2")])
    bad = log.follower_pos_m.copy()
    bad[3, 1] = np.nan
    with pytest.raises(FlightLogError, match="NaN"):
        FlightLog(log.t_s, log.leader_pos_m, log.leader_vel_mps, log.leader_quat, bad,
                  log.follower_vel_mps, log.follower_quat, log.follower_cmd_accel_mps2,
                  log.follower_thrust_n, log.follower_obs_accel_mps2)


def test_corrupt_and_foreign_files(tmp_path):
    junk = tmp_path / "junk.npz"
    junk.write_bytes(b"definitely not a zip")
    with pytest.raises(FlightLogError, match="corrupt") as err:
        load_flightlogs(junk)
    assert str(junk) in str(err.value)
    other = tmp_path / "other.npz"
    np.savez(other, x=np.zeros(3))
    with pytest.raises(FlightLogError, match="not an aerodock FlightLog"):
        load_flightlogs(other)
    with pytest.raises(FlightLogError, match="not found"):
        load_flightlogs(tmp_path / "absent.npz")


def test_failed_write_keeps_the_old_file(tmp_path, monkeypatch):
    path = save_flightlogs(tmp_path / "logs.npz", [make_log(name="old")])

    def boom(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(np, "savez_compressed", boom)
    with pytest.raises(OSError):
        save_flightlogs(path, [make_log(name="new")])
    assert load_flightlogs(path)[0].name == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["logs.npz"]  # no temp file left behind
