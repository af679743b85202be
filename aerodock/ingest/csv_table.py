"""Numeric CSV tables, as the log readers read them (:func:`read_csv_table`).

A process keeps the tables it has parsed, by their text (:data:`PARSED_CACHE_BYTES` of them, the
least recently read dropped first): reading the same files again (``reproduce`` reads the
Neural-Swarm flights three times, a study or a test suite more) costs their reading and hashing,
not their parsing. The text is the key, so a file that changed is parsed again whatever its
name, size or time stamp; each caller gets its own copy of the arrays.
"""

from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from aerodock.fileio import MAX_CSV_BYTES, read_input_text
from aerodock.ingest.common import input_errors
from aerodock.ingest.errors import IngestError

PARSED_CACHE_BYTES = 128 * 2**20
"""How much a process keeps of the tables it parsed, bytes: each table's arrays, comments and
column names, an eighth of its text (the key's share) and 1 kB (the 38 shared Neural-Swarm files
count for 24 MB)."""


@dataclass(frozen=True)
class CsvTable:
    """A numeric CSV file: column names, data ``(rows, columns)`` and each row's line number."""

    path: Path
    columns: list[str]
    data: np.ndarray
    lines: np.ndarray
    comments: list[str]

    def column(self, name: str) -> np.ndarray:
        """The values of column ``name``."""
        return self.data[:, self.columns.index(name)]


_PARSED: OrderedDict[tuple[bool, bytes], tuple[CsvTable, int]] = OrderedDict()
_HELD = [0]  # bytes the kept tables count for
_LOCK = threading.Lock()
_ENTRY_BYTES = 1024  # what a kept table counts for beyond its arrays and text


def _size(parsed: CsvTable, text: str) -> int:
    """What keeping ``parsed`` (read from ``text``) counts for, bytes."""
    return parsed.data.nbytes + parsed.lines.nbytes + len(text) // 8 + _ENTRY_BYTES + sum(
        len(c) for c in parsed.comments) + sum(len(c) for c in parsed.columns)


def _remember(key: tuple[bool, bytes], parsed: CsvTable, size: int) -> bool:
    """Keep ``parsed`` under ``key`` (``size``: :func:`_size`), dropping the least recently read
    tables beyond :data:`PARSED_CACHE_BYTES`; False if it is too large to keep."""
    if size > PARSED_CACHE_BYTES:
        return False
    with _LOCK:
        old = _PARSED.pop(key, None)
        if old is not None:
            _HELD[0] -= old[1]
        _PARSED[key] = (parsed, size)
        _HELD[0] += size
        while _HELD[0] > PARSED_CACHE_BYTES:
            _, (_, dropped) = _PARSED.popitem(last=False)
            _HELD[0] -= dropped
    return True


def read_csv_table(path: Path, *, header_in_comment: bool) -> CsvTable:
    """Read a comma-separated numeric table with one header line (NumPy's reader for plain
    numbers, Python's ``csv`` module for quoted fields and to name a fault; a table read before
    in this process is not parsed again: the module docstring).

    Fields may be quoted (``"t_s","leader_x_m"``); a UTF-8 byte-order mark is dropped; lines
    starting with ``#`` are comments. The file must be a regular file of at most
    :data:`aerodock.fileio.MAX_CSV_BYTES` (a FIFO or a device is refused unread).

    Args:
        path: The file.
        header_in_comment: The header is the first line starting with ``#`` (Neural-Swarm);
            otherwise it is the first line that is not a ``#`` comment.

    Raises:
        IngestError: unreadable, non-regular, too large or empty file, no header, no data
            rows, rows with a different number of fields than the header (naming the line), or a
            field that is not a number.
    """
    where = str(path)
    with input_errors(where, "cannot read file"):
        text = read_input_text(path, "CSV file", MAX_CSV_BYTES, encoding="utf-8-sig",
                               errors="replace")
    if not text.strip():
        raise IngestError(where, "empty file")
    key = (header_in_comment, hashlib.blake2b(text.encode("utf-8", "surrogatepass"),
                                              digest_size=20).digest())
    with _LOCK:
        kept = _PARSED.get(key)
        if kept is not None:
            _PARSED.move_to_end(key)
    if kept is not None:
        table = kept[0]
    else:
        table = _parse(path, text, header_in_comment)
        if not _remember(key, table, _size(table, text)):  # not kept: the caller's own
            return table
    return CsvTable(path, list(table.columns), table.data.copy(), table.lines.copy(),
                    list(table.comments))


def _parse(path: Path, text: str, header_in_comment: bool) -> CsvTable:
    """The table in ``text``, read from ``path`` (the reading of :func:`read_csv_table`)."""
    import csv

    where = str(path)

    def fields_of(line: str, number: int) -> list[str]:
        try:
            return next(csv.reader([line], skipinitialspace=True))
        except (csv.Error, StopIteration) as err:
            raise IngestError(where, f"line {number}: not CSV ({err})") from None

    header: list[str] | None = None
    comments: list[str] = []
    body: list[str] = []  # the data lines, stripped
    line_numbers: list[int] = []
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip().lstrip("\ufeff")
        if not line:
            continue
        if line.startswith("#"):
            if header is None and header_in_comment:
                header = [c.strip() for c in fields_of(line.lstrip("#").strip(), number)]
            else:
                comments.append(line[1:].strip())
            continue
        if header is None:
            if header_in_comment:
                raise IngestError(where, "no header line: expected a first line starting with "
                                         "'#' that names the columns")
            header = [c.strip() for c in fields_of(line, number)]
            continue
        body.append(line)
        line_numbers.append(number)
    if header is None:
        raise IngestError(where, "no header line naming the columns")
    if not body:
        raise IngestError(where, "empty: a header but no data rows")
    data = _numeric_rows(body, len(header)) if not any('"' in line for line in body) else None
    if data is None:  # quoted fields, or a fault to name: field by field
        data = _checked_rows(where, header, body, line_numbers, fields_of)
    return CsvTable(path, header, data, np.array(line_numbers), comments)


def _numeric_rows(lines: list[str], columns: int) -> np.ndarray | None:
    """Unquoted numeric CSV lines as ``(rows, columns)`` floats, parsed by NumPy's reader (the
    numbers Python's ``float`` reads; the shared Neural-Swarm files in about half the time of
    ``csv`` and ``np.array`` of strings); None where a line is ragged or a field is not a
    number, for :func:`_checked_rows` to name it, and where the two readers differ: NumPy trims
    ``\\x1f`` around a number as white space (``float`` does not), and ``csv`` refuses a field
    longer than its limit."""
    import csv

    if any("\x1f" in line for line in lines) or max(map(len, lines)) > csv.field_size_limit():
        return None
    try:
        data = np.loadtxt(lines, delimiter=",", dtype=float, ndmin=2, comments=None,
                          quotechar=None)
    except ValueError:
        return None
    return data if data.shape == (len(lines), columns) else None


def _checked_rows(where: str, header: list[str], lines: list[str], numbers: list[int],
                  fields_of: Callable[[str, int], list[str]]) -> np.ndarray:
    """The data lines field by field (Python's ``csv``: quoted fields), raising an IngestError
    that names the first ragged line, else the first field that is not a number."""
    rows = []
    for line, number in zip(lines, numbers, strict=True):
        fields = fields_of(line, number)
        if len(fields) != len(header):
            raise IngestError(where, f"line {number} has {len(fields)} fields, the header has "
                                     f"{len(header)} (truncated or ragged file?)")
        rows.append(fields)
    try:
        return np.array(rows, dtype=float)
    except ValueError:
        for fields, number in zip(rows, numbers, strict=True):
            for name, value in zip(header, fields, strict=True):
                try:
                    float(value)
                except ValueError:
                    raise IngestError(
                        where, f"line {number}: column {name!r} holds {value.strip()!r}, "
                        f"not a number"
                    ) from None
        raise
