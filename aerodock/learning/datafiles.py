"""Data set files: reading and writing ``.npz`` data sets, and loading data from paths.

A data set file (``.npz``, written atomically, read with ``allow_pickle=False``) holds the keys
``format`` (the string ``"aerodock-dataset"``), ``version`` (1), ``x``, ``leader_R``, ``y``,
``flight_id``, ``t_s``, optionally ``y_true_mean``, ``y_torque`` and ``y_torque_true``, and
``meta`` (a JSON string): the arrays and metadata of a :class:`~aerodock.learning.dataset.Dataset`.
:func:`load_data_paths` takes FlightLog files, data set files and folders of them.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np

from aerodock.fileio import (
    MAX_NPZ_BYTES,
    READ_ERRORS,
    InputError,
    atomic_open,
    check_npz_header,
    one_line,
    open_input,
)
from aerodock.flightlog import FORMAT_NAME as FLIGHTLOG_FORMAT
from aerodock.flightlog import FlightLog, FlightLogError, load_flightlogs
from aerodock.learning.dataset import (
    OPTIONAL_ARRAYS,
    OPTIONAL_SCALARS,
    DataError,
    Dataset,
    build_dataset,
    concat_datasets,
)

DATASET_FORMAT = "aerodock-dataset"
DATASET_VERSION = 1


def save_dataset(path: str | Path, ds: Dataset) -> Path:
    """Write ``ds`` to ``path`` (``.npz``) atomically: a failure leaves any old file intact."""
    path = Path(path)
    if path.suffix != ".npz":
        path = path.with_name(path.name + ".npz")
    arrays: dict[str, np.ndarray] = {
        "format": np.array(DATASET_FORMAT),
        "version": np.array(DATASET_VERSION),
        "x": ds.x, "leader_R": ds.leader_R, "y": ds.y, "flight_id": ds.flight_id, "t_s": ds.t_s,
        "meta": np.array(json.dumps(ds.meta)),
    }
    for name in OPTIONAL_ARRAYS + OPTIONAL_SCALARS:
        if getattr(ds, name) is not None:
            arrays[name] = getattr(ds, name)
    with atomic_open(path, "wb") as fh:
        np.savez_compressed(fh, **arrays)
    return path


def _npz_format(path: Path) -> str | None:
    """The ``format`` string of an npz file, or None (raises DataError if unreadable)."""
    try:
        with open_input(path, "data file", MAX_NPZ_BYTES) as fh, \
                np.load(fh, allow_pickle=False) as data:
            return str(data["format"]) if "format" in data.files else None
    except FileNotFoundError:
        raise DataError(f"{path}: file not found") from None
    except InputError as err:
        raise DataError(str(err)) from None
    except (*READ_ERRORS, MemoryError) as err:
        raise DataError(f"{path}: not a readable .npz file ({type(err).__name__}: "
                        f"{one_line(err)})") from None


def load_dataset(path: str | Path) -> Dataset:
    """Read a dataset file written by :func:`save_dataset`.

    Raises:
        DataError: missing, corrupt, not a dataset, newer version, or inconsistent contents.
    """
    path = Path(path)
    try:
        with open_input(path, "dataset file", MAX_NPZ_BYTES) as fh, \
                np.load(fh, allow_pickle=False) as data:
            keys = check_npz_header(data, path, DATASET_FORMAT, DATASET_VERSION, "dataset",
                                    DataError)
            missing = [k for k in ("x", "leader_R", "y", "flight_id", "t_s", "meta")
                       if k not in keys]
            if missing:
                raise DataError(f"{path}: dataset lacks {', '.join(missing)}")
            arrays = {k: data[k] for k in ("x", "leader_R", "y", "flight_id", "t_s")}
            optional = {k: data[k] for k in OPTIONAL_ARRAYS + OPTIONAL_SCALARS if k in keys}
            meta = json.loads(str(data["meta"]))
    except FileNotFoundError:
        raise DataError(f"{path}: file not found") from None
    except DataError:
        raise
    except InputError as err:
        raise DataError(str(err)) from None
    except (*READ_ERRORS, MemoryError) as err:
        raise DataError(f"{path}: corrupt or unreadable dataset file ({type(err).__name__}: "
                        f"{one_line(err)})") from None
    for name, arr in {**arrays, **optional}.items():
        if arr.dtype.kind not in ("iu" if name == "flight_id" else "fiu"):
            raise DataError(f"{path}: {name} has dtype {arr.dtype}, not numbers")
    for name in ("x", "leader_R", "y", "t_s"):
        if not np.all(np.isfinite(arrays[name])):
            raise DataError(f"{path}: {name} contains NaN or infinite values")
    if not isinstance(meta, dict):
        raise DataError(f"{path}: dataset metadata is not a JSON object")
    try:
        ds = Dataset(**arrays, **optional, meta=meta)
    except DataError as err:
        raise DataError(f"{path}: {str(err).removeprefix('dataset: ')}") from None
    except (TypeError, ValueError, AttributeError, KeyError, IndexError) as err:
        raise DataError(f"{path}: inconsistent dataset contents or metadata "
                        f"({type(err).__name__}: {one_line(err)})") from None
    return ds


def load_data_paths(
    paths: Sequence[str | Path],
    *,
    free_air_radius_m: float | None = None,
    lowpass_hz: float | None = None,
) -> Dataset:
    """One Dataset from FlightLog files, dataset files and folders of them.

    Each path is a FlightLog file (``format == "aerodock-flightlog"``), a dataset file
    (``"aerodock-dataset"``), or a folder, searched recursively for ``*.npz`` files of either
    kind (hidden files are skipped, and so are other ``.npz`` files such as a model's
    ``weights.npz``: they are listed in ``meta["skipped_files"]``). A file given twice is read
    once. All FlightLogs are labelled together (so flights without free-air samples can borrow
    the others' bias), then joined with the loaded datasets.

    Raises:
        DataError: a missing path, a folder without FlightLog or dataset files, an unreadable
            file, or a file given explicitly that is neither kind (one line, naming the file).
    """
    if not paths:
        raise DataError("no data paths given")
    logs: list[FlightLog] = []
    datasets: list[Dataset] = []
    sources: list[str] = []
    skipped: list[str] = []
    seen: dict[Path, bool] = {}  # resolved path -> is an aerodock FlightLog/dataset file
    for raw in paths:
        path = Path(raw)
        if path.is_dir():
            files = sorted(
                p for p in path.rglob("*.npz")
                if not any(part.startswith(".") for part in p.relative_to(path).parts)
            )
        elif path.exists():
            files = [path]
        else:
            raise DataError(f"{path}: no such file or folder")
        n_used = 0
        for file in files:
            key = file.resolve()
            if key in seen:
                n_used += seen[key]
                continue
            fmt = _npz_format(file)
            seen[key] = fmt in (FLIGHTLOG_FORMAT, DATASET_FORMAT)
            if not seen[key] and path.is_dir():
                skipped.append(str(file))
                continue
            n_used += 1
            if fmt == FLIGHTLOG_FORMAT:
                try:
                    logs.extend(load_flightlogs(file))
                except FlightLogError as err:
                    raise DataError(str(err)) from None
            elif fmt == DATASET_FORMAT:
                datasets.append(load_dataset(file))
            else:
                raise DataError(f"{file}: not an aerodock FlightLog or dataset file")
            sources.append(str(file))
        if path.is_dir() and not n_used:
            raise DataError(f"{path}: folder holds no FlightLog or dataset .npz files")
    if logs:
        try:
            datasets.insert(0, build_dataset(
                logs, free_air_radius_m=free_air_radius_m, lowpass_hz=lowpass_hz
            ))
        except (FlightLogError, ValueError) as err:
            raise DataError(str(err)) from None
    ds = concat_datasets(datasets)
    return replace(ds, meta={**ds.meta, "files": sources, "skipped_files": skipped})
