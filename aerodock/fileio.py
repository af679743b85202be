"""Atomic file writes: a failure (or an interrupt) never leaves a half-written file behind."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Any

import numpy as np


@contextmanager
def atomic_open(path: str | Path, mode: str = "wb", suffix: str = ".tmp") -> Iterator[IO[Any]]:
    """Open a temporary file beside ``path``; on success it replaces ``path`` in one step.

    Any existing file at ``path`` stays untouched until the new one is complete; on an error
    the temporary file is removed and the error propagates.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=suffix)
    try:
        with os.fdopen(fd, mode) as fh:
            yield fh
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def json_default(obj: Any) -> Any:
    """``json.dumps(default=...)`` for NumPy scalars and arrays and paths."""
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def check_npz_header(data: Any, path: Path, format_name: str, max_version: int, what: str,
                     error: type[Exception]) -> set[str]:
    """Check an opened ``.npz``'s ``format`` and ``version`` keys; returns its key set.

    Raises ``error`` with a one-line message naming ``path`` for a foreign or newer file.
    """
    keys = set(data.files)
    if "format" not in keys or str(data["format"]) != format_name:
        raise error(f"{path}: not an aerodock {what} file")
    version = int(data["version"])
    if version > max_version:
        raise error(f"{path}: {what} format version {version} is newer than this aerodock "
                    f"({max_version}); upgrade aerodock")
    return keys
