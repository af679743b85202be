"""Reader for PX4 ULog files (through ``pyulog``): one vehicle per file, paired by time.

``aerodock ingest --format ulog LEADER.ulg FOLLOWER.ulg`` pairs the two files: the **first is the
leader, the second the follower** (more files: taken two at a time, in the order given). With
``single=True`` (``--single``) every file is a follower on its own, with a *virtual* leader held
still 100 m above the follower's first position (``leader_offset_m``), far enough that no
downwash reaches the follower; ``meta["leader"] == "virtual"`` marks such flights.

Topics (time stamps in µs, PX4 frames: NED world, FRD body):

- ``vehicle_local_position``: ``x, y, z, vx, vy, vz`` (NED); its time stamps are the flight's.
- ``vehicle_attitude``: ``q[0..3]``, ``[w, x, y, z]``, body FRD to NED.
- Commanded thrust, normalised (``[0, 1]`` along ``-z_b``), the first topic present of
  ``vehicle_thrust_setpoint.xyz``, ``vehicle_rates_setpoint.thrust_body``,
  ``vehicle_attitude_setpoint.thrust_body``; in logs of PX4 1.10 and older, which have no
  thrust vector, the scalar ``thrust`` of ``vehicle_rates_setpoint`` or
  ``vehicle_attitude_setpoint`` (along ``-z_b``). It becomes acceleration through the hover
  thrust (``hover_thrust`` option, else ``hover_thrust_estimate.hover_thrust``, else the
  ``MPC_THR_HOVER`` parameter): ``|a| = g * thrust / hover``; or through ``max_thrust_n`` and the
  mass. The label basis is ``"thrust"``: ``cmd = g e3 + R thrust_body g / hover``. A hover thrust
  outside 0.05-0.95 is implausible (an error for the option; estimate rows that are NaN or
  implausible are dropped, with a warning).
- Observed acceleration: ``vehicle_acceleration.xyz`` (body specific force, ``R f + g e3``),
  else ``vehicle_local_position.ax, ay, az`` (NED, gravity removed), else (old logs)
  ``sensor_combined.accelerometer_m_s2`` (body specific force).
- ``vehicle_land_detected.landed``, if logged, gives ``extra["label_valid"]`` (False on the
  ground, where the support force, not the air, explains ``a_obs - cmd``).
- ``vehicle_status`` (``vehicle_type``, or ``is_rotary_wing`` in old logs) or else the
  ``MAV_TYPE`` parameter: a vehicle that is not a multirotor gives a warning.
- Plausibility: an accelerometer whose median reading is about 1 (g, not m/s²) or points down,
  an attitude upside down in most samples, or positions and velocities that disagree by a
  factor near 1000 stop with an error naming the likely cause.

Clocks: each log's stamps count from its own boot. Two logs are put on one clock through GPS
time (``vehicle_gps_position``/``sensor_gps`` ``time_utc_usec``) when both have it, else their
boot clocks are taken as shared (e.g. logs of one SITL run), and the overlap is checked.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from aerodock.flightlog import FlightLog
from aerodock.geometry import (
    E3,
    GRAVITY_MPS2,
    quat_to_rotmat,
    rotmat_to_quat,
    specific_force_to_accel,
)
from aerodock.ingest.common import (
    bracket_gap_s,
    check_finite,
    check_hover_thrust,
    check_kinematics,
    check_mass,
    check_pair_alignment,
    check_specific_force,
    check_time,
    check_time_unit,
    check_upright,
    resample_hold,
    resample_linear,
    resample_quat,
)
from aerodock.ingest.errors import IngestError, ingest_warning
from aerodock.ingest.ulog_file import load_ulog

SOURCE = "ulog"
DEFAULT_MASS_KG = 1.0
DEFAULT_LEADER_OFFSET_M = (0.0, 0.0, -100.0)
THRUST_TOPICS = (
    ("vehicle_thrust_setpoint", "xyz"),
    ("vehicle_rates_setpoint", "thrust_body"),
    ("vehicle_attitude_setpoint", "thrust_body"),
    # PX4 <= 1.10: a scalar normalised thrust along -z_b
    ("vehicle_rates_setpoint", "thrust"),
    ("vehicle_attitude_setpoint", "thrust"),
)
TOPICS = (
    "vehicle_local_position", "vehicle_attitude", "vehicle_acceleration",
    "hover_thrust_estimate", "vehicle_gps_position", "sensor_gps", "vehicle_land_detected",
    "vehicle_status", "sensor_combined", *dict.fromkeys(topic for topic, _ in THRUST_TOPICS),
)
# vehicle_status.vehicle_type (PX4 >= 1.11) and MAV_TYPE values of multirotors
_ROTARY_WING_TYPE = 1
_VEHICLE_TYPES = {0: "unknown", 1: "rotary wing", 2: "fixed wing", 3: "rover", 4: "airship"}
_MULTIROTOR_MAV_TYPES = {2, 3, 13, 14, 15}  # quad, coaxial, hexa, octo, tri
_MAV_TYPES = {1: "fixed wing", 4: "helicopter", 10: "ground rover", 11: "surface boat",
              12: "submarine", 19: "VTOL", 20: "VTOL", 21: "VTOL", 22: "VTOL"}


@dataclass
class UlogTrack:
    """One vehicle's ULog, on its local-position time stamps (boot clock, seconds)."""

    path: Path
    t_s: np.ndarray
    pos_m: np.ndarray
    vel_mps: np.ndarray
    quat: np.ndarray
    cmd_accel_mps2: np.ndarray
    thrust_n: np.ndarray
    obs_accel_mps2: np.ndarray
    utc_offset_s: float | None
    meta: dict[str, Any] = field(default_factory=dict)
    label_valid: np.ndarray | None = None


def _topic(datasets: dict[str, dict[str, np.ndarray]], name: str, fields: list[str],
           where: str) -> tuple[np.ndarray, np.ndarray]:
    """Checked time (s) and fields ``(T, k)`` of one topic."""
    data = datasets[name]
    missing = [f for f in ["timestamp", *fields] if f not in data]
    if missing:
        raise IngestError(where, f"topic {name} lacks fields {', '.join(missing)}")
    stamps = np.asarray(data["timestamp"], dtype=float)
    column = f"{name}.timestamp"
    check_time(stamps, where, column=column)
    check_time_unit(stamps, "us", where, column=column)
    values = np.stack([np.asarray(data[f], dtype=float) for f in fields], axis=1)
    check_finite({f"{name}.{f}": values[:, k] for k, f in enumerate(fields)}, where)
    return stamps * 1e-6, values


def read_ulog_vehicle(path: Path, *, mass_kg: float | None = None,
                      hover_thrust: float | None = None,
                      max_thrust_n: float | None = None) -> UlogTrack:
    """Read one vehicle's ULog file into NED arrays on its local-position time stamps.

    Args:
        path: The ``.ulg`` file.
        mass_kg: Vehicle mass (default 1 kg with a warning: it only scales ``thrust_n``
            when the hover thrust is known).
        hover_thrust: Normalised hover thrust, overriding the log's estimate and parameter.
        max_thrust_n: Thrust at normalised 1, N; if given, used instead of the hover thrust.

    Raises:
        IngestError: unreadable or empty file, a missing topic or field, NaNs, bad time stamps
            (duplicated, non-monotonic, not in µs), no hover thrust, no overlap of the topics.
    """
    path = Path(path)
    where = str(path)
    ulog = load_ulog(path, TOPICS)
    datasets = {d.name: d.data for d in ulog.data_list if d.multi_id == 0}
    for name in ("vehicle_local_position", "vehicle_attitude"):
        if name not in datasets:
            raise IngestError(where, f"missing topic {name}")
    t_lp, lp = _topic(datasets, "vehicle_local_position", ["x", "y", "z", "vx", "vy", "vz"],
                      where)
    t_att, quat = _topic(datasets, "vehicle_attitude", [f"q[{k}]" for k in range(4)], where)
    t_thr, thrust_body, thrust_topic = _thrust_setpoint(datasets, where)
    check_kinematics(t_lp, lp[:, :3], lp[:, 3:], where, "vehicle_local_position")
    t_acc, accel, accel_source = _acceleration_topic(datasets, where)

    start = max(t_lp[0], t_att[0], t_thr[0], t_acc[0])
    end = min(t_lp[-1], t_att[-1], t_thr[-1], t_acc[-1])
    keep = (t_lp >= start) & (t_lp <= end)
    if keep.sum() < 2:
        raise IngestError(where, "vehicle_local_position, vehicle_attitude, the thrust setpoint "
                                 "and the acceleration do not overlap in time")
    t = t_lp[keep]
    q = resample_quat(t_att, quat, t)
    rot = quat_to_rotmat(q)
    check_upright(rot, where, "vehicle_attitude", "q not in w, x, y, z order, or not FRD to "
                                                  "NED?")
    vehicle_type = _warn_unless_multirotor(ulog, datasets, path)

    if mass_kg is None:
        mass = DEFAULT_MASS_KG
        mass_assumed = True
    else:
        mass = check_mass(mass_kg, where, "--mass-kg")
        mass_assumed = False
    thr = resample_hold(t_thr, thrust_body, t)
    thrust_norm = np.linalg.norm(thr, axis=1)
    if max_thrust_n is not None:
        if mass_assumed:
            raise IngestError(where, "max_thrust_n needs the vehicle mass: pass --mass-kg")
        max_thrust = check_mass(max_thrust_n, where, "max thrust (N)")
        accel_per_unit = max_thrust / mass
        thrust_model = f"max_thrust_n={max_thrust:g}"
    else:
        hover, hover_source = _hover_thrust(ulog, datasets, hover_thrust, t, where)
        accel_per_unit = GRAVITY_MPS2 / hover
        thrust_model = f"hover_thrust from {hover_source}"
    accel_per_unit = np.broadcast_to(accel_per_unit, t.shape)
    # thrust_body is a body-FRD vector (z negative upwards): its world image is R thrust_body.
    cmd = GRAVITY_MPS2 * E3 + np.einsum("tij,tj->ti", rot, thr) * accel_per_unit[:, None]

    acc = resample_linear(t_acc, accel, t)
    obs = acc if accel_source == "vehicle_local_position.ax/ay/az" else \
        specific_force_to_accel(rot, acc)

    utc_offset = _utc_offset_s(datasets)
    label_valid = _label_valid(datasets, t)
    meta = {
        "file": where,
        "thrust_topic": thrust_topic,
        "thrust_model": thrust_model,
        "obs_accel_source": accel_source,
        "mass_kg": mass,
        "mass_assumed": mass_assumed,
        "clock_utc_offset_s": utc_offset,
        "px4_version": str(ulog.msg_info_dict.get("ver_sw_branch", "")),
        "vehicle_type": vehicle_type,
        "landed_fraction": None if label_valid is None else float(np.mean(~label_valid)),
    }
    _note_xy_valid(meta, datasets, keep, path)
    return UlogTrack(
        path=path, t_s=t, pos_m=lp[keep, :3], vel_mps=lp[keep, 3:], quat=q, cmd_accel_mps2=cmd,
        thrust_n=mass * thrust_norm * accel_per_unit, obs_accel_mps2=obs, utc_offset_s=utc_offset,
        meta=meta, label_valid=label_valid,
    )


def _thrust_setpoint(datasets: dict[str, dict[str, np.ndarray]],
                     where: str) -> tuple[np.ndarray, np.ndarray, str]:
    """The commanded thrust: the first topic of :data:`THRUST_TOPICS` present with its field.

    A scalar thrust (PX4 1.10 and older) is the vector ``(0, 0, -thrust)`` (along ``-z_b``).

    Returns:
        ``(t_s, thrust_body (T, 3), "topic.field")``: time, s, and the normalised body-FRD
        thrust vector.

    Raises:
        IngestError: no thrust setpoint topic (or none with a thrust field), or a bad topic.
    """
    thrust_src = next(((t, f) for t, f in THRUST_TOPICS if t in datasets
                       and (f"{f}[0]" in datasets[t] or f in datasets[t])), None)
    if thrust_src is None:
        present = [t for t in dict.fromkeys(t for t, _ in THRUST_TOPICS) if t in datasets]
        raise IngestError(where, "missing topic: no thrust setpoint (none of "
                                 f"{', '.join(dict.fromkeys(t for t, _ in THRUST_TOPICS))}"
                                 + (f"; {', '.join(present)} without a thrust field)" if present
                                    else ")"))
    if f"{thrust_src[1]}[0]" in datasets[thrust_src[0]]:
        t_thr, thrust_body = _topic(datasets, thrust_src[0],
                                    [f"{thrust_src[1]}[{k}]" for k in range(3)], where)
    else:  # PX4 <= 1.10: scalar thrust along -z_b
        t_thr, scalar = _topic(datasets, thrust_src[0], [thrust_src[1]], where)
        thrust_body = np.column_stack([np.zeros((len(t_thr), 2)), -scalar[:, 0]])
    return t_thr, thrust_body, f"{thrust_src[0]}.{thrust_src[1]}"


def _acceleration_topic(datasets: dict[str, dict[str, np.ndarray]],
                        where: str) -> tuple[np.ndarray, np.ndarray, str]:
    """The observed acceleration's topic (see the module docstring), a body specific force
    checked for plausibility.

    Returns:
        ``(t_s, accel (T, 3), source)``: ``source`` is ``"vehicle_acceleration"`` or
        ``"sensor_combined"`` (body FRD specific force, m/s²) or
        ``"vehicle_local_position.ax/ay/az"`` (NED acceleration, gravity removed).

    Raises:
        IngestError: a bad topic, or a specific force in g or pointing down.
    """
    lp_fields = datasets["vehicle_local_position"]
    if "vehicle_acceleration" in datasets:
        t_acc, accel = _topic(datasets, "vehicle_acceleration", [f"xyz[{k}]" for k in range(3)],
                              where)
        accel_source = "vehicle_acceleration"
    elif "ax" in lp_fields or "sensor_combined" not in datasets:
        t_acc, accel = _topic(datasets, "vehicle_local_position", ["ax", "ay", "az"], where)
        accel_source = "vehicle_local_position.ax/ay/az"
    else:  # old logs: the raw accelerometer (body FRD specific force)
        t_acc, accel = _topic(datasets, "sensor_combined",
                              [f"accelerometer_m_s2[{k}]" for k in range(3)], where)
        accel_source = "sensor_combined"
    if accel_source != "vehicle_local_position.ax/ay/az":
        check_specific_force(accel, where, f"{accel_source} (specific force, body FRD)",
                             down_axis=E3, frame="body z already up? (PX4's body frame is FRD)")
    return t_acc, accel, accel_source


def _label_valid(datasets: dict[str, dict[str, np.ndarray]], t: np.ndarray) -> np.ndarray | None:
    """False where ``vehicle_land_detected`` says landed, held onto ``t`` (None: not logged).

    On the ground the support force, not the air, explains ``a_obs - cmd``: not a label.
    """
    land = datasets.get("vehicle_land_detected")
    if land is None or "landed" not in land or not len(land["timestamp"]):
        return None
    t_land = np.asarray(land["timestamp"], dtype=float) * 1e-6
    order = np.argsort(t_land, kind="stable")
    return resample_hold(t_land[order], np.asarray(land["landed"])[order] == 0, t)


def _note_xy_valid(meta: dict[str, Any], datasets: dict[str, dict[str, np.ndarray]],
                   keep: np.ndarray, path: Path) -> None:
    """Add ``xy_valid_fraction`` to ``meta`` where the log has ``vehicle_local_position.xy_valid``
    (over the ``keep`` samples), warning (for the caller of :func:`read_ulog_vehicle`) when it is
    below one."""
    if "xy_valid" in datasets["vehicle_local_position"]:
        valid = np.asarray(datasets["vehicle_local_position"]["xy_valid"])[keep]
        meta["xy_valid_fraction"] = float(np.mean(valid != 0))
        if meta["xy_valid_fraction"] < 1.0:
            warnings.warn(ingest_warning(
                path, f"horizontal position valid in only {100 * meta['xy_valid_fraction']:.0f}%"
                " of vehicle_local_position samples"), stacklevel=3)


def _hover_thrust(ulog: Any, datasets: dict[str, dict[str, np.ndarray]],
                  option: float | None, t: np.ndarray, where: str) -> tuple[Any, str]:
    if option is not None:
        value = float(option)
        if not check_hover_thrust(value):
            raise IngestError(where, f"hover thrust {option!r} is implausible: expected the "
                                     "normalised thrust that holds a hover, 0.05-0.95")
        return value, "option"
    est = datasets.get("hover_thrust_estimate")
    if est is not None and "hover_thrust" in est and len(est.get("timestamp", [])):
        stamps = np.asarray(est["timestamp"], dtype=float)
        hover = np.asarray(est["hover_thrust"], dtype=float)
        good = np.isfinite(stamps) & np.array([check_hover_thrust(h) for h in hover], bool)
        if "valid" in est:
            good &= np.asarray(est["valid"]) != 0
        if good.sum() < len(hover):
            warnings.warn(ingest_warning(
                where, f"hover_thrust_estimate: {len(hover) - int(good.sum())} of {len(hover)} "
                "rows are NaN, not valid or implausible (outside 0.05-0.95) and were dropped"),
                stacklevel=3)
        if good.any():
            t_h, h = stamps[good], hover[good]
            check_time(t_h, where, column="hover_thrust_estimate.timestamp")
            return resample_hold(t_h * 1e-6, h, t), "hover_thrust_estimate"
    param = ulog.initial_parameters.get("MPC_THR_HOVER")
    if param is not None and check_hover_thrust(float(param)):
        return float(param), "MPC_THR_HOVER"
    raise IngestError(where, "no plausible hover thrust (no usable hover_thrust_estimate rows, "
                             "MPC_THR_HOVER missing or outside 0.05-0.95): pass --hover-thrust "
                             "or max_thrust_n")


def _warn_unless_multirotor(ulog: Any, datasets: dict[str, dict[str, np.ndarray]],
                            path: Path) -> str:
    """The vehicle type (from vehicle_status or MAV_TYPE); warns when it is not a multirotor."""
    status = datasets.get("vehicle_status")
    kind: str | None = None
    rotary: bool | None = None
    if status is not None and "vehicle_type" in status and len(status["vehicle_type"]):
        codes = np.asarray(status["vehicle_type"]).astype(int)
        code = int(codes[-1])
        kind, rotary = _VEHICLE_TYPES.get(code, f"type {code}"), code == _ROTARY_WING_TYPE
        if "is_vtol" in status and np.asarray(status["is_vtol"]).any():
            share = float(np.mean(codes == _ROTARY_WING_TYPE))
            kind = f"a VTOL, in multirotor mode in {100 * share:.0f}% of vehicle_status"
            rotary = False
    elif status is not None and "is_rotary_wing" in status and len(status["is_rotary_wing"]):
        rotary = bool(np.asarray(status["is_rotary_wing"])[-1])
        kind = "rotary wing" if rotary else "fixed wing"
        if "is_vtol" in status and np.asarray(status["is_vtol"]).any():
            kind, rotary = "VTOL", False
    else:
        mav_type = ulog.initial_parameters.get("MAV_TYPE")
        if mav_type is not None:
            code = int(mav_type)
            rotary = code in _MULTIROTOR_MAV_TYPES
            kind = "multirotor" if rotary else _MAV_TYPES.get(code, f"MAV_TYPE {code}")
    if rotary is False:
        warnings.warn(ingest_warning(
            path, f"the vehicle is not a multirotor ({kind}): aerodock's downwash models and "
            "labels assume one"), stacklevel=3)
    return kind or "unknown"


def _utc_offset_s(datasets: dict[str, dict[str, np.ndarray]]) -> float | None:
    for name in ("vehicle_gps_position", "sensor_gps"):
        data = datasets.get(name)
        if data is None or "time_utc_usec" not in data:
            continue
        utc = np.asarray(data["time_utc_usec"], dtype=float)
        stamps = np.asarray(data["timestamp"], dtype=float)
        good = utc > 0
        if good.any():
            return float(np.median(utc[good] - stamps[good])) * 1e-6
    return None


def _check_time_base(track: UlogTrack) -> None:
    if track.t_s.shape[0] < 2:
        raise IngestError(track.path, "fewer than 2 samples")


def pair_tracks(leader: UlogTrack, follower: UlogTrack, *, min_overlap_fraction: float = 0.5,
                max_gap_s: float = 0.2) -> FlightLog:
    """FlightLog of two vehicles' tracks on the follower's time stamps (see the module doc).

    Raises:
        IngestError: the logs do not overlap enough in time (different lengths or clocks).
    """
    if leader.utc_offset_s is not None and follower.utc_offset_s is not None:
        clock = "gps-utc"
        t_leader = leader.t_s + leader.utc_offset_s
        t_follower = follower.t_s + follower.utc_offset_s
    else:
        clock = "boot (assumed shared)"
        t_leader, t_follower = leader.t_s, follower.t_s
    start, end = check_pair_alignment(
        t_follower, t_leader, str(follower.path), str(leader.path),
        max_start_offset_s=np.inf, min_overlap_fraction=min_overlap_fraction,
    )
    inside = (t_follower >= start) & (t_follower <= end)
    keep = inside & (bracket_gap_s(t_leader, t_follower) <= max_gap_s)
    if keep.sum() < 2:
        raise IngestError(follower.path, f"fewer than 2 samples overlap {leader.path}")
    t = t_follower[keep]
    meta = _meta(follower, f"{follower.path.stem}_with_{leader.path.stem}")
    meta.update({
        "leader": "logged",
        "leader_mass_kg": leader.meta["mass_kg"],
        "files": {"leader": str(leader.path), "follower": str(follower.path)},
        "clock": clock,
        "t_origin_s": float(t[0]),
        "overlap_s": float(end - start),
        "dropped_samples": int(inside.sum() - keep.sum()),
    })
    return FlightLog(
        t_s=t - t[0],
        leader_pos_m=resample_linear(t_leader, leader.pos_m, t),
        leader_vel_mps=resample_linear(t_leader, leader.vel_mps, t),
        leader_quat=resample_quat(t_leader, leader.quat, t),
        follower_pos_m=follower.pos_m[keep],
        follower_vel_mps=follower.vel_mps[keep],
        follower_quat=follower.quat[keep],
        follower_cmd_accel_mps2=follower.cmd_accel_mps2[keep],
        follower_thrust_n=follower.thrust_n[keep],
        follower_obs_accel_mps2=follower.obs_accel_mps2[keep],
        meta=meta,
        extra=_extra(follower, keep, resample_linear(t_leader, leader.thrust_n, t)),
    )


def single_track(follower: UlogTrack, *,
                 leader_offset_m: tuple[float, float, float] = DEFAULT_LEADER_OFFSET_M,
                 leader_mass_kg: float | None = None) -> FlightLog:
    """FlightLog of one vehicle as the follower, with a still virtual leader far away.

    The leader sits at ``follower_pos[0] + leader_offset_m`` (default 100 m above), level, with
    zero velocity, so no downwash reaches the follower.
    """
    n = follower.t_s.shape[0]
    leader_pos = follower.pos_m[0] + np.asarray(leader_offset_m, dtype=float)
    meta = _meta(follower, follower.path.stem)
    meta.update({
        "leader": "virtual",
        "leader_offset_m": [float(v) for v in leader_offset_m],
        "leader_mass_kg": leader_mass_kg if leader_mass_kg is not None else follower.meta[
            "mass_kg"],
        "files": {"follower": str(follower.path)},
        "clock": "boot",
        "t_origin_s": float(follower.t_s[0]),
    })
    return FlightLog(
        t_s=follower.t_s - follower.t_s[0],
        leader_pos_m=np.tile(leader_pos, (n, 1)),
        leader_vel_mps=np.zeros((n, 3)),
        leader_quat=np.tile(rotmat_to_quat(np.eye(3)), (n, 1)),
        follower_pos_m=follower.pos_m,
        follower_vel_mps=follower.vel_mps,
        follower_quat=follower.quat,
        follower_cmd_accel_mps2=follower.cmd_accel_mps2,
        follower_thrust_n=follower.thrust_n,
        follower_obs_accel_mps2=follower.obs_accel_mps2,
        meta=meta,
        extra=_extra(follower, np.ones(n, dtype=bool), np.zeros(n)),
    )


def _extra(follower: UlogTrack, keep: np.ndarray, leader_thrust_n: np.ndarray
           ) -> dict[str, np.ndarray]:
    extra = {"leader_thrust_n": leader_thrust_n}
    if follower.label_valid is not None:
        extra["label_valid"] = follower.label_valid[keep]
    return extra


def _meta(follower: UlogTrack, name: str) -> dict[str, Any]:
    return {
        "name": name,
        "source": SOURCE,
        "frame": "NED",
        "label_basis": "thrust",
        "follower_mass_kg": follower.meta["mass_kg"],
        "mass_assumed": follower.meta["mass_assumed"],
        "thrust_topic": follower.meta["thrust_topic"],
        "thrust_model": follower.meta["thrust_model"],
        "obs_accel_source": follower.meta["obs_accel_source"],
        "landed_fraction": follower.meta["landed_fraction"],
        "vehicle_type": follower.meta["vehicle_type"],
        "gravity_mps2": GRAVITY_MPS2,
    }


def read_ulog(paths: list[Path], *, single: bool = False, mass_kg: float | None = None,
              hover_thrust: float | None = None, max_thrust_n: float | None = None,
              leader_offset_m: tuple[float, float, float] = DEFAULT_LEADER_OFFSET_M,
              min_overlap_fraction: float = 0.5, max_gap_s: float = 0.2,
              progress: Callable[[int, int], None] | None = None) -> list[FlightLog]:
    """Read ULog files: pairs (leader, follower) in the order given, or each alone (``single``).

    Args:
        paths: ``.ulg`` files; without ``single`` an even number: leader, follower, leader, ...
        single: Every file is a follower with a virtual far leader (see :func:`single_track`).
        mass_kg: Mass of every vehicle (default 1 kg, with a warning).
        hover_thrust: Normalised hover thrust of every vehicle (default: from each log).
        max_thrust_n: Thrust at normalised 1, N (instead of the hover thrust).
        leader_offset_m: Offset of the virtual leader from the follower's start (``single``).
        min_overlap_fraction: Smallest accepted common span, as a fraction of the longer log.
        max_gap_s: Follower samples whose leader interpolation spans a longer gap are dropped.
        progress: Called as ``progress(done, total)`` after each file.

    Raises:
        IngestError: an odd number of files without ``single``, or any bad file.
    """
    paths = [Path(p) for p in paths]
    if not single and len(paths) % 2:
        raise IngestError(paths[-1], f"{len(paths)} ULog files: give pairs (LEADER.ulg "
                                     "FOLLOWER.ulg), or --single for one vehicle per file")
    if mass_kg is None:
        warnings.warn(ingest_warning(
            paths[0] if paths else "ulog", f"no --mass-kg: assuming {DEFAULT_MASS_KG:g} kg (it "
            "scales follower_thrust_n only; the label uses the hover thrust)"), stacklevel=2)
    tracks = []
    for i, path in enumerate(paths):
        track = read_ulog_vehicle(path, mass_kg=mass_kg, hover_thrust=hover_thrust,
                                  max_thrust_n=max_thrust_n)
        _check_time_base(track)
        tracks.append(track)
        if progress:
            progress(i + 1, len(paths))
    if single:
        return [single_track(track, leader_offset_m=leader_offset_m) for track in tracks]
    return [pair_tracks(tracks[i], tracks[i + 1], min_overlap_fraction=min_overlap_fraction,
                        max_gap_s=max_gap_s) for i in range(0, len(tracks), 2)]
