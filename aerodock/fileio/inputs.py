"""Reading inputs: regular files only, of bounded size; strict TOML; guarded ``.npz`` headers.

* :func:`check_input_file`, :func:`open_input`, :func:`read_input_bytes`,
  :func:`read_input_text` -- every input is a regular file (a FIFO or a device is refused before
  it is opened, so nothing blocks or reads for ever) of bounded size.
* :func:`read_toml` -- a TOML file parsed; every failure is one line naming the file.
* :func:`check_npz_header` -- the ``format``/``version`` keys of an aerodock ``.npz`` file and
  the sizes its members declare, checked before any array is read.
* :func:`one_line` -- an error's message as one line.
"""

from __future__ import annotations

import math
import os
import stat
import struct
import tokenize
import tomllib
import zipfile
import zlib
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Any

import numpy as np

# Largest uncompressed ``.npz`` aerodock reads (all members together): an hour of two-vehicle
# flight at 100 Hz is about 100 MB, so this leaves room while refusing files that declare
# terabytes (a corrupt or hostile header would otherwise make NumPy allocate before reading).
MAX_NPZ_BYTES = 4 * 1024**3
# What reading a damaged zip/npy member can raise (zlib, zipfile, NumPy's header parser).
READ_ERRORS: tuple[type[BaseException], ...] = (
    zipfile.BadZipFile, zlib.error, EOFError, OSError, ValueError, KeyError, TypeError,
    NotImplementedError, RuntimeError, OverflowError, UnicodeError, struct.error,
    SyntaxError, tokenize.TokenError, RecursionError,
)


def one_line(err: BaseException | str, *, first_line: bool = False) -> str:
    """The text of an error (or a string) as one line; the type name if it has no text.

    Every run of whitespace (newlines included) becomes one space; with ``first_line`` the
    first line of the text is kept as written instead (the messages of ``train``, ``evaluate``
    and ``export``, which show a path with two spaces in it as it is).
    """
    if first_line:
        text = str(err).strip()
        text = text.splitlines()[0] if text else ""
    else:
        text = " ".join(str(err).split())
    return text or (type(err).__name__ if isinstance(err, BaseException) else "")


def npz_int(data: Any, key: str, path: Path, error: type[Exception]) -> int:
    """An integer scalar stored under ``key`` in an opened ``.npz`` (e.g. ``version``).

    Raises ``error`` naming ``path`` if it is missing or is not one integer.
    """
    if key not in data.files:
        raise error(f"{path}: '{key}' missing")
    value = data[key]
    if value.shape != () or value.dtype.kind not in "iu":
        raise error(f"{path}: '{key}' must be one integer, got {value.dtype} {value.shape}")
    return int(value)


def check_npz_sizes(data: Any, path: Path, error: type[Exception],
                    max_bytes: int = MAX_NPZ_BYTES) -> None:
    """Check the sizes every member of an opened ``.npz`` declares, before reading any of them.

    Each ``.npy`` header's shape and dtype must fit in the member's stored size, and all members
    together in ``max_bytes``; object arrays are refused. Raises ``error`` naming ``path``.
    """
    zf: zipfile.ZipFile | None = getattr(data, "zip", None)
    if zf is None:
        return
    total = 0
    for info in zf.infolist():
        total += info.file_size
        if total > max_bytes:
            raise error(f"{path}: holds more than {max_bytes / 1024**3:.0f} GiB uncompressed "
                        "(the limit aerodock reads)")
        if not info.filename.endswith(".npy"):
            continue
        try:
            with zf.open(info) as fh:
                version = np.lib.format.read_magic(fh)
                if version == (1, 0):
                    shape, _, dtype = np.lib.format.read_array_header_1_0(fh)
                else:
                    shape, _, dtype = np.lib.format.read_array_header_2_0(fh)
                header_bytes = fh.tell()
        except READ_ERRORS as err:
            raise error(f"{path}: corrupt member {info.filename} "
                        f"({type(err).__name__}: {one_line(err)})") from None
        if dtype.hasobject:
            raise error(f"{path}: member {info.filename} holds Python objects (not allowed)")
        declared = math.prod(shape) * dtype.itemsize
        if declared > info.file_size - header_bytes:
            raise error(f"{path}: member {info.filename} declares {declared} bytes but holds "
                        f"{info.file_size - header_bytes} (corrupt file)")


def check_npz_header(data: Any, path: Path, format_name: str, max_version: int, what: str,
                     error: type[Exception]) -> set[str]:
    """Check an opened ``.npz``'s ``format`` and ``version`` keys and its members' sizes.

    Returns its key set. Raises ``error`` with a one-line message naming ``path`` for a foreign
    or newer file, or for members whose declared sizes do not fit the file.
    """
    check_npz_sizes(data, path, error)
    keys = set(data.files)
    if "format" not in keys:
        raise error(f"{path}: not an aerodock {what} file")
    fmt = data["format"]
    if fmt.shape != () or fmt.dtype.kind != "U" or str(fmt) != format_name:
        raise error(f"{path}: not an aerodock {what} file")
    version = npz_int(data, "version", path, error)
    if version < 1:
        raise error(f"{path}: bad {what} format version {version}")
    if version > max_version:
        raise error(f"{path}: {what} format version {version} is newer than this aerodock "
                    f"({max_version}); upgrade aerodock")
    return keys


def read_toml(path: str | Path, what: str, error: type[Exception]) -> dict[str, Any]:
    """Parse the TOML file at ``path``; every failure is one ``error`` naming the file.

    The file must be a regular file of at most :data:`MAX_TOML_BYTES` (a FIFO, a device such
    as ``/dev/zero`` or a huge file is refused before it is read; see :func:`read_input_text`).

    Args:
        path: the file.
        what: what the file is, for the messages (e.g. ``"config file"``).
        error: the exception class to raise (a ``ValueError`` subclass of the caller's).
    """
    try:
        return tomllib.loads(read_input_text(path, what, MAX_TOML_BYTES))
    except FileNotFoundError:
        raise error(f"{path}: {what} not found") from None
    except InputError as err:
        raise error(str(err)) from None
    except (OSError, UnicodeDecodeError) as err:
        raise error(f"{path}: cannot read {what} ({err})") from None
    except tomllib.TOMLDecodeError as err:
        raise error(f"{path}: invalid TOML ({err})") from None
    except RecursionError:
        raise error(f"{path}: invalid TOML (nested too deeply)") from None


# --------------------------------------------------------------------------------------------
# Reading inputs: regular files only, and only so many bytes
# --------------------------------------------------------------------------------------------

MAX_TOML_BYTES = 1024**2
"""Largest TOML input (a config, fault file, topic mapping or sweep specification): these are a
few kilobytes; a megabyte leaves room and parses in well under a second."""
MAX_CSV_BYTES = 256 * 1024**2
"""Largest CSV flight log (about an hour of two-vehicle flight at 100 Hz in the generic schema;
parsing holds several times its size in memory)."""
MAX_JSON_BYTES = 16 * 1024**2
"""Largest JSON document read (a model directory's ``model.json``)."""
_CHUNK = 1024**2


class InputError(ValueError):
    """An input path that cannot be read as one: not a regular file, or too large.

    The message is one line, ``PATH: reason``; ``path`` and ``reason`` are kept apart for
    callers whose errors name the file themselves.
    """

    def __init__(self, path: str | Path, reason: str) -> None:
        self.path = str(path)
        self.reason = reason
        super().__init__(f"{path}: {reason}")

    def __reduce__(self) -> tuple:
        # rebuilt from its two parts (an error raised on a worker process reaches the driver)
        return (type(self), (self.path, self.reason))


def _size_text(n_bytes: int) -> str:
    for unit, size in (("GiB", 1024**3), ("MiB", 1024**2), ("KiB", 1024)):
        if n_bytes >= size:
            return f"{n_bytes / size:g} {unit}"
    return f"{n_bytes} bytes"


def _check_input_mode(path: str | Path, mode: int, what: str) -> None:
    if stat.S_ISDIR(mode):
        raise InputError(path, f"is a folder, not a {what}")
    if not stat.S_ISREG(mode):
        raise InputError(path, f"not a regular file (a FIFO, device or socket); refusing to "
                               f"read it as a {what}")


def check_input_file(path: str | Path, what: str = "file", max_bytes: int | None = None) -> int:
    """Refuse an input path that is not a regular file, or holds more than ``max_bytes``.

    Checked with ``os.stat`` before anything opens the file, so a FIFO (which would block the
    reader for ever), a device such as ``/dev/zero`` (endless) or a folder is refused at once.

    Args:
        path: the input.
        what: what the file is, for the message (``"config file"``).
        max_bytes: the largest size accepted (None: any).

    Returns:
        The file's size in bytes.

    Raises:
        FileNotFoundError: ``path`` does not exist.
        InputError: ``path`` is not a regular file, or is larger than ``max_bytes``.
    """
    st = os.stat(path)
    _check_input_mode(path, st.st_mode, what)
    if max_bytes is not None and st.st_size > max_bytes:
        raise InputError(path, f"{what} is {_size_text(st.st_size)}, more than the "
                               f"{_size_text(max_bytes)} aerodock reads")
    return st.st_size


@contextmanager
def open_input(path: str | Path, what: str = "file",
               max_bytes: int | None = None) -> Iterator[IO[bytes]]:
    """Open a regular input file for binary reading, never blocking on a FIFO.

    The path is checked with :func:`check_input_file`, then opened with ``O_NONBLOCK`` (a FIFO
    swapped in after the check does not block the open) and checked again on the open
    descriptor, so what is read is the regular file that was checked.

    Raises:
        FileNotFoundError: ``path`` does not exist.
        InputError: not a regular file, or larger than ``max_bytes``.
        OSError: it cannot be opened.
    """
    check_input_file(path, what, max_bytes)
    fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    try:
        st = os.fstat(fd)
        _check_input_mode(path, st.st_mode, what)
        os.set_blocking(fd, True)
        fh = os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise
    with fh:
        yield fh


def read_input_bytes(path: str | Path, what: str = "file", max_bytes: int = MAX_NPZ_BYTES) -> bytes:
    """The bytes of a regular input file of at most ``max_bytes`` (see :func:`open_input`).

    The size is checked before reading and again while reading (a file that grows, or a file
    whose size the system does not report, such as one under ``/proc``, is cut off at the limit
    and refused), so no more than ``max_bytes + 1`` bytes are ever held.

    Raises:
        FileNotFoundError: ``path`` does not exist.
        InputError: not a regular file, or larger than ``max_bytes``.
        OSError: it cannot be read.
    """
    chunks: list[bytes] = []
    total = 0
    with open_input(path, what, max_bytes) as fh:
        while True:
            chunk = fh.read(min(_CHUNK, max_bytes + 1 - total))
            if not chunk:
                break
            chunks.append(chunk)
            total += len(chunk)
            if total > max_bytes:
                raise InputError(path, f"{what} is more than the {_size_text(max_bytes)} "
                                       "aerodock reads")
    return b"".join(chunks)


def read_input_text(path: str | Path, what: str = "file", max_bytes: int = MAX_TOML_BYTES,
                    encoding: str = "utf-8", errors: str = "strict") -> str:
    """The text of a regular input file of at most ``max_bytes`` (see :func:`read_input_bytes`).

    Raises:
        FileNotFoundError: ``path`` does not exist.
        InputError: not a regular file, or larger than ``max_bytes``.
        UnicodeDecodeError: not text in ``encoding`` (with ``errors="strict"``).
        OSError: it cannot be read.
    """
    return read_input_bytes(path, what, max_bytes).decode(encoding, errors)
