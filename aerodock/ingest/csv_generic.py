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
    read_csv_table,
)
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
    missing = [c for c in REQUIRED_COLUMNS if c not in columns]
    if missing:
        shown = ", ".join(missing[:6]) + (f" (+{len(missing) - 6} more)" if len(missing) > 6
                                          else "")
        raise IngestError(where, f"missing columns: {shown}")
    dupes = sorted({c for c in columns if columns.count(c) > 1})
    if dupes:
        raise IngestError(where, f"duplicated column names: {', '.join(dupes)}")
    known = [c for c in ALL_COLUMNS if c in columns]
    check_time(table.column(TIME_COLUMN), where, column=TIME_COLUMN, row_name="line",
               rows=table.lines)
    check_time_unit(table.column(TIME_COLUMN), "s", where, column=TIME_COLUMN)
    check_finite({c: table.column(c) for c in known}, where, row_name="line", rows=table.lines)

    def block(names: list[str] | tuple[str, ...]) -> np.ndarray:
        return np.stack([table.column(c) for c in names], axis=1)

    frame_name = str(frame or meta.get("frame", "NED")).upper()
    if frame_name not in ("NED", "ENU"):
        raise IngestError(where, f"unknown frame {frame_name!r}; use NED or ENU")
    world, body = (ENU_TO_NED, FLIP_YZ) if frame_name == "ENU" else (np.eye(3), np.eye(3))

    states = {}
    for role in ("leader", "follower"):
        cols = vehicle_columns(role)
        quat = block(cols[6:10])
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
        states[role] = (convert_vectors(world, block(cols[0:3])),
                        convert_vectors(world, block(cols[3:6])), quat)
        check_kinematics(table.column(TIME_COLUMN), states[role][0], states[role][1], where,
                         role)
    t_s = table.column(TIME_COLUMN)
    cmd = convert_vectors(world, block(CMD_COLUMNS))

    masses = {}
    for role in ("leader", "follower"):
        value = mass_kg if mass_kg is not None else meta.get(f"{role}_mass_kg")
        masses[role] = None if value is None else check_mass(value, where, f"{role} mass")
    if THRUST_COLUMN in columns:
        thrust = table.column(THRUST_COLUMN)
    elif masses["follower"] is not None:
        thrust = masses["follower"] * np.linalg.norm(GRAVITY_MPS2 * E3 - cmd, axis=1)
    else:
        raise IngestError(where, f"no {THRUST_COLUMN} column and no follower mass to derive it "
                                 f"(add it, or follower_mass_kg in '# meta:', or --mass-kg)")
    present_obs = [c for c in OBS_COLUMNS if c in columns]
    if len(present_obs) == 3:
        obs = convert_vectors(world, block(OBS_COLUMNS))
        obs_source = "column"
    elif present_obs:
        missing_obs = ", ".join(c for c in OBS_COLUMNS if c not in columns)
        raise IngestError(where, f"missing columns: {missing_obs}")
    else:
        obs = differentiate(t_s, states["follower"][1])
        obs_source = "differentiated follower velocity"

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

