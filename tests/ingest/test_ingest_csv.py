"""Generic CSV reader: round trip, frames, optional columns and bad input."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from ingest_helpers import DISTURBANCE, MASS_KG, synthetic_flight

from aerodock.flightlog import FlightLog
from aerodock.geometry import quat_to_rotmat, rotmat_to_quat
from aerodock.ingest import read_logs
from aerodock.ingest.common import ENU_TO_NED, FLIP_YZ
from aerodock.ingest.csv_generic import REQUIRED_COLUMNS, read_csv, write_csv
from aerodock.ingest.csv_table import read_csv_table
from aerodock.ingest.errors import IngestError


def _log(n: int = 200) -> FlightLog:
    fl = synthetic_flight(np.arange(n) * 0.01)
    return FlightLog(
        t_s=fl["t"], leader_pos_m=fl["leader_p"], leader_vel_mps=fl["leader_v"],
        leader_quat=rotmat_to_quat(fl["leader_R"]), follower_pos_m=fl["p"],
        follower_vel_mps=fl["v"], follower_quat=fl["quat"], follower_cmd_accel_mps2=fl["u"],
        follower_thrust_n=fl["thrust_n"], follower_obs_accel_mps2=fl["a"],
        meta={"name": "loop", "leader_mass_kg": MASS_KG, "follower_mass_kg": MASS_KG,
              "label_basis": "command", "source": "sim"},
        extra={"leader_thrust_n": np.full(n, MASS_KG * 9.81), "ref_pos_m": fl["p"] + 0.01},
    )


def test_round_trip_is_exact(tmp_path: Path) -> None:
    log = _log()
    path = write_csv(log, tmp_path / "loop.csv")
    back = read_csv(path)
    for name in ("t_s", "leader_pos_m", "leader_vel_mps", "leader_quat", "follower_pos_m",
                 "follower_vel_mps", "follower_quat", "follower_cmd_accel_mps2",
                 "follower_thrust_n", "follower_obs_accel_mps2"):
        np.testing.assert_array_equal(getattr(back, name), getattr(log, name), err_msg=name)
    assert set(back.extra) == {"leader_thrust_n", "ref_pos_m"}
    np.testing.assert_array_equal(back.extra["ref_pos_m"], log.extra["ref_pos_m"])
    assert back.meta["name"] == "loop"
    assert back.meta["source"] == "sim"
    assert back.meta["follower_mass_kg"] == MASS_KG
    assert back.meta["frame"] == "NED"
    label = back.follower_obs_accel_mps2 - back.follower_cmd_accel_mps2
    np.testing.assert_allclose(label, np.tile(DISTURBANCE, (200, 1)), atol=1e-12)
    # through read_logs and a folder
    assert read_logs("csv", [tmp_path])[0].n_samples == 200


def test_optional_columns_are_derived(tmp_path: Path) -> None:
    log = _log(400)
    path = write_csv(log, tmp_path / "full.csv")
    header, *rows = path.read_text().splitlines()[1:]
    names = header.split(",")
    keep = [i for i, n in enumerate(names) if n in REQUIRED_COLUMNS]
    slim = tmp_path / "slim.csv"
    slim.write_text("\n".join([",".join(names[i] for i in keep)]
                              + [",".join(r.split(",")[i] for i in keep) for r in rows]) + "\n")
    back = read_csv(slim, mass_kg=MASS_KG)
    np.testing.assert_allclose(back.follower_thrust_n, log.follower_thrust_n, rtol=1e-9)
    assert back.meta["obs_accel_source"] == "differentiated follower velocity"
    np.testing.assert_allclose(back.follower_obs_accel_mps2[1:-1], log.follower_obs_accel_mps2[
        1:-1], atol=1e-3)
    assert back.meta["label_basis"] == "command"
    assert back.meta["leader_mass_kg"] == MASS_KG


def test_enu_frame_is_converted(tmp_path: Path) -> None:
    log = _log()
    rot_enu = ENU_TO_NED @ quat_to_rotmat(log.follower_quat) @ FLIP_YZ
    enu = FlightLog(
        t_s=log.t_s, leader_pos_m=log.leader_pos_m @ ENU_TO_NED,
        leader_vel_mps=log.leader_vel_mps @ ENU_TO_NED,
        leader_quat=rotmat_to_quat(ENU_TO_NED @ quat_to_rotmat(log.leader_quat) @ FLIP_YZ),
        follower_pos_m=log.follower_pos_m @ ENU_TO_NED,
        follower_vel_mps=log.follower_vel_mps @ ENU_TO_NED, follower_quat=rotmat_to_quat(rot_enu),
        follower_cmd_accel_mps2=log.follower_cmd_accel_mps2 @ ENU_TO_NED,
        follower_thrust_n=log.follower_thrust_n,
        follower_obs_accel_mps2=log.follower_obs_accel_mps2 @ ENU_TO_NED,
        meta={**log.meta, "frame": "ENU"},
    )
    path = write_csv(enu, tmp_path / "enu.csv")
    back = read_csv(path, frame="enu")
    np.testing.assert_allclose(back.follower_pos_m, log.follower_pos_m, atol=1e-12)
    np.testing.assert_allclose(back.follower_quat, log.follower_quat, atol=1e-9)
    np.testing.assert_allclose(back.follower_cmd_accel_mps2, log.follower_cmd_accel_mps2,
                               atol=1e-12)
    assert back.meta["converted_from_frame"] == "ENU"


# --------------------------------------------------------------------------------------------
# Bad input
# --------------------------------------------------------------------------------------------


def _edit(tmp_path: Path, edit) -> Path:  # type: ignore[no-untyped-def]
    path = write_csv(_log(), tmp_path / "flight.csv")
    meta, header, *rows = path.read_text().splitlines()
    names = header.split(",")
    table = [r.split(",") for r in rows]
    names, table = edit(names, table)
    path.write_text("\n".join([meta, ",".join(names)] + [",".join(r) for r in table]) + "\n")
    return path


def _expect(path: Path, *phrases: str) -> None:
    with pytest.raises(IngestError) as info:
        read_csv(path)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"{path}: ")
    for phrase in phrases:
        assert phrase in message, message


def test_missing_columns(tmp_path: Path) -> None:
    path = _edit(tmp_path, lambda n, t: ([c if c != "leader_vy_mps" else "leader_vy" for c in n],
                                         t))
    _expect(path, "missing columns: leader_vy_mps")


def test_nan(tmp_path: Path) -> None:
    def edit(names: list[str], table: list[list[str]]) -> tuple[list[str], list[list[str]]]:
        table[40][names.index("follower_cmd_ay_mps2")] = "nan"
        return names, table

    _expect(_edit(tmp_path, edit), "NaN in column 'follower_cmd_ay_mps2' at line 43")


def test_non_monotonic_time(tmp_path: Path) -> None:
    _expect(_edit(tmp_path, lambda n, t: (n, t[:10] + [t[11], t[10]] + t[12:])),
            "not monotonic", "line 14")


def test_duplicated_time(tmp_path: Path) -> None:
    _expect(_edit(tmp_path, lambda n, t: (n, t[:10] + [t[10]] + t[10:])),
            "duplicated time", "line 14")


def test_time_in_milliseconds(tmp_path: Path) -> None:
    def edit(names: list[str], table: list[list[str]]) -> tuple[list[str], list[list[str]]]:
        for row in table:
            row[0] = repr(float(row[0]) * 1000)
        return names, table

    _expect(_edit(tmp_path, edit), "'t_s' looks like milliseconds, expected seconds")


def test_ragged_rows(tmp_path: Path) -> None:
    _expect(_edit(tmp_path, lambda n, t: (n, t[:-1] + [t[-1][:-5]])), "line 202 has",
            "fields, the header has")


def test_empty_file(tmp_path: Path) -> None:
    path = tmp_path / "empty.csv"
    path.write_text("")
    _expect(path, "empty file")


def test_no_thrust_and_no_mass(tmp_path: Path) -> None:
    def edit(names: list[str], table: list[list[str]]) -> tuple[list[str], list[list[str]]]:
        i = names.index("follower_thrust_n")
        return names[:i] + names[i + 1:], [r[:i] + r[i + 1:] for r in table]

    path = _edit(tmp_path, edit)
    path.write_text("\n".join(path.read_text().splitlines()[1:]) + "\n")  # drop the meta line
    _expect(path, "no follower_thrust_n column and no follower mass")


def test_bad_meta_line(tmp_path: Path) -> None:
    path = write_csv(_log(), tmp_path / "flight.csv")
    lines = path.read_text().splitlines()
    path.write_text("\n".join(["# meta: {not json"] + lines[1:]) + "\n")
    _expect(path, "'# meta:' line is not valid JSON")


def test_quoted_and_unquoted_tables_read_the_same_numbers(tmp_path: Path) -> None:
    """NumPy's reader takes plain files, Python's ``csv`` quoted ones and the spellings NumPy
    refuses (``1_000``): the same values either way, bit for bit."""
    rows = [[0.1, -2.5e-3, 1e300], [float("nan"), 7.0, -0.0], [3.0, 5e-324, 1e400]]
    plain, quoted, odd = tmp_path / "plain.csv", tmp_path / "quoted.csv", tmp_path / "odd.csv"
    plain.write_text("# a comment\na,b,c\n" + "\n".join(
        ", ".join(repr(v) for v in r) for r in rows) + "\n")
    quoted.write_text('"a","b","c"\n' + "\n".join(
        ",".join(f'"{v!r}"' for v in r) for r in rows) + "\n")
    odd.write_text("a,b,c\n1_000, 2, 3\n")
    a = read_csv_table(plain, header_in_comment=False)
    b = read_csv_table(quoted, header_in_comment=False)
    assert a.columns == b.columns == ["a", "b", "c"] and a.comments == ["a comment"]
    assert a.data.tobytes() == b.data.tobytes() == np.array(rows).tobytes()
    assert list(a.lines) == [3, 4, 5] and list(b.lines) == [2, 3, 4]
    np.testing.assert_array_equal(read_csv_table(odd, header_in_comment=False).data,
                                  [[1000.0, 2.0, 3.0]])


def test_what_pythons_float_refuses_stays_refused(tmp_path: Path) -> None:
    """NumPy's reader trims a unit separator (``\\x1f``) around a number and has no field size
    limit; the tables still read as Python reads them: refused, naming the line."""
    path = tmp_path / "sep.csv"
    path.write_text("a,b\n1,\x1f2\n")
    with pytest.raises(IngestError, match=r"line 2: column 'b' holds"):
        read_csv_table(path, header_in_comment=False)
    path.write_text("a,b\n1," + "1" * 200_000 + "\n")
    with pytest.raises(IngestError, match=r"line 2: not CSV \(field larger than field limit"):
        read_csv_table(path, header_in_comment=False)


def test_a_field_that_is_not_a_number_is_named(tmp_path: Path) -> None:
    path = tmp_path / "bad.csv"
    path.write_text("a,b\n1,2\n3,x7\n")
    with pytest.raises(IngestError, match=r"line 3: column 'b' holds 'x7', not a number"):
        read_csv_table(path, header_in_comment=False)


def test_a_table_read_again_is_a_fresh_copy_and_a_changed_file_is_read_anew(tmp_path: Path
                                                                             ) -> None:
    """The parsed-table cache is keyed by the text: the same bytes give equal arrays that the
    caller owns; new bytes of the same size under the same name (and time stamp) are parsed."""
    import os

    path = tmp_path / "t.csv"
    path.write_text("a,b\n1,2\n3,4\n")
    first = read_csv_table(path, header_in_comment=False)
    first.data[0, 0] = 99.0  # the caller's copy
    again = read_csv_table(path, header_in_comment=False)
    np.testing.assert_array_equal(again.data, [[1.0, 2.0], [3.0, 4.0]])
    assert again.data is not first.data and again.path == path
    stamp = path.stat().st_mtime_ns
    path.write_text("a,b\n5,6\n7,8\n")
    os.utime(path, ns=(stamp, stamp))
    np.testing.assert_array_equal(read_csv_table(path, header_in_comment=False).data,
                                  [[5.0, 6.0], [7.0, 8.0]])
