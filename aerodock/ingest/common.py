"""Shared pieces of the log readers: validation, time units, frames, resampling, pairing.

Every reader turns its source into :class:`aerodock.flightlog.FlightLog` (world NED, body FRD, SI)
and rejects bad input with a one-line :class:`~aerodock.ingest.errors.IngestError` naming the file
and the problem. The checks live here so every reader words them the same way.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from aerodock.fileio import InputError, check_input_file
from aerodock.geometry import GRAVITY_MPS2
from aerodock.ingest.errors import IngestError

# World ENU (REP-103) -> NED: north = y_enu, east = x_enu, down = -z_enu.
ENU_TO_NED = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
# A rotation of pi about x: body FLU -> FRD; Neural-Swarm z-up world (x, y, z) -> (x, -y, -z).
FLIP_YZ = np.diag([1.0, -1.0, -1.0])
IDENTITY = np.eye(3)

# Unit name -> seconds per unit.
TIME_UNITS: dict[str, float] = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}
_UNIT_LABEL = {"s": "seconds", "ms": "milliseconds", "us": "microseconds", "ns": "nanoseconds"}

# A flight log's sample spacing, seconds: between 10 kHz and 5 Hz (a slower log cannot show the
# downwash, whose turbulence decorrelates in about 0.1 s; a 1 kHz log with its time in ms would
# otherwise pass as 1 Hz).
MIN_PLAUSIBLE_DT_S = 1e-4
MAX_PLAUSIBLE_DT_S = 0.2

# Plausibility limits of multirotor flight data (see check_kinematics and friends).
MAX_PLAUSIBLE_SPEED_MPS = 30.0
MAX_PLAUSIBLE_POSITION_M = 10_000.0
MOVING_SPEED_MPS = 0.05


# --------------------------------------------------------------------------------------------
# Validation
# --------------------------------------------------------------------------------------------


def check_not_empty(n_samples: int, where: str, what: str = "samples", minimum: int = 2) -> None:
    """Raise if fewer than ``minimum`` samples are present.

    Raises:
        IngestError: ``"{where}: empty (no samples)"`` or too few samples.
    """
    if n_samples == 0:
        raise IngestError(where, f"empty: no {what}")
    if n_samples < minimum:
        raise IngestError(where, f"only {n_samples} {what}; need at least {minimum}")


def _row(i: int, rows: np.ndarray | None) -> int:
    return int(rows[i]) if rows is not None else i


def check_finite(columns: dict[str, np.ndarray], where: str, *, row_name: str = "sample",
                 rows: np.ndarray | None = None) -> None:
    """Raise on the first NaN or infinite value, naming the column and the row.

    Args:
        columns: Column name -> array with samples along the first axis.
        where: The file, for the message.
        row_name: How rows are called in the message (``"sample"``, ``"line"``).
        rows: Row number to report for each sample (default: the 0-based sample index).

    Raises:
        IngestError: ``"{where}: NaN in column 'vx' at line 17 (1 bad rows in all)"``.
    """
    for name, values in columns.items():
        arr = np.asarray(values, dtype=float)
        if arr.shape[0] == 0:
            continue
        bad = ~np.isfinite(arr.reshape(arr.shape[0], -1)).all(axis=1)
        if bad.any():
            i = int(np.argmax(bad))
            kind = "NaN" if np.isnan(arr[i]).any() else "infinite value"
            raise IngestError(
                where, f"{kind} in column {name!r} at {row_name} {_row(i, rows)} "
                f"({int(bad.sum())} bad rows in all)"
            )


def check_time(t: np.ndarray, where: str, *, column: str = "time", row_name: str = "sample",
               rows: np.ndarray | None = None) -> None:
    """Raise unless ``t`` is non-empty, finite and strictly increasing.

    Raises:
        IngestError: empty, NaN, duplicated or decreasing time, with the row of the first problem.
    """
    t = np.asarray(t, dtype=float)
    check_not_empty(t.shape[0], where)
    check_finite({column: t}, where, row_name=row_name, rows=rows)
    dt = np.diff(t)
    if np.any(dt <= 0):
        i = int(np.argmax(dt <= 0)) + 1
        if dt[i - 1] == 0:
            n_dup = int(np.sum(dt == 0))
            raise IngestError(
                where, f"duplicated time in column {column!r} at {row_name} {_row(i, rows)} "
                f"(value {t[i]:.9g} repeats; {n_dup} duplicates in all)"
            )
        raise IngestError(
            where, f"time in column {column!r} is not monotonic: goes back from {t[i - 1]:.9g} "
            f"to {t[i]:.9g} at {row_name} {_row(i, rows)}"
        )


def median_spacing(t: np.ndarray) -> float:
    """Median of the positive time steps (0.0 if there are none)."""
    dt = np.diff(np.asarray(t, dtype=float))
    dt = dt[dt > 0]
    return float(np.median(dt)) if dt.size else 0.0


def detect_time_unit(t_raw: np.ndarray, where: str, *, column: str = "time",
                     expected_dt_s: float = 0.01, tolerance: float = 10.0) -> str:
    """Unit of raw time stamps, from their spacing and the expected sample period.

    The candidate units (s, ms, µs, ns) are a factor 1000 apart, so with ``tolerance`` at most
    about 30 only one can put the median spacing within ``tolerance`` of ``expected_dt_s``.

    Returns:
        The unit name, a key of :data:`TIME_UNITS`.

    Raises:
        IngestError: no unit gives a plausible sample rate.
    """
    med = median_spacing(t_raw)
    best = min(TIME_UNITS, key=lambda u: abs(np.log(max(med * TIME_UNITS[u], 1e-300)
                                                     / expected_dt_s)))
    ratio = med * TIME_UNITS[best] / expected_dt_s
    if med <= 0 or not (1.0 / tolerance <= ratio <= tolerance):
        raise IngestError(
            where, f"cannot tell the unit of column {column!r}: median spacing {med:.6g} is "
            f"not about {expected_dt_s:g} s ({1.0 / expected_dt_s:g} Hz) in s, ms, us or ns"
        )
    return best


def check_time_unit(t_raw: np.ndarray, unit: str, where: str, *, column: str = "time") -> None:
    """Raise if stamps declared in ``unit`` give an implausible sample rate (unit mix-up).

    A flight log is sampled between 5 Hz and 10 kHz. Stamps 1000 times too coarse or too fine
    (milliseconds written where microseconds are expected, ...) fall outside that range, and the
    message names the unit that would fit.

    Raises:
        IngestError: ``"{where}: column 't_s' looks like milliseconds, expected seconds (...)"``.
    """
    med = median_spacing(t_raw)
    dt_s = med * TIME_UNITS[unit]
    if med <= 0 or MIN_PLAUSIBLE_DT_S <= dt_s <= MAX_PLAUSIBLE_DT_S:
        return
    fits = [u for u, scale in TIME_UNITS.items()
            if MIN_PLAUSIBLE_DT_S <= med * scale <= MAX_PLAUSIBLE_DT_S]
    guess = f"looks like {_UNIT_LABEL[fits[0]]}" if fits else "has an implausible spacing"
    raise IngestError(
        where, f"time column {column!r} {guess}, expected {_UNIT_LABEL[unit]} (median spacing "
        f"{med:.6g} {unit} = {1.0 / dt_s:.3g} Hz; a flight log is sampled at 5 Hz-10 kHz)"
    )


def check_mass(mass_kg: float, where: str, what: str = "mass") -> float:
    """Return ``mass_kg`` as float, raising unless it is finite and positive."""
    try:
        mass = float(mass_kg)
    except (TypeError, ValueError):
        raise IngestError(where, f"{what} {mass_kg!r} is not a number") from None
    if not np.isfinite(mass) or mass <= 0:
        raise IngestError(where, f"{what} must be a positive number of kg, got {mass_kg!r}")
    return mass


# --------------------------------------------------------------------------------------------
# Plausibility: data that reads fine but means something else (units, axes, orders)
# --------------------------------------------------------------------------------------------


def check_kinematics(t_s: np.ndarray, pos_m: np.ndarray, vel_mps: np.ndarray | None,
                     where: str, what: str) -> None:
    """Raise when positions, velocities and time do not fit together as SI flight data.

    Checks: positions within 10 km; speeds (given, and from differentiated positions) below
    30 m/s; and, while the vehicle moves, the given velocity about equal to d/dt of the position
    (a factor near 1000 means positions in mm, or time in ms read as s).

    Raises:
        IngestError: ``"FILE: follower speed from positions is 520 m/s: positions in mm?"``.
    """
    pos = np.asarray(pos_m, dtype=float)
    t = np.asarray(t_s, dtype=float)
    if pos.shape[0] < 3:
        return
    far = float(np.max(np.abs(pos)))
    if far > MAX_PLAUSIBLE_POSITION_M:
        raise IngestError(where, f"{what} position reaches {far:.3g} m: not metres (mm?) "
                                 "or not a local frame")
    dpdt = np.gradient(pos, t, axis=0)
    speed_from_pos = np.linalg.norm(dpdt, axis=1)
    p99 = float(np.percentile(speed_from_pos, 99))
    if vel_mps is None:
        if p99 > MAX_PLAUSIBLE_SPEED_MPS:
            raise IngestError(where, f"{what} speed from positions is {p99:.3g} m/s (99th "
                                     "percentile): positions in mm, or time not in s?")
        return
    vel = np.asarray(vel_mps, dtype=float)
    speed = np.linalg.norm(vel, axis=1)
    moving = (speed > MOVING_SPEED_MPS) | (speed_from_pos > MOVING_SPEED_MPS)
    if moving.sum() >= max(5, pos.shape[0] // 20):
        ratio = float(np.median(speed_from_pos[moving]) / max(np.median(speed[moving]), 1e-12))
        if ratio > 30.0:
            raise IngestError(where, f"{what} positions change {ratio:.3g}x faster than its "
                                     "velocity says: positions in mm (not m)?")
        if ratio < 1.0 / 30.0:
            raise IngestError(where, f"{what} positions change {1 / ratio:.3g}x slower than its "
                                     "velocity says: time in ms read as s (or velocity in mm/s)?")
    v99 = float(np.percentile(speed, 99))
    if v99 > MAX_PLAUSIBLE_SPEED_MPS:
        raise IngestError(where, f"{what} speed is {v99:.3g} m/s (99th percentile): velocity "
                                 "not in m/s?")


def check_upright(rot: np.ndarray, where: str, what: str, hint: str) -> None:
    """Raise when the attitude is upside down (body z up) in most samples.

    A multirotor's FRD body z points down (``R[2, 2] > 0`` in NED) unless it flips; an
    attitude upside down in most samples is a mix-up (quaternion order, frame), named by
    ``hint``.

    Raises:
        IngestError: ``"FILE: follower attitude is upside down in 100% of samples: {hint}"``.
    """
    r22 = np.asarray(rot, dtype=float)[:, 2, 2]
    flipped = float(np.mean(r22 < 0.0))
    if flipped > 0.5:
        raise IngestError(where, f"{what} attitude is upside down in {100 * flipped:.0f}% of "
                                 f"samples: {hint}")


def check_specific_force(force: np.ndarray, where: str, what: str, *, down_axis: np.ndarray,
                         frame: str) -> None:
    """Raise when measured specific forces are not m/s² or point the wrong way.

    An accelerometer on a flying or resting multirotor reads about g (9.81 m/s²) in magnitude
    over a flight, pointing up. ``down_axis`` is the unit vector of the sensor's frame that
    points down at rest (``(0, 0, 1)`` in FRD, ``(0, 0, -1)`` in a z-up frame).

    Raises:
        IngestError: ``"FILE: follower acceleration has median magnitude 1.0: in g, not
            m/s^2?"``, or a hover acceleration of the wrong sign (axis already flipped).
    """
    f = np.asarray(force, dtype=float)
    if f.shape[0] < 3:
        return
    magnitude = float(np.median(np.linalg.norm(f, axis=1)))
    if 0.5 <= magnitude <= 2.0:
        raise IngestError(where, f"{what} has median magnitude {magnitude:.3g}: in g, not "
                                 "m/s^2? (an accelerometer reads about 9.81 m/s^2)")
    if not 4.0 <= magnitude <= 25.0:
        raise IngestError(where, f"{what} has median magnitude {magnitude:.3g} m/s^2; an "
                                 "accelerometer reads about 9.81 (units?)")
    along_down = float(np.median(f @ np.asarray(down_axis, dtype=float)))
    if along_down > 0.5 * GRAVITY_MPS2:
        raise IngestError(where, f"{what} points down ({along_down:+.3g} m/s^2 along the "
                                 f"downward axis) where a hovering accelerometer reads up: "
                                 f"{frame}")


def check_hover_thrust(value: float) -> bool:
    """True for a plausible normalised hover thrust (0.05-0.95; PX4 limits MPC_THR_HOVER so)."""
    return bool(np.isfinite(value) and 0.05 <= value <= 0.95)


# --------------------------------------------------------------------------------------------
# Frames
# --------------------------------------------------------------------------------------------


def convert_vectors(world: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """Express world-frame vectors ``(T, 3)`` in the target world frame (``world @ v``)."""
    return np.asarray(vectors, dtype=float) @ world.T


def convert_rotations(world: np.ndarray, rot: np.ndarray, body: np.ndarray) -> np.ndarray:
    """Body-to-world rotations ``(T, 3, 3)`` re-expressed: ``world @ R @ body.T``.

    ``world`` maps source-world to NED coordinates and ``body`` maps source-body to FRD
    coordinates, so ``v_ned = world R_src v_src_body = (world R_src body^T) v_frd``.
    """
    return world @ np.asarray(rot, dtype=float) @ body.T


def differentiate(t_s: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Time derivative of samples ``(T, ...)`` (second-order central differences)."""
    if len(t_s) < 2:
        return np.zeros_like(values)
    return np.gradient(values, t_s, axis=0, edge_order=1)


# --------------------------------------------------------------------------------------------
# Resampling and pairing
# --------------------------------------------------------------------------------------------


def resample_linear(t_src: np.ndarray, values: np.ndarray, t_dst: np.ndarray) -> np.ndarray:
    """Linear interpolation of ``values`` ``(T_src, ...)`` at ``t_dst`` (inside ``t_src``)."""
    values = np.asarray(values, dtype=float)
    flat = values.reshape(values.shape[0], -1)
    out = np.stack([np.interp(t_dst, t_src, flat[:, k]) for k in range(flat.shape[1])], axis=-1)
    return out.reshape((len(t_dst),) + values.shape[1:])


def resample_hold(t_src: np.ndarray, values: np.ndarray, t_dst: np.ndarray) -> np.ndarray:
    """Zero-order hold: the last source sample at or before each ``t_dst`` (commands, setpoints)."""
    idx = np.clip(np.searchsorted(t_src, t_dst, side="right") - 1, 0, len(t_src) - 1)
    return np.asarray(values)[idx]


def resample_quat(t_src: np.ndarray, quat_wxyz: np.ndarray, t_dst: np.ndarray) -> np.ndarray:
    """Interpolate unit quaternions (normalised linear interpolation, hemisphere-continuous)."""
    q = np.array(quat_wxyz, dtype=float)
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    # q and -q are the same rotation: flip signs so consecutive samples are on one hemisphere.
    flips = np.concatenate([[1.0], np.sign(np.sum(q[1:] * q[:-1], axis=1))])
    flips[flips == 0] = 1.0
    q *= np.cumprod(flips)[:, None]
    out = resample_linear(t_src, q, t_dst)
    out /= np.linalg.norm(out, axis=1, keepdims=True)
    return out * np.where(out[:, :1] < 0, -1.0, 1.0)


def bracket_gap_s(t_src: np.ndarray, t_dst: np.ndarray) -> np.ndarray:
    """For each ``t_dst``, the spacing of the two source samples around it (0 on a sample)."""
    idx = np.clip(np.searchsorted(t_src, t_dst, side="left"), 1, len(t_src) - 1)
    gap = t_src[idx] - t_src[idx - 1]
    exact = np.isin(t_dst, t_src)
    return np.where(exact, 0.0, gap)


def overlap_window(t_a: np.ndarray, t_b: np.ndarray) -> tuple[float, float]:
    """Common time span ``(start, end)`` of two strictly increasing time bases."""
    return max(float(t_a[0]), float(t_b[0])), min(float(t_a[-1]), float(t_b[-1]))


def check_pair_alignment(t_follower: np.ndarray, t_leader: np.ndarray, follower: str,
                         leader: str, *, max_start_offset_s: float,
                         min_overlap_fraction: float) -> tuple[float, float]:
    """Check that two logs of one flight share a clock, and return their overlap window.

    Raises:
        IngestError: start times further apart than ``max_start_offset_s``, or an overlap
            shorter than ``min_overlap_fraction`` of the longer log (files of different lengths).
    """
    start_offset = float(t_leader[0] - t_follower[0])
    if abs(start_offset) > max_start_offset_s:
        raise IngestError(
            follower, f"starts {-start_offset:+.3f} s from {leader} (tolerance "
            f"{max_start_offset_s:g} s): the clocks do not agree or these are not one flight"
        )
    start, end = overlap_window(t_follower, t_leader)
    longest = max(float(t_follower[-1] - t_follower[0]), float(t_leader[-1] - t_leader[0]))
    overlap = max(end - start, 0.0)
    if longest <= 0 or overlap < min_overlap_fraction * longest:
        raise IngestError(
            follower, f"files of different lengths: spans "
            f"{t_follower[-1] - t_follower[0]:.2f} s but {leader} spans "
            f"{t_leader[-1] - t_leader[0]:.2f} s (overlap {overlap:.2f} s, "
            f"{100 * overlap / max(longest, 1e-12):.0f}% < {100 * min_overlap_fraction:.0f}%)"
        )
    return start, end


def estimate_lag_s(t_a: np.ndarray, x_a: np.ndarray, t_b: np.ndarray, x_b: np.ndarray, *,
                   max_lag_s: float = 1.0, dt_s: float = 0.01) -> tuple[float, float]:
    """Time shift that best aligns two signals of one flight (a kinematic clock check).

    Returns:
        ``(lag_s, correlation)``: ``x_b(t - lag_s)`` best matches ``x_a(t)``, i.e. features in
        ``b`` appear ``lag_s`` later than in ``a``, with the normalised correlation at that lag
        (near 1 when the signals share a clear common pattern; near 0 makes the lag meaningless).
    """
    start, end = overlap_window(t_a, t_b)
    if end - start < 4 * max_lag_s:
        return 0.0, 0.0
    grid = np.arange(start, end, dt_s)
    a = np.interp(grid, t_a, x_a)
    b = np.interp(grid, t_b, x_b)
    a -= a.mean()
    b -= b.mean()
    norm = float(np.sqrt(np.dot(a, a) * np.dot(b, b)))
    if norm <= 0:
        return 0.0, 0.0
    n_lag = int(round(max_lag_s / dt_s))
    n = len(grid)
    corr = np.array([
        np.dot(a[max(0, -k):n - max(0, k)], b[max(0, k):n - max(0, -k)])
        for k in range(-n_lag, n_lag + 1)
    ])
    k_best = int(np.argmax(corr))
    # corr[k] pairs a(t) with b(t + k dt): a peak at k > 0 means b shows a's features k dt later.
    return (k_best - n_lag) * dt_s, float(corr[k_best] / norm)


# --------------------------------------------------------------------------------------------
# Input files
# --------------------------------------------------------------------------------------------

BAG_SUFFIXES = (".db3", ".mcap")


@contextmanager
def input_errors(where: str | Path, unreadable: str) -> Iterator[None]:
    """Turn the input reader's errors into one-line :class:`IngestError` s naming ``where``
    (``unreadable``: the words before the system's reason for an unreadable file)."""
    try:
        yield
    except FileNotFoundError:
        raise IngestError(where, "file not found") from None
    except InputError as err:
        raise IngestError(where, err.reason) from None
    except OSError as err:
        raise IngestError(where, f"{unreadable} ({err.strerror or err})") from None


def check_regular_input(path: Path, what: str = "log file") -> None:
    """Refuse an input that is not a regular file, before any reader opens it: a FIFO would
    block its reader for ever and a device such as ``/dev/zero`` never ends.

    Raises:
        IngestError: ``path`` is missing, a FIFO, a device, a socket or a folder.
    """
    with input_errors(path, "cannot read"):
        check_input_file(path, what)


def check_bag_folder(path: Path) -> None:
    """A ROS 2 bag folder's ``metadata.yaml`` and storage files must be regular files.

    Raises:
        IngestError: one of them is a FIFO, a device, a socket or a folder.
    """
    for item in sorted(Path(path).iterdir()):
        if item.name == "metadata.yaml" or item.suffix.lower() in BAG_SUFFIXES:
            check_regular_input(item, "bag file")
