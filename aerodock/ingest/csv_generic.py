"""Generic CSV: one file per flight, for users who export their own logs.

Schema (comma-separated, one header line; names carry their units; NED world, FRD body)::

    # meta: {"name": "my_flight_01", "leader_mass_kg": 0.7, "follower_mass_kg": 0.7}
    t_s,leader_x_m,leader_y_m,leader_z_m,leader_vx_mps,...,follower_cmd_az_mps2,...

=================================================  ======  ======================================
column                                             unit    meaning
=================================================  ======  ======================================
``t_s``                                            s       time, strictly increasing
``leader_x_m, leader_y_m, leader_z_m``             m       leader position (NED: z down)
``leader_vx_mps, leader_vy_mps, leader_vz_mps``    m/s     leader velocity
``leader_qw, leader_qx, leader_qy, leader_qz``     -       leader attitude, body to world
``follower_x_m`` ... ``follower_qz``               as above  the follower, same 10 columns
``follower_cmd_ax_mps2`` (``ay``, ``az``)          m/s²    acceleration the follower's actuation
                                                           explains: commanded ``u_1:3``, or
                                                           ``g e3 - R e3 T/m`` (label basis thrust)
``follower_thrust_n`` (optional)                   N       collective thrust; if absent,
                                                           ``m |g e3 - cmd|`` (needs the mass)
``follower_obs_ax_mps2`` (``ay``, ``az``)          m/s²    observed kinematic acceleration,
(optional)                                                 gravity removed; if absent, the time
                                                           derivative of the follower velocity
``extra_<name>`` or ``extra_<name>[i]``            any     optional extra arrays, kept as
(optional)                                                 ``FlightLog.extra[name]``
=================================================  ======  ======================================

Comment lines start with ``#``. One of them may be ``# meta: {...}`` (a JSON object) with the
flight's metadata: ``name``, ``leader_mass_kg``, ``follower_mass_kg``, ``label_basis``
(``"command"``, the default, or ``"thrust"``) and ``frame`` (``"NED"``, the default, or ``"ENU"``
for an ENU world with FLU body, converted on reading). :func:`write_csv` writes this format, so a
FlightLog survives a round trip.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from aerodock.fileio import atomic_open, json_default
from aerodock.flightlog import LABEL_BASES, FlightLog
from aerodock.geometry import E3, GRAVITY_MPS2, quat_to_rotmat, rotmat_to_quat
from aerodock.ingest.common import (
    ENU_TO_NED,
    FLIP_YZ,
    check_finite,
    check_kinematics,
    check_mass,
    check_time,
    check_time_unit,
    check_upright,
    convert_rotations,
    convert_vectors,
    differentiate,
)
from aerodock.ingest.csv_table import CsvTable, read_csv_table
from aerodock.ingest.errors import IngestError

SOURCE = "csv"
_VEHICLE_COLUMNS = (
    ("pos", ("x_m", "y_m", "z_m")),
    ("vel", ("vx_mps", "vy_mps", "vz_mps")),
    ("quat", ("qw", "qx", "qy", "qz")),
)
CMD_COLUMNS = ("follower_cmd_ax_mps2", "follower_cmd_ay_mps2", "follower_cmd_az_mps2")
OBS_COLUMNS = ("follower_obs_ax_mps2", "follower_obs_ay_mps2", "follower_obs_az_mps2")
THRUST_COLUMN = "follower_thrust_n"
TIME_COLUMN = "t_s"


def vehicle_columns(role: str) -> list[str]:
    """The 10 state columns of ``role`` (``"leader"`` or ``"follower"``)."""
    return [f"{role}_{suffix}" for _, suffixes in _VEHICLE_COLUMNS for suffix in suffixes]


REQUIRED_COLUMNS = (TIME_COLUMN, *vehicle_columns("leader"), *vehicle_columns("follower"),
                    *CMD_COLUMNS)
ALL_COLUMNS = (*REQUIRED_COLUMNS, THRUST_COLUMN, *OBS_COLUMNS)


def _parse_meta(comments: list[str], where: str) -> dict[str, Any]:
    meta: dict[str, Any] = {}
    for comment in comments:
        key, sep, value = comment.partition(":")
        if sep and key.strip().lower() == "meta":
            try:
                parsed = json.loads(value)
            except json.JSONDecodeError as err:
                raise IngestError(where, f"'# meta:' line is not valid JSON ({err.msg})") from None
            except RecursionError:  # the parser recurses once per bracket
                raise IngestError(where, "'# meta:' line is nested too deeply") from None
            if not isinstance(parsed, dict):
                raise IngestError(where, "'# meta:' line must hold a JSON object")
            meta.update(parsed)
    name = meta.get("name")
    if name is not None and (not isinstance(name, str) or not name.strip()):
        raise IngestError(where, f"'# meta:' name must be a non-empty string, got {name!r}")
    basis = meta.get("label_basis")
    if basis is not None and basis not in LABEL_BASES:
        raise IngestError(where, f"'# meta:' label_basis must be one of "
                                 f"{'|'.join(LABEL_BASES)}, got {basis!r}")
    return meta


def read_csv(path: Path, *, frame: str | None = None, mass_kg: float | None = None) -> FlightLog:
    """Read one flight in the generic CSV schema (see the module docstring).

    Args:
        path: The CSV file.
        frame: ``"ned"`` or ``"enu"``, overriding the file's ``meta.frame`` (default NED).
        mass_kg: Mass of both vehicles, overriding the file's metadata.

    Raises:
        IngestError: empty file, missing columns, NaNs, bad time (duplicated, non-monotonic,
            milliseconds instead of seconds), ragged rows, bad quaternions or masses.
    """
    path = Path(path)
    where = str(path)
    table = read_csv_table(path, header_in_comment=False)
    meta = _parse_meta(table.comments, where)
    columns = table.columns
    _check_columns(columns, where)
    known = [c for c in ALL_COLUMNS if c in columns]
    check_time(table.column(TIME_COLUMN), where, column=TIME_COLUMN, row_name="line",
               rows=table.lines)
    check_time_unit(table.column(TIME_COLUMN), "s", where, column=TIME_COLUMN)
    check_finite({c: table.column(c) for c in known}, where, row_name="line", rows=table.lines)

    frame_name = str(frame or meta.get("frame", "NED")).upper()
    if frame_name not in ("NED", "ENU"):
        raise IngestError(where, f"unknown frame {frame_name!r}; use NED or ENU")
    world, body = (ENU_TO_NED, FLIP_YZ) if frame_name == "ENU" else (np.eye(3), np.eye(3))

    states = {role: _vehicle_state(table, role, world, body, frame_name, where)
              for role in ("leader", "follower")}
    t_s = table.column(TIME_COLUMN)
    cmd = convert_vectors(world, _block(table, CMD_COLUMNS))

    masses = {}
    for role in ("leader", "follower"):
        value = mass_kg if mass_kg is not None else meta.get(f"{role}_mass_kg")
        masses[role] = None if value is None else check_mass(value, where, f"{role} mass")
    thrust = _follower_thrust(table, cmd, masses["follower"], where)
    obs, obs_source = _observed_accel(table, world, t_s, states["follower"][1], where)

    extra = _read_extra(table.columns, table.data, where)
    check_finite(extra, where, row_name="line", rows=table.lines)
    meta = dict(meta)
    meta.setdefault("name", path.stem)
    meta.update({
        "source": meta.get("source", SOURCE),
        "file": str(path),
        "frame": "NED",
        "label_basis": meta.get("label_basis", "command"),
        "leader_mass_kg": masses["leader"],
        "follower_mass_kg": masses["follower"],
        "obs_accel_source": obs_source,
    })
    if frame_name != "NED":
        meta["converted_from_frame"] = frame_name
    return FlightLog(
        t_s=t_s,
        leader_pos_m=states["leader"][0],
        leader_vel_mps=states["leader"][1],
        leader_quat=states["leader"][2],
        follower_pos_m=states["follower"][0],
        follower_vel_mps=states["follower"][1],
        follower_quat=states["follower"][2],
        follower_cmd_accel_mps2=cmd,
        follower_thrust_n=thrust,
        follower_obs_accel_mps2=obs,
        meta=meta,
        extra=extra,
    )


def _check_columns(columns: list[str], where: str) -> None:
    """Refuse a header without every required column or with a name twice.

    Raises:
        IngestError: missing columns (the first six named) or duplicated column names.
    """
    missing = [c for c in REQUIRED_COLUMNS if c not in columns]
    if missing:
        shown = ", ".join(missing[:6]) + (f" (+{len(missing) - 6} more)" if len(missing) > 6
                                          else "")
        raise IngestError(where, f"missing columns: {shown}")
    dupes = sorted({c for c in columns if columns.count(c) > 1})
    if dupes:
        raise IngestError(where, f"duplicated column names: {', '.join(dupes)}")


def _block(table: CsvTable, names: list[str] | tuple[str, ...]) -> np.ndarray:
    """The columns ``names`` of ``table`` side by side, ``(n, len(names))``."""
    return np.stack([table.column(c) for c in names], axis=1)


def _vehicle_state(table: CsvTable, role: str, world: np.ndarray, body: np.ndarray,
                   frame_name: str, where: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One vehicle's position (m), velocity (m/s) and attitude quaternion, in NED.

    Args:
        table: the CSV table.
        role: ``"leader"`` or ``"follower"``.
        world: the file's world frame to NED rotation.
        body: the file's body frame to FRD rotation.
        frame_name: ``"NED"`` or ``"ENU"`` (the quaternions are recomputed for ENU).
        where: the file, for errors.

    Returns:
        ``(pos_m (n, 3), vel_mps (n, 3), quat (n, 4) w, x, y, z)``.

    Raises:
        IngestError: a quaternion far from unit norm, an attitude not upright, or positions
            and velocities that disagree.
    """
    cols = vehicle_columns(role)
    quat = _block(table, cols[6:10])
    norm = np.linalg.norm(quat, axis=1)
    if np.any(np.abs(norm - 1.0) > 0.1):
        i = int(np.argmax(np.abs(norm - 1.0) > 0.1))
        raise IngestError(where, f"{role}_qw..qz has norm {norm[i]:.3g} at line "
                                 f"{table.lines[i]}, not a unit quaternion")
    rot = convert_rotations(world, quat_to_rotmat(quat), body)
    check_upright(rot, where, role, f"{role}_qw..qz in x, y, z, w order (the schema is w, "
                                    "x, y, z), or an ENU file read as NED (add frame: ENU)?")
    if frame_name != "NED":
        quat = rotmat_to_quat(rot)
    pos = convert_vectors(world, _block(table, cols[0:3]))
    vel = convert_vectors(world, _block(table, cols[3:6]))
    check_kinematics(table.column(TIME_COLUMN), pos, vel, where, role)
    return pos, vel, quat


def _follower_thrust(table: CsvTable, cmd: np.ndarray, follower_mass_kg: float | None,
                     where: str) -> np.ndarray:
    """The follower's collective thrust, N: its column, else ``m |g e3 - cmd|``.

    Raises:
        IngestError: no thrust column and no follower mass to derive it.
    """
    if THRUST_COLUMN in table.columns:
        return table.column(THRUST_COLUMN)
    if follower_mass_kg is not None:
        return follower_mass_kg * np.linalg.norm(GRAVITY_MPS2 * E3 - cmd, axis=1)
    raise IngestError(where, f"no {THRUST_COLUMN} column and no follower mass to derive it "
                             f"(add it, or follower_mass_kg in '# meta:', or --mass-kg)")


def _observed_accel(table: CsvTable, world: np.ndarray, t_s: np.ndarray,
                    follower_vel_mps: np.ndarray, where: str) -> tuple[np.ndarray, str]:
    """The follower's observed acceleration (m/s², NED) and where it came from: its three
    columns, else the time derivative of its velocity.

    Raises:
        IngestError: some but not all of the three columns.
    """
    columns = table.columns
    present_obs = [c for c in OBS_COLUMNS if c in columns]
    if len(present_obs) == 3:
        return convert_vectors(world, _block(table, OBS_COLUMNS)), "column"
    if present_obs:
        missing_obs = ", ".join(c for c in OBS_COLUMNS if c not in columns)
        raise IngestError(where, f"missing columns: {missing_obs}")
    return differentiate(t_s, follower_vel_mps), "differentiated follower velocity"


def _read_extra(columns: list[str], data: np.ndarray, where: str) -> dict[str, np.ndarray]:
    groups: dict[str, list[tuple[int, int]]] = {}
    for i, name in enumerate(columns):
        if not name.startswith("extra_"):
            continue
        key = name[len("extra_"):]
        if key.endswith("]") and "[" in key:
            base, _, idx = key[:-1].partition("[")
            try:
                groups.setdefault(base, []).append((int(idx), i))
            except ValueError:
                raise IngestError(where, f"bad extra column name {name!r}") from None
        else:
            groups.setdefault(key, []).append((-1, i))
    extra = {}
    for key, members in groups.items():
        if members[0][0] < 0:
            extra[key] = data[:, members[0][1]]
        else:
            extra[key] = data[:, [i for _, i in sorted(members)]]
    return extra


def write_csv(log: FlightLog, path: Path) -> Path:
    """Write ``log`` in the generic CSV schema (atomically), including 1-D and 2-D extras.

    Returns:
        The path written.
    """
    path = Path(path)
    names: list[str] = list(ALL_COLUMNS)
    blocks = [
        log.t_s[:, None], log.leader_pos_m, log.leader_vel_mps, log.leader_quat,
        log.follower_pos_m, log.follower_vel_mps, log.follower_quat,
        log.follower_cmd_accel_mps2, log.follower_thrust_n[:, None], log.follower_obs_accel_mps2,
    ]
    for key, arr in log.extra.items():
        arr = np.asarray(arr, dtype=float)
        if arr.ndim == 1:
            names.append(f"extra_{key}")
            blocks.append(arr[:, None])
        elif arr.ndim == 2:
            names.extend(f"extra_{key}[{k}]" for k in range(arr.shape[1]))
            blocks.append(arr)
        else:
            raise IngestError(path, f"extra {key!r} has {arr.ndim} dimensions; CSV holds 1 or 2")
    data = np.concatenate(blocks, axis=1)
    meta = {k: v for k, v in log.meta.items() if k != "frame"}
    meta_line = json.dumps(meta, default=json_default)
    with atomic_open(path, "w") as fh:
        fh.write(f"# meta: {meta_line}\n{','.join(names)}\n")
        np.savetxt(fh, data, delimiter=",", fmt="%.17g")
    return path

