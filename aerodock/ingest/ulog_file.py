"""Reading a PX4 ULog file with pyulog, within a budget of bytes read (a corrupt file cannot
make the reader loop for ever); :mod:`aerodock.ingest.ulog` maps what it read to FlightLogs."""

from __future__ import annotations

import contextlib
import io
import struct
import warnings
from pathlib import Path
from typing import Any

from aerodock.fileio import InputError, check_input_file
from aerodock.ingest.errors import IngestError, ingest_warning

READ_BUDGET_FACTOR = 64
"""A ULog may be read at most this many times its size (plus :data:`READ_BUDGET_EXTRA_BYTES`).
pyulog reads a sound file once; its resynchronisation after corrupt bytes re-reads some; on a
truncated file whose last message claims more bytes than remain, its definitions loop seeks back
further than it read and never ends (found by tools/audit.py)."""
READ_BUDGET_EXTRA_BYTES = 64 << 20


class _BoundedReader:
    """A binary file for pyulog that raises ``error`` once more than the budget was read."""

    def __init__(self, raw: Any, size: int, error: type[Exception]) -> None:
        self._raw, self._error = raw, error
        self._left = READ_BUDGET_FACTOR * size + READ_BUDGET_EXTRA_BYTES

    def read(self, n: int = -1) -> bytes:
        data = self._raw.read(n)
        self._left -= max(len(data), 1)
        if self._left < 0:
            raise self._error("its messages loop back on themselves (corrupt or truncated)")
        return data

    def seek(self, offset: int, whence: int = 0) -> int:
        return self._raw.seek(offset, whence)

    def tell(self) -> int:
        return self._raw.tell()

    def close(self) -> None:
        self._raw.close()


def load_ulog(path: Path, topics: tuple[str, ...]) -> Any:
    """The ULog at ``path`` (pyulog's ``ULog``) with only ``topics`` read, within the read
    budget; a corrupt-message note as a warning.

    Raises:
        IngestError: no pyulog, no file, an empty, unreadable or looping file.
    """
    try:
        from pyulog import ULog
        from pyulog.exceptions import ULogException
    except ImportError:  # pragma: no cover - the ingest extra is not installed
        raise IngestError(path, "reading ULog needs pyulog: pip install 'aerodock[ingest]'") \
            from None
    try:
        size = check_input_file(path, "ULog file")
    except FileNotFoundError:
        raise IngestError(path, "file not found") from None
    except InputError as err:
        raise IngestError(path, err.reason) from None
    if size == 0:
        raise IngestError(path, "empty file")
    sink = io.StringIO()  # pyulog prints corruption notes; keep them off the user's terminal
    try:
        with contextlib.redirect_stdout(sink), open(path, "rb") as raw:
            reader = _BoundedReader(raw, size, ULogException)
            ulog = ULog(reader, message_name_filter_list=list(topics))
    except ULogException as err:
        raise IngestError(path, f"not a readable ULog file ({err})") from None
    except (OSError, ValueError, IndexError, KeyError, struct.error, UnicodeDecodeError) as err:
        raise IngestError(path, f"corrupt ULog file ({type(err).__name__}: {err})") from None
    if ulog.file_corruption:
        warnings.warn(ingest_warning(path, "pyulog reports corrupt messages; they were skipped"),
                      stacklevel=3)
    return ulog
