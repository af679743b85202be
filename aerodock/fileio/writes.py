"""Atomic writes of files and folders.

* :func:`atomic_open` -- a failure (or an interrupt) never leaves a half-written file behind, and
  the new file gets the permissions an ordinary ``open`` would give it (the umask applies).
* :func:`write_dir_atomic` -- a directory of files replaced as a whole (a model directory): a
  kill at any moment leaves either the complete old directory or the complete new one; the
  temporary sibling a kill leaves is removed by the next such write in the same folder.
  :func:`building_dir` does the same for an output folder of several files and sub-folders.
  Both refuse an output folder given as a symbolic link (:func:`refuse_symlink`): the swap
  would replace the link, not the folder it points to. A link in a parent folder is followed.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import re
import shutil
import stat
import tempfile
import time
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Any

from aerodock.fileio.inputs import InputError

try:
    import fcntl
except ImportError:  # not POSIX
    fcntl = None  # type: ignore[assignment]

_TMP_SUFFIX = ".tmp"


def _umask() -> int:
    """The process's umask (read by setting it and putting it back)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def check_writable_target(path: str | Path) -> Path:
    """Refuse an output path that exists and is not a regular file (a FIFO, a device, a folder)
    or is a symbolic link (a file is replaced by renaming, which would replace the link itself
    and leave the file it points to as it was).

    Raises:
        IsADirectoryError: ``path`` is a folder.
        OSError: ``path`` is a symbolic link or another kind of non-regular file.
    """
    path = Path(path)
    if path.is_symlink():
        raise OSError(f"{path}: is a symbolic link; aerodock replaces an output file by "
                      "renaming and does not follow links: give the file it points to "
                      f"({os.path.realpath(path)}) or a new name")
    try:
        mode = path.stat().st_mode
    except FileNotFoundError:
        return path
    if stat.S_ISDIR(mode):
        raise IsADirectoryError(f"{path}: is a folder; give a file name")
    if not stat.S_ISREG(mode):
        raise OSError(f"{path}: not a regular file (a FIFO, device or socket); "
                      "refusing to replace it")
    return path


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def remove_stale_temps(path: str | Path) -> list[Path]:
    """Remove temporary files of :func:`atomic_open` for ``path`` left by killed processes.

    A process killed with SIGKILL cannot clean up; its temporary file names its process id, so
    the next write to the same path removes it once that process is gone. Returns the removed
    files.
    """
    path = Path(path)
    removed = []
    for tmp in path.parent.glob(f".{path.name}.*{_TMP_SUFFIX}"):
        pid_text = tmp.name[len(path.name) + 2:].split(".", 1)[0]
        if pid_text.isdigit() and not _pid_alive(int(pid_text)):
            tmp.unlink(missing_ok=True)
            removed.append(tmp)
    return removed


@contextmanager
def atomic_open(path: str | Path, mode: str = "wb", suffix: str = _TMP_SUFFIX,
                verify: Callable[[Path], None] | None = None) -> Iterator[IO[Any]]:
    """Open a temporary file beside ``path``; on success it replaces ``path`` in one step.

    Any existing file at ``path`` stays untouched until the new one is complete; on an error
    (or an interrupt) the temporary file is removed and the error propagates. The new file gets
    the mode of the file it replaces, or ``0o666`` less the umask. A ``path`` that exists but
    is not a regular file (a FIFO, a device node, a folder) is refused.

    Args:
        path: the file to write.
        mode: the open mode (``"wb"`` or ``"w"``).
        suffix: the temporary file's suffix.
        verify: called with the temporary file's path once it is complete and synced, before
            the rename: an exception it raises removes the file and propagates, so ``path``
            never holds a file that failed it (and a kill during it leaves the old file).

    Raises:
        OSError: ``path`` is not a regular file, or the write failed.
    """
    path = check_writable_target(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    remove_stale_temps(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.{os.getpid()}.",
                               suffix=suffix)
    try:
        try:
            old_mode = stat.S_IMODE(path.stat().st_mode)
        except FileNotFoundError:
            old_mode = 0o666 & ~_umask()
        os.fchmod(fd, old_mode)
        with os.fdopen(fd, mode) as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        if verify is not None:
            verify(Path(tmp))
        check_writable_target(path)  # it may have changed while we wrote
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


# --------------------------------------------------------------------------------------------
# Writing a directory as a whole
# --------------------------------------------------------------------------------------------

_RENAME_EXCHANGE = 2
_AT_FDCWD = -100


def _exchange(a: Path, b: Path) -> bool:
    """Swap two existing paths in one atomic step (Linux ``renameat2``); False if unsupported."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        renameat2 = libc.renameat2
    except (OSError, AttributeError):
        return False
    renameat2.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p,
                          ctypes.c_uint]
    if renameat2(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE) == 0:
        return True
    errno = ctypes.get_errno()
    if errno in (22, 38, 95):  # EINVAL, ENOSYS, EOPNOTSUPP: file system or kernel cannot
        return False
    raise OSError(errno, f"cannot exchange {a} and {b}: {os.strerror(errno)}")


def _fsync_dir(path: Path) -> None:
    _fsync(path, os.O_RDONLY)


def _fsync(path: Path, flags: int) -> None:
    """Sync ``path`` (a folder, or a file opened with ``flags``); a failure is ignored."""
    try:
        fd = os.open(path, flags)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


# A swap's temporary directories are named ``.<name>.<pid>.<8 random>.tmp`` (the new directory
# being filled) and ``.<name>.<pid>.<8 random>.old`` (the old one set aside where the atomic
# exchange is unsupported); the writer holds an exclusive ``flock`` on the directory while it
# exists. Earlier versions named them ``.<name>.<8 random>.tmp``/``.old``, with no pid or lock.
_DIR_TEMP = re.compile(r"^\.(?P<name>.+)\.(?P<pid>[0-9]{1,9})\.(?P<rand>[a-z0-9_]{8})\."
                       r"(?P<kind>tmp|old)$")
_LEGACY_DIR_TEMP = re.compile(r"^\.(?P<name>.+)\.(?P<rand>[a-z0-9_]{8})\.(?P<kind>tmp|old)$")
# A legacy temporary directory carries no pid or lock: it counts as left behind once nothing in
# it has changed for this long (its writer, an older aerodock, took seconds to fill it).
LEGACY_DIR_TEMP_AGE_S = 3600.0


def _lock_dir(path: Path) -> int | None:
    """An fd of ``path`` holding an exclusive ``flock`` on it; None if another process holds it.

    Raises:
        OSError: ``path`` cannot be opened as a directory.
    """
    fd = os.open(path, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW)
    if fcntl is None:  # no flock (not a POSIX system): the pid alone decides
        return fd
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        os.close(fd)
        return None
    return fd


def _only_regular_files(path: Path) -> bool:
    """Whether ``path`` holds nothing but regular files (what :func:`write_dir_atomic` writes)."""
    try:
        return all(entry.is_file(follow_symlinks=False) for entry in os.scandir(path))
    except OSError:
        return False


def _newest_mtime(path: Path) -> float:
    times = [path.lstat().st_mtime]
    times += [entry.stat(follow_symlinks=False).st_mtime for entry in os.scandir(path)]
    return max(times)


def remove_stale_dir_temps(parent: str | Path, *, now: float | None = None) -> list[Path]:
    """Remove the temporary directories of :func:`write_dir_atomic` in ``parent`` that a killed
    writer left behind; returns what was removed (or restored).

    Only directories named as the swap names them are considered, and only if they hold
    nothing but regular files (what the swap writes; never a symlink or a sub-folder). A
    symbolic link named as the swap names its temporaries (with a process id), left when an
    earlier version swapped a linked output folder out, is removed like a folder once its
    process is gone (the link, never what it points to). One is
    left behind when the process in its name is gone and nobody holds its lock, or, for the
    earlier versions' names (no pid, no lock), when nothing in it has changed for
    :data:`LEGACY_DIR_TEMP_AGE_S`. A ``.old`` directory (the old contents set aside where the
    atomic exchange is unsupported) whose target no longer exists is renamed back to it, so a
    kill between the two renames leaves the old directory, not nothing.
    """
    parent = Path(parent)
    now = time.time() if now is None else now
    removed: list[Path] = []
    try:
        entries = list(os.scandir(parent))
    except OSError:
        return removed
    for entry in entries:
        match = _DIR_TEMP.match(entry.name)
        legacy = None if match else _LEGACY_DIR_TEMP.match(entry.name)
        if match and entry.is_symlink() and not _pid_alive(int(match["pid"])):
            with contextlib.suppress(OSError):
                os.unlink(entry.path)
                removed.append(Path(entry.path))
            continue
        if not (match or legacy) or not entry.is_dir(follow_symlinks=False):
            continue
        path = Path(entry.path)
        if not _only_regular_files(path):
            continue
        if match and _pid_alive(int(match["pid"])):
            continue
        try:
            if legacy and now - _newest_mtime(path) < LEGACY_DIR_TEMP_AGE_S:
                continue
            fd = _lock_dir(path)
        except OSError:
            continue
        if fd is None:  # its writer is alive (in another pid namespace, say)
            continue
        try:
            target = parent / (match or legacy)["name"]
            if (match or legacy)["kind"] == "old" and not os.path.lexists(target):
                os.rename(path, target)
            else:
                shutil.rmtree(path)
            removed.append(path)
        except OSError:
            pass
        finally:
            os.close(fd)
    return removed


def _make_dir_temp(parent: Path, name: str, kind: str) -> tuple[Path, int]:
    """A new, locked temporary directory for :func:`write_dir_atomic` and the fd holding its
    lock (see :data:`_DIR_TEMP`)."""
    for _ in range(5):
        tmp = Path(tempfile.mkdtemp(dir=parent, prefix=f".{name}.{os.getpid()}.",
                                    suffix=f".{kind}"))
        # mkdtemp's random part is 8 characters; the cleaner recognises exactly that
        try:
            fd = _lock_dir(tmp)
        except OSError:
            continue  # removed already (by a cleaner that mistook it): make another
        if fd is not None:
            try:
                if os.path.samestat(os.fstat(fd), os.lstat(tmp)):
                    return tmp, fd
            except OSError:
                pass
            os.close(fd)
    raise OSError(f"cannot create a temporary directory in {parent}")


def _swap_synced_dir(tmp: Path, path: Path) -> None:
    """Put the synced folder ``tmp`` at ``path`` in one step and remove the old one.

    ``renameat2`` with ``RENAME_EXCHANGE`` where the system has it, a plain rename where
    ``path`` does not exist; otherwise the old folder is renamed aside (``.NAME.PID.XXXX.old``,
    which :func:`remove_stale_dir_temps` restores if a kill comes between the two renames) and
    put back if the second rename fails. The parent folder is synced last.
    """
    if not os.path.lexists(path):
        os.rename(tmp, path)
    elif _exchange(tmp, path):
        _remove_entry(tmp)  # now holds the old folder (or a link swapped in since the check)
    else:
        aside = Path(tempfile.mkdtemp(dir=path.parent, prefix=f".{path.name}.{os.getpid()}.",
                                      suffix=".old"))
        os.rmdir(aside)
        os.rename(path, aside)
        try:  # its pid protects it until the lock is held
            aside_lock = _lock_dir(aside)
        except OSError:
            aside_lock = None
        try:
            try:
                os.rename(tmp, path)
            except BaseException:
                os.rename(aside, path)
                raise
            _remove_entry(aside)
        finally:
            if aside_lock is not None:
                os.close(aside_lock)
    _fsync_dir(path.parent)


def refuse_symlink(path: str | Path) -> Path:
    """Refuse an output folder given as a symbolic link (a link in a parent folder is fine).

    A folder written as a whole is swapped in by renaming, which replaces the link itself, not
    the folder it points to; rather than do that silently (or write through the link into a
    folder aerodock did not make), the link is refused.

    Raises:
        InputError: ``path`` is a symbolic link (one line, naming it).
    """
    path = Path(path)
    if path.is_symlink():
        raise InputError(path, "is a symbolic link; aerodock replaces an output folder as a "
                               "whole and does not follow links: give the folder it points to "
                               f"({os.path.realpath(path)}) or a new name")
    return path


def _remove_entry(path: Path) -> None:
    """Remove a folder tree, or a symbolic link (never what it points to); errors ignored."""
    if path.is_symlink():
        with contextlib.suppress(OSError):
            path.unlink()
    else:
        shutil.rmtree(path, ignore_errors=True)


def write_dir_atomic(path: str | Path, files: Mapping[str, bytes]) -> Path:
    """Make ``path`` a directory holding exactly ``files`` (name -> bytes), all at once.

    The files are written and synced in a sibling temporary directory that then swaps names
    with ``path`` atomically (``renameat2`` with ``RENAME_EXCHANGE`` on Linux), or is renamed to
    it if ``path`` does not exist. Where the atomic exchange is unsupported, the old directory
    is renamed aside first and restored if the second rename fails. On any error the temporary
    directory is removed and ``path`` is left as it was. A kill (SIGKILL) leaves the old
    directory or the new one and possibly a temporary sibling: the next call for any directory
    in the same folder removes it (:func:`remove_stale_dir_temps`).

    The order matters: the files are synced before the swap and the parent directory after it,
    so that a crash never makes the new name point at files that are not on disk yet.

    Raises:
        InputError: ``path`` is a symbolic link (:func:`refuse_symlink`).
        OSError: the files cannot be written.
    """
    path = refuse_symlink(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    remove_stale_dir_temps(path.parent)
    tmp, lock = _make_dir_temp(path.parent, path.name, "tmp")
    try:
        os.chmod(tmp, 0o777 & ~_umask())
        for name, blob in files.items():
            with open(tmp / name, "wb") as fh:
                fh.write(blob)
                fh.flush()
                os.fsync(fh.fileno())
        _fsync_dir(tmp)
        refuse_symlink(path)  # it may have changed while we wrote
        _swap_synced_dir(tmp, path)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    finally:
        os.close(lock)
    return path


# --------------------------------------------------------------------------------------------
# Building a folder of several files as a whole
# --------------------------------------------------------------------------------------------


def remove_stale_build_dirs(path: str | Path) -> list[Path]:
    """Remove the temporary folders of :func:`building_dir` for ``path`` left by killed runs.

    Each temporary folder names its process id (``.NAME.PID.XXXX.tmp``); one whose process is
    gone is removed (a SIGKILL cannot clean up). A symbolic link of that name (what an earlier
    version left when ``--out`` was a link: the swap moved the link there) is removed the same
    way: the link, never what it points to. Returns the removed folders and links.
    """
    path = Path(path)
    removed = []
    for tmp in path.parent.glob(f".{glob_escape(path.name)}.*{_TMP_SUFFIX}"):
        pid_text = tmp.name[len(path.name) + 2:].split(".", 1)[0]
        if not pid_text.isdigit() or _pid_alive(int(pid_text)):
            continue
        if tmp.is_symlink() or tmp.is_dir():
            _remove_entry(tmp)
            removed.append(tmp)
    return removed


def glob_escape(name: str) -> str:
    """``name`` with the glob pattern characters (``*?[``) escaped."""
    return "".join(f"[{c}]" if c in "*?[" else c for c in name)


def _fsync_tree(root: Path) -> None:
    """Sync every file and folder under ``root`` (files first, then their folders)."""
    for folder, _, names in os.walk(root, topdown=False):
        for name in names:
            _fsync(Path(folder, name), os.O_RDONLY | os.O_NONBLOCK)
        _fsync_dir(Path(folder))


def check_output_dir(path: str | Path, owned: tuple[str, ...] = ("*",)) -> Path:
    """Refuse an output folder :func:`building_dir` would refuse, before the work begins.

    Raises:
        InputError: ``path`` is a symbolic link, exists and is not a folder, or holds entries
            outside ``owned``.
    """
    path = Path(path)
    _check_owned(path, owned)
    return path


def _check_owned(path: Path, owned: tuple[str, ...]) -> None:
    """Refuse to replace a folder holding entries the command does not write (a user's files,
    or the current folder given as ``--out``)."""
    import fnmatch

    refuse_symlink(path)
    if not path.exists():
        return
    if not path.is_dir():
        raise InputError(path, "exists and is not a folder; give a folder name")
    foreign = sorted(entry.name for entry in path.iterdir()
                     if not any(fnmatch.fnmatchcase(entry.name, pattern) for pattern in owned))
    if foreign:
        shown = ", ".join(foreign[:3]) + (f" (+{len(foreign) - 3} more)" if len(foreign) > 3
                                          else "")
        raise InputError(path, f"holds files this command does not write ({shown}); the "
                               "folder is replaced as a whole, so give a new folder or one "
                               "this command wrote")


def swap_in_dir(tmp: str | Path, path: str | Path) -> None:
    """Put the finished folder ``tmp`` at ``path`` in one step; the old folder is removed.

    Uses the atomic exchange of :func:`write_dir_atomic` (``renameat2`` with
    ``RENAME_EXCHANGE``), or a plain rename where ``path`` does not exist; where the exchange
    is unsupported, the old folder is renamed aside first and restored if the second rename
    fails. Everything under ``tmp`` is synced before the swap and the parent folder after it.

    Raises:
        OSError: the swap failed; ``path`` is as it was and ``tmp`` is left for the caller.
    """
    tmp, path = Path(tmp), Path(path)
    _fsync_tree(tmp)
    _swap_synced_dir(tmp, path)


@contextmanager
def building_dir(path: str | Path, owned: tuple[str, ...] = ("*",)) -> Iterator[Path]:
    """Build a folder of several files in a temporary sibling; on success it replaces ``path``.

    ``with building_dir(out, ("results.csv", "figures")) as work:`` -- write everything into
    ``work``; when the block ends without an error, ``work`` takes ``out``'s place in one step
    (:func:`swap_in_dir`). A failure, an interrupt or a kill at any moment leaves the old
    folder as it was (a killed run's temporary folder, ``.NAME.PID.XXXX.tmp``, is removed by the
    next build of the same folder), so ``path`` holds one run's files, never a mix.

    Args:
        path: the output folder.
        owned: glob patterns of the entries the command writes; an existing ``path`` holding
            anything else is refused rather than replaced (``--out .`` would otherwise replace
            the current folder).

    Raises:
        InputError: ``path`` is a symbolic link (:func:`refuse_symlink`), exists and is not a
            folder, or holds entries outside ``owned``.
        OSError: the folder cannot be made or swapped in.
    """
    path = Path(path)
    _check_owned(path, owned)
    path.parent.mkdir(parents=True, exist_ok=True)
    remove_stale_build_dirs(path)
    tmp = Path(tempfile.mkdtemp(dir=path.parent, prefix=f".{path.name}.{os.getpid()}.",
                                suffix=_TMP_SUFFIX))
    try:
        os.chmod(tmp, 0o777 & ~_umask())
        yield tmp
        _check_owned(path, owned)  # it may have changed while we built
        swap_in_dir(tmp, path)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
