"""Reader for the public Neural-Swarm dataset (Crazyflie 2.1 CSV logs, one file per vehicle).

Files are named ``cfXX_NN.csv`` (vehicle ``cfXX``, flight ``NN``); the two files of one flight
are paired by ``NN`` within a folder, aligned in time, converted to NED, and turned into **two**
FlightLogs: each vehicle once as the follower with the other as the leader (in the swap flights
both vehicles pass under each other).

Conversion (checked on hover samples of the real data, see ``tests/ingest``):

- Time: the header says ms but the values are µs; the unit is detected from the sample spacing
  (about 100 Hz), or set with ``time_unit``.
- World: the dataset's z-up frame ``(x, y, z)`` becomes NED by ``C = diag(1, -1, -1)`` (a
  rotation of pi about x, right-handed): positions, velocities and accelerations are ``C v``.
- Attitude: the body frame flips from FLU to FRD the same way, so ``R_ned = C R_zup C``.
- Observed acceleration: ``ax, ay, az`` include gravity (``+9.8`` in z at hover), so the
  kinematic NED acceleration is ``C a_meas + g e3`` (about 0 at hover).
- Label basis ``"thrust"``: ``follower_cmd_accel_mps2 = g e3 - R_ned e3 (u1+u2+u3+u4) / m``, so
  ``a_obs - cmd = C (a_meas - R_zup e3 sum(u) / m)``, the dataset's residual in NED. Its constant
  bias (about 0.3-0.5 m/s², present with or without a vehicle above) is *not* removed here.
- Masses: both vehicles from :data:`VEHICLE_MASSES_KG` by ``vehicle`` (``"small"``, ``"large"``
  or per vehicle ``"cf50=small,cf51=large"``), or ``mass_kg`` for both. With a vehicle type
  (not ``mass_kg``) the rotor radius and count of :data:`VEHICLE_ROTORS` go into the meta too
  (``{leader,follower}_{rotor_radius_m,n_rotors}``), which the leader-aware models need, and the
  diagonal of :data:`VEHICLE_DIAGONALS_M` (``{role}_diagonal_m``, for ``aerodock field fit``); the
  leader's logged thrust (``u1+u2+u3+u4``) is ``extra["leader_thrust_n"]``.
"""

from __future__ import annotations

import re
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from aerodock.flightlog import FlightLog
from aerodock.geometry import E3, GRAVITY_MPS2, quat_to_rotmat, rotmat_to_quat, thrust_accel
from aerodock.ingest.common import (
    FLIP_YZ,
    TIME_UNITS,
    bracket_gap_s,
    check_finite,
    check_kinematics,
    check_mass,
    check_pair_alignment,
    check_specific_force,
    check_time,
    check_time_unit,
    check_upright,
    convert_rotations,
    convert_vectors,
    detect_time_unit,
    estimate_lag_s,
    resample_linear,
    resample_quat,
)
from aerodock.ingest.csv_table import read_csv_table
from aerodock.ingest.errors import IngestError, ingest_warning

SOURCE = "neural-swarm"
# Crazyflie 2.1 masses of the Neural-Swarm dataset, kg.
VEHICLE_MASSES_KG: dict[str, float] = {"small": 0.032, "large": 0.067}
# Rotor radius (m) and count of each vehicle type: the stock Crazyflie 2.x propeller is about
# 45 mm across (0.0225 m). The large one is a Crazyflie 2.1 "on parrot frame" (the dataset's
# readme.txt): Parrot's Rolling Spider airframe, whose published parameters give its rotor
# radius, 33 mm (Parrot-Developers/RollingSpiderEdu, MIT_MatlabToolbox/trunk/matlab/libs/
# RoboticsToolbox/mdl_quadrotor.m, "quad.r = 33/1000"), its mass, 68 g (the logs' 67 g), and its
# motors at (+-0.043, +-0.043) m (ExperimentAnalyzer/Hardware/ParameterIdentification.m: 0.061 m
# centre to motor, the Neural-Swarm crazyflieTypes.yaml's "arm_length: 0.06"). Both are
# quadrotors.
VEHICLE_ROTORS: dict[str, tuple[float, int]] = {"small": (0.0225, 4), "large": (0.033, 4)}
# Motor-to-motor diagonal (m) of each type: the small one's 92 mm is Bitcraze's specification of
# the Crazyflie 2.x; the large one's 0.120 m is read from the logs' own torque mixer (``torquex =
# (l / sqrt 2) (-u1 - u2 + u3 + u4)``: l / sqrt 2 = 0.04243 m for cf101, 0.03253 m for the small
# ones, i.e. 92 mm, as specified).
VEHICLE_DIAGONALS_M: dict[str, float] = {"small": 0.092, "large": 0.120}
EXPECTED_DT_S = 0.01  # about 100 Hz on board
FILE_PATTERN = re.compile(r"^(?P<vehicle>cf\d+)_(?P<flight>\d+)\.csv$", re.IGNORECASE)

# (name, unit or None) of each column the reader needs; u1..u4 in N, not the PWM columns.
_POSITION = ("x", "y", "z")
_VELOCITY = ("vx", "vy", "vz")
_ACCEL = ("ax", "ay", "az")
_QUAT_XYZW = ("qx", "qy", "qz", "qw")
_MOTOR_N = ("u1", "u2", "u3", "u4")
_RATES = ("wx", "wy", "wz")
_TORQUES = ("torquex", "torquey", "torquez")
_HEADER_TOKEN = re.compile(r"^\s*(?P<name>[^\[\]]+?)\s*(?:\[(?P<unit>[^\]]*)\])?\s*$")


@dataclass
class VehicleTrack:
    """One vehicle's log of one flight, converted to NED and SI (time on the onboard clock)."""

    path: Path
    vehicle_id: str
    flight_id: str
    time_unit: str
    t_s: np.ndarray
    pos_m: np.ndarray
    vel_mps: np.ndarray
    quat: np.ndarray
    rot: np.ndarray
    accel_mps2: np.ndarray
    thrust_n: np.ndarray
    extra: dict[str, np.ndarray] = field(default_factory=dict)


def parse_file_name(path: Path) -> tuple[str, str]:
    """``(vehicle_id, flight_id)`` from a ``cfXX_NN.csv`` file name.

    Raises:
        IngestError: the name does not follow the dataset's pattern.
    """
    match = FILE_PATTERN.match(path.name)
    if not match:
        raise IngestError(path, "not a Neural-Swarm file name: expected cfXX_NN.csv "
                                "(vehicle XX, flight NN)")
    return match["vehicle"].lower(), match["flight"]


def _column_index(columns: list[str]) -> dict[tuple[str, str], int]:
    index: dict[tuple[str, str], int] = {}
    for i, token in enumerate(columns):
        match = _HEADER_TOKEN.match(token)
        if match:
            index.setdefault((match["name"].lower(), (match["unit"] or "").lower()), i)
    return index


def _find(index: dict[tuple[str, str], int], name: str, unit: str | None = None) -> int | None:
    for (col_name, col_unit), i in index.items():
        if col_name == name and (unit is None or col_unit == unit):
            return i
    return None


def read_vehicle_file(path: Path, *, time_unit: str = "auto") -> VehicleTrack:
    """Read one ``cfXX_NN.csv`` file and convert it to NED, SI units.

    Args:
        path: The file.
        time_unit: ``"auto"`` (detect from the spacing, about 100 Hz) or one of s, ms, us, ns.

    Raises:
        IngestError: bad name, empty file, missing columns, NaNs, bad time, non-unit attitude.
    """
    path = Path(path)
    vehicle_id, flight_id = parse_file_name(path)
    table = read_csv_table(path, header_in_comment=True)
    index = _column_index(table.columns)
    wanted = {"time": _find(index, "time")}
    wanted.update({n: _find(index, n) for n in _POSITION + _VELOCITY + _ACCEL + _QUAT_XYZW})
    wanted.update({n: _find(index, n, "n") for n in _MOTOR_N})
    missing = [(f"{n}[N]" if n in _MOTOR_N else n) for n, i in wanted.items() if i is None]
    if missing:
        raise IngestError(path, f"missing columns: {', '.join(missing)}")
    col = {n: table.data[:, i] for n, i in wanted.items() if i is not None}
    where = str(path)

    t_raw = col["time"]
    time_column = table.columns[wanted["time"] or 0]
    check_time(t_raw, where, column=time_column, row_name="line", rows=table.lines)
    if time_unit == "auto":
        unit = detect_time_unit(t_raw, where, column=time_column, expected_dt_s=EXPECTED_DT_S)
    elif time_unit in TIME_UNITS:
        unit = time_unit
        check_time_unit(t_raw, unit, where, column=time_column)
    else:
        raise IngestError(path, f"unknown time unit {time_unit!r}; use auto, s, ms, us or ns")

    check_finite({table.columns[i]: table.data[:, i] for n, i in wanted.items()
                  if i is not None and n != "time"}, where, row_name="line", rows=table.lines)
    stack = {
        "pos": np.stack([col[n] for n in _POSITION], axis=1),
        "vel": np.stack([col[n] for n in _VELOCITY], axis=1),
        "accel": np.stack([col[n] for n in _ACCEL], axis=1),
        "quat_xyzw": np.stack([col[n] for n in _QUAT_XYZW], axis=1),
        "motor_n": np.stack([col[n] for n in _MOTOR_N], axis=1),
    }
    quat_xyzw = stack["quat_xyzw"]
    norm = np.linalg.norm(quat_xyzw, axis=1)
    if np.any(np.abs(norm - 1.0) > 0.1):
        i = int(np.argmax(np.abs(norm - 1.0) > 0.1))
        raise IngestError(path, f"attitude quaternion qx..qw has norm {norm[i]:.3g} at line "
                                f"{table.lines[i]}, not a unit quaternion")

    rot_zup = quat_to_rotmat(quat_xyzw[:, [3, 0, 1, 2]])
    rot_ned = convert_rotations(FLIP_YZ, rot_zup, FLIP_YZ)
    t_s = t_raw * TIME_UNITS[unit]
    check_specific_force(stack["accel"], where, "acceleration ax, ay, az",
                         down_axis=np.array([0.0, 0.0, -1.0]),
                         frame="is z already down? (Neural-Swarm files are z-up)")
    check_kinematics(t_s, stack["pos"], stack["vel"], where, vehicle_id)
    check_upright(rot_ned, where, vehicle_id, "quaternion in w, x, y, z order? (Neural-Swarm "
                                              "files hold qx, qy, qz, qw)")
    # az includes gravity (+g at hover, z up): kinematic NED acceleration is C a_meas + g e3.
    accel_ned = convert_vectors(FLIP_YZ, stack["accel"]) + GRAVITY_MPS2 * E3
    extra: dict[str, np.ndarray] = {}
    rate_idx = [_find(index, n) for n in _RATES]
    if all(i is not None for i in rate_idx):
        rates = table.data[:, rate_idx]
        if np.all(np.isfinite(rates)):
            extra["body_rates_radps"] = convert_vectors(FLIP_YZ, rates)  # FLU -> FRD
    torque_idx = [_find(index, n) for n in _TORQUES]
    if all(i is not None for i in torque_idx):
        torques = table.data[:, torque_idx]
        if np.all(np.isfinite(torques)):
            # The torque the firmware commanded: the logs' own mixer of the per-motor thrusts it
            # asked for (u1..u4), FLU -> FRD.
            extra["body_torque_nm"] = convert_vectors(FLIP_YZ, torques)
    pwm_idx = [_find(index, n, "pwm") for n in _MOTOR_N]
    if all(i is not None for i in pwm_idx):
        pwm = table.data[:, pwm_idx]
        if np.all(np.isfinite(pwm)):
            extra["motor_pwm"] = pwm  # normalised 0..1, the motors in the logs' order
    # The per-motor thrusts the firmware asked for (u1..u4, N, the logs' order: what the torque
    # columns mix) and the battery's voltage: with the PWM, each motor's own command map
    extra["motor_thrust_n"] = stack["motor_n"]
    vbat = _find(index, "vbat")
    if vbat is not None and np.all(np.isfinite(table.data[:, vbat])):
        extra["battery_v"] = table.data[:, vbat]
    return VehicleTrack(
        path=path,
        vehicle_id=vehicle_id,
        flight_id=flight_id,
        time_unit=unit,
        t_s=t_s,
        pos_m=convert_vectors(FLIP_YZ, stack["pos"]),
        vel_mps=convert_vectors(FLIP_YZ, stack["vel"]),
        quat=rotmat_to_quat(rot_ned),
        rot=rot_ned,
        accel_mps2=accel_ned,
        thrust_n=stack["motor_n"].sum(axis=1),
        extra=extra,
    )


def vehicle_masses(vehicle: str, mass_kg: float | None, ids: list[str],
                   where: str) -> dict[str, float]:
    """Mass of each vehicle id from the vehicle table or an explicit mass.

    Args:
        vehicle: ``"small"``/``"large"`` for all vehicles, or ``"cf50=small,cf51=large"``.
        mass_kg: If given, the mass of every vehicle (overrides ``vehicle``).
        ids: The vehicle ids that need a mass.
        where: For error messages.

    Raises:
        IngestError: unknown vehicle type, a vehicle without a type, or a bad mass.
    """
    if mass_kg is not None:
        mass = check_mass(mass_kg, where, "--mass-kg")
        return dict.fromkeys(ids, mass)
    kinds: dict[str, str] = {}
    spec = (vehicle or "small").strip().lower()
    if "=" in spec:
        for item in spec.split(","):
            key, _, kind = item.partition("=")
            kinds[key.strip()] = kind.strip()
    else:
        kinds = dict.fromkeys(ids, spec)
    masses = {}
    for vid in ids:
        kind = kinds.get(vid)
        if kind is None:
            raise IngestError(where, f"--vehicle {vehicle!r} gives no type for {vid}")
        if kind not in VEHICLE_MASSES_KG:
            raise IngestError(where, f"unknown vehicle type {kind!r}; use "
                                     f"{' or '.join(VEHICLE_MASSES_KG)} or --mass-kg")
        masses[vid] = VEHICLE_MASSES_KG[kind]
    return masses


def vehicle_rotors(vehicle: str, ids: list[str]) -> dict[str, tuple[float, int, float]]:
    """``(rotor_radius_m, n_rotors, diagonal_m)`` of each vehicle id from :data:`VEHICLE_ROTORS`
    and :data:`VEHICLE_DIAGONALS_M` by its type in ``vehicle`` (as :func:`vehicle_masses`, which
    has already checked it)."""
    spec = (vehicle or "small").strip().lower()
    if "=" in spec:
        kinds = {key.strip(): kind.strip() for key, _, kind in
                 (item.partition("=") for item in spec.split(","))}
    else:
        kinds = dict.fromkeys(ids, spec)
    return {vid: (*VEHICLE_ROTORS[kinds[vid]], VEHICLE_DIAGONALS_M[kinds[vid]]) for vid in ids}


def pair_files(paths: list[Path]) -> list[tuple[Path, Path]]:
    """Group ``cfXX_NN.csv`` files into the two files of each flight (same folder, same NN).

    A lone file is paired with the only other ``cf*_NN.csv`` of its folder, if there is one.

    Raises:
        IngestError: a bad file name, a flight with one file and no partner, or more than two.
    """
    groups: dict[tuple[Path, str], list[Path]] = {}
    for path in paths:
        _, flight = parse_file_name(path)
        groups.setdefault((path.parent, flight), [])
        if path not in groups[(path.parent, flight)]:
            groups[(path.parent, flight)].append(path)
    pairs = []
    for (folder, flight), files in sorted(groups.items(), key=lambda kv: (str(kv[0][0]), kv[0][1])):
        if len(files) == 1:
            partners = [p for p in sorted(folder.glob(f"*_{flight}.csv"))
                        if p != files[0] and FILE_PATTERN.match(p.name)]
            if len(partners) != 1:
                raise IngestError(files[0], f"no partner file for flight {flight} (expected one "
                                            f"other cfXX_{flight}.csv in {folder})")
            files = [files[0], partners[0]]
        if len(files) > 2:
            names = ", ".join(p.name for p in files)
            raise IngestError(folder, f"flight {flight} has {len(files)} vehicle files ({names}); "
                                      f"expected 2")
        ids = [parse_file_name(p)[0] for p in files]
        if ids[0] == ids[1]:
            raise IngestError(files[1], f"pairs with {files[0].name}: same vehicle {ids[0]}")
        pairs.append((files[0], files[1]) if ids[0] < ids[1] else (files[1], files[0]))
    return pairs


def build_flightlog(follower: VehicleTrack, leader: VehicleTrack, *, follower_mass_kg: float,
                    leader_mass_kg: float, max_start_offset_s: float = 0.5,
                    min_overlap_fraction: float = 0.8, max_gap_s: float = 0.05,
                    max_lag_s: float = 0.1,
                    rotors: dict[str, tuple[float, ...]] | None = None) -> FlightLog:
    """One FlightLog of ``follower`` with ``leader``, on the follower's time stamps.

    ``rotors`` (``{"leader": (rotor_radius_m, n_rotors[, diagonal_m]), "follower": ...}``), when
    given, go into the meta as ``{role}_rotor_radius_m``, ``{role}_n_rotors`` (and
    ``{role}_diagonal_m``).

    The leader is interpolated onto the follower's samples over the common time window; samples
    where the leader's log has a gap longer than ``max_gap_s`` are dropped (counted in the meta).

    Raises:
        IngestError: clocks that disagree, files of different lengths, or no samples left.
    """
    start, end = check_pair_alignment(
        follower.t_s, leader.t_s, str(follower.path), str(leader.path),
        max_start_offset_s=max_start_offset_s, min_overlap_fraction=min_overlap_fraction,
    )
    inside = (follower.t_s >= start) & (follower.t_s <= end)
    keep = inside & (bracket_gap_s(leader.t_s, follower.t_s) <= max_gap_s)
    n_keep = int(keep.sum())
    if n_keep < 2:
        raise IngestError(follower.path, f"fewer than 2 samples overlap {leader.path}")
    t = follower.t_s[keep]

    # Kinematic clock check: in these flights both vehicles move at once (a swap).
    lag_s, corr = estimate_lag_s(
        follower.t_s, np.linalg.norm(follower.vel_mps[:, :2], axis=1),
        leader.t_s, np.linalg.norm(leader.vel_mps[:, :2], axis=1),
    )
    if corr > 0.5 and abs(lag_s) > max_lag_s:
        warnings.warn(ingest_warning(
            follower.path, f"its motion and {leader.path.name}'s line up best with a "
            f"{lag_s:+.2f} s clock shift (correlation {corr:.2f}); check the alignment"),
            stacklevel=2)

    follower_rot = follower.rot[keep]
    name = f"{follower.path.parent.name}_{follower.flight_id}_{follower.vehicle_id}"
    meta = {
        "name": name,
        "source": SOURCE,
        "frame": "NED",
        "label_basis": "thrust",
        "leader_mass_kg": leader_mass_kg,
        "follower_mass_kg": follower_mass_kg,
        **{f"{role}_{key}": value for role, values in (rotors or {}).items()
           for key, value in zip(("rotor_radius_m", "n_rotors", "diagonal_m"), values)},
        "leader_id": leader.vehicle_id,
        "follower_id": follower.vehicle_id,
        "flight_id": follower.flight_id,
        "files": {"leader": str(leader.path), "follower": str(follower.path)},
        "time_unit_detected": {"leader": leader.time_unit, "follower": follower.time_unit},
        "t_origin_s": float(t[0]),
        "clock_start_offset_s": float(leader.t_s[0] - follower.t_s[0]),
        "clock_lag_estimate_s": lag_s,
        "clock_lag_correlation": corr,
        "overlap_s": float(end - start),
        "dropped_samples": int(inside.sum() - n_keep),
        "outside_overlap_samples": int((~inside).sum()),
        "gravity_mps2": GRAVITY_MPS2,
        "conversion": "z-up (x, y, z) -> NED (x, -y, -z); body FLU -> FRD; R_ned = C R C",
    }
    extra = {"leader_thrust_n": resample_linear(leader.t_s, leader.thrust_n, t)}
    if "body_rates_radps" in follower.extra:
        extra["follower_body_rates_radps"] = follower.extra["body_rates_radps"][keep]
    if "body_torque_nm" in follower.extra:
        extra["follower_motor_torque_nm"] = follower.extra["body_torque_nm"][keep]
    for key in ("motor_pwm", "motor_thrust_n", "battery_v"):
        if key in follower.extra:
            extra[f"follower_{key}"] = follower.extra[key][keep]
    return FlightLog(
        t_s=t - t[0],
        leader_pos_m=resample_linear(leader.t_s, leader.pos_m, t),
        leader_vel_mps=resample_linear(leader.t_s, leader.vel_mps, t),
        leader_quat=resample_quat(leader.t_s, leader.quat, t),
        follower_pos_m=follower.pos_m[keep],
        follower_vel_mps=follower.vel_mps[keep],
        follower_quat=follower.quat[keep],
        follower_cmd_accel_mps2=thrust_accel(follower_rot, follower.thrust_n[keep],
                                             follower_mass_kg),
        follower_thrust_n=follower.thrust_n[keep],
        follower_obs_accel_mps2=follower.accel_mps2[keep],
        meta=meta,
        extra=extra,
    )


def read_neural_swarm(paths: list[Path], *, vehicle: str = "small",
                      mass_kg: float | None = None, time_unit: str = "auto",
                      max_start_offset_s: float = 0.5, min_overlap_fraction: float = 0.8,
                      max_gap_s: float = 0.05,
                      progress: Callable[[int, int], None] | None = None) -> list[FlightLog]:
    """Read Neural-Swarm ``cfXX_NN.csv`` files: two FlightLogs per flight (both roles).

    Args:
        paths: The vehicle files (any order; paired by flight number within a folder).
        vehicle: Vehicle type for the mass table: ``"small"`` (0.032 kg), ``"large"``
            (0.067 kg) or per vehicle ``"cf50=small,cf51=large"``.
        mass_kg: Mass of every vehicle, overriding ``vehicle``.
        time_unit: ``"auto"`` (from the spacing) or s, ms, us, ns.
        max_start_offset_s: Largest accepted difference between the two files' first stamps.
        min_overlap_fraction: Smallest accepted common span, as a fraction of the longer file.
        max_gap_s: Follower samples whose leader interpolation spans a longer gap are dropped.
        progress: Called as ``progress(done, total)`` after each file.

    Returns:
        For each flight (sorted by folder and number), the FlightLog with the lower-numbered
        vehicle as the follower, then the one with the other vehicle as the follower.

    Raises:
        IngestError: on any bad file or pairing, naming the file and the problem.
    """
    pairs = pair_files([Path(p) for p in paths])
    total = 2 * len(pairs)
    logs: list[FlightLog] = []
    done = 0
    for path_a, path_b in pairs:
        track_a = read_vehicle_file(path_a, time_unit=time_unit)
        done += 1
        if progress:
            progress(done, total)
        track_b = read_vehicle_file(path_b, time_unit=time_unit)
        done += 1
        ids = [track_a.vehicle_id, track_b.vehicle_id]
        masses = vehicle_masses(vehicle, mass_kg, ids, str(path_a))
        rotors = None if mass_kg is not None else vehicle_rotors(vehicle, ids)
        for follower, leader in ((track_a, track_b), (track_b, track_a)):
            logs.append(build_flightlog(
                follower, leader, follower_mass_kg=masses[follower.vehicle_id],
                leader_mass_kg=masses[leader.vehicle_id], max_start_offset_s=max_start_offset_s,
                min_overlap_fraction=min_overlap_fraction, max_gap_s=max_gap_s,
                rotors=None if rotors is None else {"leader": rotors[leader.vehicle_id],
                                                    "follower": rotors[follower.vehicle_id]},
            ))
        if progress:
            progress(done, total)
    return logs
