"""Real-flight-log readers: every source becomes a :class:`aerodock.flightlog.FlightLog`.

Formats (see ``aerodock/ingest/README.md``):

- ``neural-swarm``: the public Neural-Swarm Crazyflie CSV files, ``cfXX_NN.csv`` (one per vehicle
  per flight, paired by ``NN``; two FlightLogs per flight, one per follower);
- ``csv``: the generic CSV schema of :mod:`aerodock.ingest.csv_generic`, one file per flight;
- ``rosbag``: ROS 2 bags (``.db3``, ``.mcap`` or a bag folder) with a topic mapping;
- ``ulog``: PX4 ULog files, one vehicle per file, given as LEADER FOLLOWER pairs (or ``single``).

Example::

    from aerodock.ingest import read_logs
    logs = read_logs("neural-swarm", [Path("data/swap_ss")], vehicle="small")

Every bad input raises :class:`IngestError` with a one-line ``FILE: problem`` message; remarks
that do not stop reading are :class:`IngestWarning` warnings.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from pathlib import Path
from typing import Any

from aerodock.flightlog import FlightLog
from aerodock.ingest.common import check_bag_folder, check_regular_input
from aerodock.ingest.errors import IngestError, IngestWarning

FORMATS = ("neural-swarm", "csv", "rosbag", "ulog")
_SUFFIXES = {"neural-swarm": (".csv",), "csv": (".csv",), "ulog": (".ulg",),
             "rosbag": (".db3", ".mcap")}

__all__ = ["FORMATS", "IngestError", "IngestWarning", "expand_paths", "read_logs"]


def _is_bag_dir(path: Path) -> bool:
    return (path / "metadata.yaml").is_file()


def expand_paths(fmt: str, paths: list[Path]) -> list[Path]:
    """Files (or bag folders) of format ``fmt`` named by ``paths``; a folder gives its files.

    A folder is expanded to the files of the format directly inside it, sorted by name (for
    ``rosbag``: a folder with ``metadata.yaml`` is one bag; otherwise its bag folders and
    ``.db3``/``.mcap`` files). Duplicates are dropped, the order is kept.

    Raises:
        IngestError: unknown format, a path that does not exist, a file that is not a regular
            file (a FIFO, a device), or a folder without such files.
    """
    if fmt not in FORMATS:
        raise IngestError(fmt, f"unknown format; use one of {', '.join(FORMATS)}")
    if not paths:
        raise IngestError(fmt, "no input paths given")
    out: list[Path] = []
    for path in (Path(p) for p in paths):
        if not path.exists():
            raise IngestError(path, "no such file or folder")
        if path.is_dir() and fmt == "rosbag" and _is_bag_dir(path):
            check_bag_folder(path)
            out.append(path)
        elif path.is_dir():
            found = sorted(
                p for p in path.iterdir()
                if (p.is_file() and p.suffix.lower() in _SUFFIXES[fmt]
                    and not p.name.startswith("."))
                or (fmt == "rosbag" and p.is_dir() and _is_bag_dir(p))
            )
            if not found:
                kinds = " or ".join(_SUFFIXES[fmt]) + (" files or bag folders"
                                                       if fmt == "rosbag" else " files")
                raise IngestError(path, f"folder has no {kinds} for format {fmt}")
            for item in found:
                if item.is_dir():
                    check_bag_folder(item)
                else:
                    check_regular_input(item)
            out.extend(found)
        else:
            check_regular_input(path)
            out.append(path)
    seen: set[Path] = set()
    unique = []
    for path in out:
        key = path.resolve()
        if key not in seen:
            seen.add(key)
            unique.append(path)
    return unique


def _per_file(read_one: Callable[..., FlightLog]) -> Callable[..., list[FlightLog]]:
    """A reader of many files from a reader of one (one flight per file), with progress."""

    def read_all(paths: list[Path], *,
                 progress: Callable[[int, int], None] | None = None,
                 **options: Any) -> list[FlightLog]:
        logs = []
        within = "progress" in inspect.signature(read_one).parameters
        for i, path in enumerate(paths):
            if progress and within:  # finer steps inside a file (rosbag: messages read)
                options["progress"] = (lambda done, total, i=i: progress(
                    i + done / max(total, 1), len(paths)))
            logs.append(read_one(path, **options))
            if progress:
                progress(i + 1, len(paths))
        return logs

    # inspect.signature follows __wrapped__: read_logs checks options against read_one's.
    read_all.__wrapped__ = read_one  # type: ignore[attr-defined]
    return read_all


def _reader(fmt: str) -> Callable[..., list[FlightLog]]:
    if fmt == "neural-swarm":
        from aerodock.ingest.neural_swarm import read_neural_swarm
        return read_neural_swarm
    if fmt == "csv":
        from aerodock.ingest.csv_generic import read_csv
        return _per_file(read_csv)
    if fmt == "rosbag":
        from aerodock.ingest.rosbag import read_rosbag
        return _per_file(read_rosbag)
    from aerodock.ingest.ulog import read_ulog
    return read_ulog


def read_logs(fmt: str, paths: list[Path], *, progress: Callable[[int, int], None] | None = None,
              **options: Any) -> list[FlightLog]:
    """Read logs of format ``fmt`` from files or folders into FlightLogs (NED, SI).

    Args:
        fmt: One of :data:`FORMATS`.
        paths: Files or folders (a folder gives the files of that format inside it, sorted).
        progress: Called as ``progress(done, total)`` as files are read.
        **options: Reader options; ``None`` values are ignored. Per format:
            ``neural-swarm``: ``vehicle`` ("small", "large", "cf50=small,cf51=large"),
            ``mass_kg``, ``time_unit``, ``max_start_offset_s``, ``min_overlap_fraction``,
            ``max_gap_s``; ``csv``: ``frame``, ``mass_kg``; ``rosbag``: ``mapping`` (dict or TOML
            path), ``mass_kg``; ``ulog``: ``single``, ``mass_kg``, ``hover_thrust``,
            ``max_thrust_n``, ``leader_offset_m``, ``min_overlap_fraction``, ``max_gap_s``.

    Returns:
        The flights, in input order (Neural-Swarm: by folder and flight, two per flight).

    Raises:
        IngestError: an option that does not apply to the format, or any bad input (one line
            naming the file and the problem).
    """
    files = expand_paths(fmt, paths)
    reader = _reader(fmt)
    accepted = set(inspect.signature(reader).parameters) - {"paths", "progress"}
    given = {k: v for k, v in options.items() if v is not None and v is not False}
    unknown = sorted(set(given) - accepted)
    if unknown:
        names = ", ".join("--" + k.replace("_", "-") for k in unknown)
        raise IngestError(fmt, f"option {names} does not apply to this format")
    return reader(files, progress=progress, **given)
