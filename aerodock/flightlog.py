"""FlightLog: the one record format shared by simulated and real flights.

A ``FlightLog`` is one flight of a leader (A) and a follower (B), time-aligned on one clock, in the
world NED frame (z down), SI units. Everything downstream (labels, training, plots) reads
FlightLogs, never a simulator object.

On-disk format (``.npz``, written atomically, read with ``allow_pickle=False``): one file holds one
or more flights. Keys:

- ``format``: the string ``"aerodock-flightlog"``; ``version``: integer (currently 1);
- ``n_flights``: integer;
- ``f{i}/meta``: a JSON string (masses, source, label basis, ...);
- ``f{i}/{field}``: one array per field below, and ``f{i}/extra/{name}`` for optional arrays.

Fields (T samples):

=========================  ========  ====================================================
``t_s``                    (T,)      time, s, strictly increasing
``leader_pos_m``           (T, 3)    leader position, NED
``leader_vel_mps``         (T, 3)    leader velocity, NED
``leader_quat``            (T, 4)    leader attitude, body to world, ``[w, x, y, z]``
``follower_pos_m``         (T, 3)    follower position
``follower_vel_mps``       (T, 3)    follower velocity
``follower_quat``          (T, 4)    follower attitude
``follower_cmd_accel_mps2`` (T, 3)   acceleration the follower's own actuation explains: the
                                     commanded ``u_1:3`` sent to the inversion map (simulated or
                                     flown with a controller log), or ``g e3 - R e3 T/m`` from
                                     measured thrust (``meta["label_basis"] == "thrust"``)
``follower_thrust_n``      (T,)      collective thrust (commanded or measured), N
``follower_obs_accel_mps2`` (T, 3)   observed kinematic acceleration (gravity removed), NED
=========================  ========  ====================================================
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from aerodock.fileio import (
    MAX_NPZ_BYTES,
    READ_ERRORS,
    InputError,
    atomic_open,
    check_npz_header,
    check_writable_target,
    json_default,
    npz_int,
    one_line,
    open_input,
)

LABEL_BASES = ("command", "thrust")
"""What ``meta["label_basis"]`` may say the follower's explained acceleration is (see
:mod:`aerodock.mission.recorder`); any other value is refused."""
FORMAT_NAME = "aerodock-flightlog"
FORMAT_VERSION = 1
VEC3_FIELDS = (
    "leader_pos_m", "leader_vel_mps", "follower_pos_m", "follower_vel_mps",
    "follower_cmd_accel_mps2", "follower_obs_accel_mps2",
)
QUAT_FIELDS = ("leader_quat", "follower_quat")
FIELDS = ("t_s", *VEC3_FIELDS, *QUAT_FIELDS, "follower_thrust_n")
# Largest magnitude of a position (m), velocity (m/s), acceleration (m/s²) or thrust (N): far
# beyond any flight, yet small enough that squares and products stay finite downstream.
MAX_ABS_VALUE = 1e6


class FlightLogError(ValueError):
    """A FlightLog (in memory or on disk) is malformed; the message says where and what."""


@dataclass(frozen=True)
class FlightLog:
    """One two-vehicle flight, NED, SI units. See the module docstring for the fields."""

    t_s: np.ndarray
    leader_pos_m: np.ndarray
    leader_vel_mps: np.ndarray
    leader_quat: np.ndarray
    follower_pos_m: np.ndarray
    follower_vel_mps: np.ndarray
    follower_quat: np.ndarray
    follower_cmd_accel_mps2: np.ndarray
    follower_thrust_n: np.ndarray
    follower_obs_accel_mps2: np.ndarray
    meta: dict[str, Any] = field(default_factory=dict)
    extra: dict[str, np.ndarray] = field(default_factory=dict)

    def __post_init__(self) -> None:
        where = self.meta.get("name", "flightlog")
        n = np.shape(self.t_s)[0] if np.ndim(self.t_s) == 1 else -1
        if n < 0:
            raise FlightLogError(f"{where}: t_s must be 1-D")
        for name in FIELDS:
            arr = np.asarray(getattr(self, name), dtype=float)
            object.__setattr__(self, name, arr)
            expected = {"t_s": (n,), "follower_thrust_n": (n,)}.get(
                name, (n, 4) if name in QUAT_FIELDS else (n, 3)
            )
            if arr.shape != expected:
                raise FlightLogError(f"{where}: {name} has shape {arr.shape}, expected {expected}")
            if not np.all(np.isfinite(arr)):
                raise FlightLogError(f"{where}: {name} contains NaN or infinite values")
            if name != "t_s" and arr.size and np.max(np.abs(arr)) > MAX_ABS_VALUE:
                raise FlightLogError(f"{where}: {name} has values beyond {MAX_ABS_VALUE:g} "
                                     "(not SI units?)")
            if name in QUAT_FIELDS and arr.size:
                norm = np.linalg.norm(arr, axis=1)
                if np.any(np.abs(norm - 1.0) > 0.1):
                    raise FlightLogError(f"{where}: {name} holds quaternions of norm "
                                         f"{norm[np.argmax(np.abs(norm - 1.0))]:.3g}, not unit")
        basis = self.meta.get("label_basis")
        if basis is not None and basis not in LABEL_BASES:
            raise FlightLogError(f"{where}: label_basis must be one of {'|'.join(LABEL_BASES)}, "
                                 f"got {basis!r}")
        for key, arr in self.extra.items():
            if np.shape(arr)[:1] != (n,):
                raise FlightLogError(f"{where}: extra {key!r} must have {n} rows")
        if n >= 2 and not np.all(np.diff(self.t_s) > 0):
            raise FlightLogError(f"{where}: t_s is not strictly increasing")

    @property
    def n_samples(self) -> int:
        """Number of time samples."""
        return int(self.t_s.shape[0])

    @property
    def duration_s(self) -> float:
        """Flight duration in seconds."""
        return float(self.t_s[-1] - self.t_s[0]) if self.n_samples else 0.0

    @property
    def name(self) -> str:
        """Human-readable flight name (from the metadata)."""
        return str(self.meta.get("name", "flight"))

    def slice(self, start: int, stop: int) -> FlightLog:
        """Samples ``start:stop`` as a new FlightLog."""
        kwargs = {k: getattr(self, k)[start:stop] for k in FIELDS}
        extra = {k: v[start:stop] for k, v in self.extra.items()}
        return replace(self, **kwargs, extra=extra)


def save_flightlogs(path: str | Path, logs: list[FlightLog]) -> Path:
    """Write ``logs`` to ``path`` (``.npz``) atomically: a failure leaves any old file intact.

    ``.npz`` is added to a name without it; a ``path`` that exists and is not a regular file
    (``/dev/null``, a FIFO, a folder) is refused as given, before the suffix is added.

    Raises:
        OSError: ``path`` is not a regular file, or the write failed.
    """
    path = check_writable_target(path)  # /dev/null must not become /dev/null.npz
    if path.suffix != ".npz":
        path = path.with_suffix(path.suffix + ".npz") if path.suffix else path.with_suffix(".npz")
    arrays: dict[str, np.ndarray] = {
        "format": np.array(FORMAT_NAME),
        "version": np.array(FORMAT_VERSION),
        "n_flights": np.array(len(logs)),
    }
    for i, log in enumerate(logs):
        arrays[f"f{i}/meta"] = np.array(json.dumps(log.meta, default=json_default))
        for name in FIELDS:
            arrays[f"f{i}/{name}"] = getattr(log, name)
        for key, arr in log.extra.items():
            arrays[f"f{i}/extra/{key}"] = np.asarray(arr)
    with atomic_open(path, "wb") as fh:
        np.savez_compressed(fh, **arrays)
    return path


def _meta(data: Any, key: str, path: Path) -> dict[str, Any]:
    """The JSON metadata of one flight, which must be a JSON object."""
    value = data[key]
    if value.shape != () or value.dtype.kind != "U":
        raise FlightLogError(f"{path}: {key} must be one JSON string")
    try:
        meta = json.loads(str(value))
    except RecursionError:
        raise FlightLogError(f"{path}: {key} is nested too deeply") from None
    except json.JSONDecodeError as err:
        raise FlightLogError(f"{path}: {key} is not valid JSON ({err})") from None
    if not isinstance(meta, dict):
        raise FlightLogError(f"{path}: {key} must be a JSON object, got {type(meta).__name__}")
    return meta


def load_flightlogs(path: str | Path) -> list[FlightLog]:
    """Read every flight in an aerodock FlightLog file.

    Raises:
        FlightLogError: missing file, not an aerodock FlightLog, newer version, or bad contents
            (one line naming the file).
    """
    path = Path(path)
    try:
        with open_input(path, "FlightLog file", MAX_NPZ_BYTES) as fh, \
                np.load(fh, allow_pickle=False) as data:
            keys = check_npz_header(data, path, FORMAT_NAME, FORMAT_VERSION, "FlightLog",
                                    FlightLogError)
            n_flights = npz_int(data, "n_flights", path, FlightLogError)
            if not 0 <= n_flights <= len(keys):
                raise FlightLogError(f"{path}: n_flights = {n_flights} does not match the file")
            logs = []
            for i in range(n_flights):
                missing = [n for n in (*FIELDS, "meta") if f"f{i}/{n}" not in keys]
                if missing:
                    raise FlightLogError(f"{path}: flight {i} lacks {', '.join(missing)}")
                meta = _meta(data, f"f{i}/meta", path)
                meta.setdefault("name", f"{path.stem}[{i}]")
                prefix = f"f{i}/extra/"
                extra = {k[len(prefix):]: data[k] for k in keys if k.startswith(prefix)}
                arrays = {n: data[f"f{i}/{n}"] for n in FIELDS}
                for name, arr in arrays.items():
                    if arr.dtype.kind not in "fiu":
                        raise FlightLogError(f"{path}: flight {i} {name} is not numeric "
                                             f"({arr.dtype})")
                logs.append(FlightLog(**arrays, meta=meta, extra=extra))
            return logs
    except FileNotFoundError:
        raise FlightLogError(f"{path}: file not found") from None
    except IsADirectoryError:
        raise FlightLogError(f"{path}: is a folder, not a FlightLog file") from None
    except FlightLogError:
        raise
    except InputError as err:
        raise FlightLogError(str(err)) from None
    except MemoryError:
        raise FlightLogError(f"{path}: too large to read into memory") from None
    except READ_ERRORS as err:
        raise FlightLogError(f"{path}: corrupt or unreadable FlightLog file "
                             f"({type(err).__name__}: {one_line(err)})") from None
