"""aerodock.fileio: atomic writes (mode, targets, leftovers), strict JSON, guarded npz headers."""

from __future__ import annotations

import io
import os
import stat
import subprocess
import sys
import zipfile

import numpy as np
import pytest

from aerodock.fileio import (
    atomic_open,
    check_npz_header,
    dumps_json,
    json_ready,
    one_line,
    remove_stale_dir_temps,
    remove_stale_temps,
    write_dir_atomic,
    write_json,
)


def _mode(path):
    return stat.S_IMODE(path.stat().st_mode)


def test_new_file_gets_the_umask_mode(tmp_path):
    old = os.umask(0o027)
    try:
        with atomic_open(tmp_path / "a.bin") as fh:
            fh.write(b"x")
    finally:
        os.umask(old)
    assert _mode(tmp_path / "a.bin") == 0o640


def test_replaced_file_keeps_its_mode(tmp_path):
    path = tmp_path / "a.bin"
    path.write_bytes(b"old")
    path.chmod(0o604)
    with atomic_open(path) as fh:
        fh.write(b"new")
    assert path.read_bytes() == b"new" and _mode(path) == 0o604


def test_non_regular_targets_are_refused(tmp_path):
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    with pytest.raises(OSError, match="not a regular file"):
        with atomic_open(fifo) as fh:
            fh.write(b"x")
    assert stat.S_ISFIFO(fifo.stat().st_mode)
    with pytest.raises(IsADirectoryError):
        with atomic_open(tmp_path) as fh:
            fh.write(b"x")
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]


def test_an_error_or_interrupt_leaves_the_old_file_and_no_temp(tmp_path):
    path = tmp_path / "a.bin"
    path.write_bytes(b"old")
    for exc in (RuntimeError, KeyboardInterrupt):
        with pytest.raises(exc):
            with atomic_open(path) as fh:
                fh.write(b"half")
                raise exc()
    assert path.read_bytes() == b"old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.bin"]


def test_temps_of_dead_processes_are_removed_by_the_next_write(tmp_path):
    path = tmp_path / "a.bin"
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True).stdout.strip()
    stale = tmp_path / f".a.bin.{dead}.abc123.tmp"
    stale.write_bytes(b"half")
    mine = tmp_path / f".a.bin.{os.getpid()}.xyz.tmp"  # a live writer's: kept
    mine.write_bytes(b"busy")
    assert remove_stale_temps(path) == [stale]
    assert mine.exists() and not stale.exists()


def test_a_failed_verify_leaves_the_old_file_and_no_temp(tmp_path):
    path = tmp_path / "a.bin"
    path.write_bytes(b"old")
    seen = []

    def verify(tmp):
        seen.append(tmp.read_bytes())  # complete before the check, under its temporary name
        assert tmp != path and path.read_bytes() == b"old"
        raise ValueError("wrong")

    with pytest.raises(ValueError, match="wrong"):
        with atomic_open(path, verify=verify) as fh:
            fh.write(b"new")
    assert seen == [b"new"] and path.read_bytes() == b"old"
    assert os.listdir(tmp_path) == ["a.bin"]
    with atomic_open(path, verify=lambda tmp: None) as fh:
        fh.write(b"new")
    assert path.read_bytes() == b"new"


def _dead_pid() -> int:
    return int(subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                              capture_output=True, text=True).stdout)


def _dir_with(path, files):
    path.mkdir()
    for name, blob in files.items():
        (path / name).write_bytes(blob)
    return path


def test_a_killed_swap_leaves_a_temp_dir_that_the_next_write_removes(tmp_path):
    """SIGKILL while the new directory is being filled: the old directory stays, and the
    temporary sibling left behind goes with the next write in the same folder."""
    write_dir_atomic(tmp_path / "m", {"a": b"old"})
    code = ("import os, signal\n"
            "import aerodock.fileio.writes as f\n"
            "real = f._fsync_dir\n"
            "def die(path):\n"
            "    if path.name.endswith('.tmp'): os.kill(os.getpid(), signal.SIGKILL)\n"
            "    real(path)\n"
            "f._fsync_dir = die\n"
            f"f.write_dir_atomic({str(tmp_path / 'm')!r}, {{'a': b'new'}})\n")
    proc = subprocess.run([sys.executable, "-c", code])
    assert proc.returncode == -9
    left = [p.name for p in tmp_path.iterdir() if p.name != "m"]
    assert len(left) == 1 and left[0].startswith(".m.") and left[0].endswith(".tmp"), left
    assert (tmp_path / "m" / "a").read_bytes() == b"old"
    write_dir_atomic(tmp_path / "other", {"b": b"x"})  # a write to a sibling cleans it
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m", "other"]


def test_only_our_dead_unlocked_temp_dirs_are_removed(tmp_path):
    import fcntl
    import time

    dead, alive = _dead_pid(), os.getpid()
    stale = _dir_with(tmp_path / f".m.{dead}.abcd_123.tmp", {"model.json": b"{}"})
    busy = _dir_with(tmp_path / f".m.{alive}.abcd_124.tmp", {"model.json": b"{}"})
    locked = _dir_with(tmp_path / f".m.{dead}.abcd_125.tmp", {"model.json": b"{}"})
    fd = os.open(locked, os.O_RDONLY)
    fcntl.flock(fd, fcntl.LOCK_EX)  # a writer in another pid namespace holds it
    keep = {
        "not ours": _dir_with(tmp_path / "m.tmp", {"a": b""}),
        "user folder": _dir_with(tmp_path / f".m.{dead}.toolong12.tmp", {"a": b""}),
        "a file": tmp_path / f".m.{dead}.abcd_126.tmp",
        "sub-folder": _dir_with(tmp_path / f".m.{dead}.abcd_127.tmp", {"a": b""}),
    }
    keep["a file"].write_bytes(b"atomic_open's")
    (keep["sub-folder"] / "inner").mkdir()
    link_target = _dir_with(tmp_path / "precious", {"a": b"mine"})
    link = tmp_path / f".m.{dead}.abcd_128.tmp"  # a linked folder an earlier swap left
    link.symlink_to(link_target)
    legacy_new = _dir_with(tmp_path / ".m.abcd_129.tmp", {"a": b""})
    legacy_old = _dir_with(tmp_path / ".m.abcd_130.tmp", {"a": b""})
    past = time.time() - 2 * 3600  # old enough that age alone would not keep any of them
    for p in (legacy_old, legacy_old / "a", *keep.values()):
        os.utime(p, (past, past))
    try:
        removed = remove_stale_dir_temps(tmp_path)
    finally:
        os.close(fd)
    assert sorted(removed) == sorted([stale, legacy_old, link])
    assert busy.exists() and locked.exists() and legacy_new.exists()
    assert all(p.exists() for p in keep.values())
    assert not os.path.lexists(link)  # the link goes, never what it points to
    assert (link_target / "a").read_bytes() == b"mine"
    assert not stale.exists() and not legacy_old.exists()


def test_an_old_directory_set_aside_is_restored_when_its_target_is_gone(tmp_path):
    """Without the atomic exchange the old directory is renamed aside first: a kill between
    the two renames leaves it there, and the next write puts it back before anything else."""
    dead = _dead_pid()
    aside = _dir_with(tmp_path / f".m.{dead}.abcd_123.old", {"a": b"old"})
    new = _dir_with(tmp_path / f".m.{dead}.abcd_124.tmp", {"a": b"new"})
    assert sorted(remove_stale_dir_temps(tmp_path)) == sorted([aside, new])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m"]
    assert (tmp_path / "m" / "a").read_bytes() == b"old"
    done = _dir_with(tmp_path / f".m.{dead}.abcd_125.old", {"a": b"older"})  # target exists
    assert remove_stale_dir_temps(tmp_path) == [done]
    assert (tmp_path / "m" / "a").read_bytes() == b"old"


def test_sigterm_unwinds_an_atomic_write(tmp_path):
    code = ("import signal, time; from aerodock.cli.app import _terminate; "
            "signal.signal(signal.SIGTERM, _terminate)\n"
            "from aerodock.fileio import atomic_open\n"
            f"with atomic_open({str(tmp_path / 'a.bin')!r}) as fh:\n"
            "    fh.write(b'x'); print('ready', flush=True); time.sleep(30)\n")
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    assert proc.stdout.readline().strip() == "ready"
    proc.terminate()
    assert proc.wait(timeout=30) == 143
    assert list(tmp_path.iterdir()) == []


def test_dumps_json_is_strict():
    assert dumps_json({"a": np.float64(1.5), "b": np.arange(2)}, indent=None) == \
        '{"a": 1.5, "b": [0, 1]}'
    for bad in ({"x": float("inf")}, {"x": [np.float32("nan")]}, {"x": np.array([np.nan])}):
        with pytest.raises(ValueError, match="non-finite number at 'x"):
            dumps_json(bad)


def test_json_ready_writes_a_missing_figure_as_null(tmp_path):
    doc = {"a": float("nan"), "b": (1, np.float64(-np.inf)), 3: np.array([0.5, np.nan]),
           "c": np.int64(7)}
    ready = json_ready(doc)
    assert ready == {"a": None, "b": [1, None], "3": [0.5, None], "c": 7}
    assert type(ready["c"]) is int
    path = write_json(tmp_path / "d.json", ready)
    assert path.read_text() == dumps_json(ready) and not path.read_text().endswith("\n")
    assert write_json(path, ready, final_newline=True).read_text().endswith("}\n")
    with pytest.raises(ValueError, match="non-finite number at 'a'"):
        write_json(tmp_path / "e.json", doc)  # the strict writer: nothing written
    assert not (tmp_path / "e.json").exists()


def test_one_line_folds_whitespace_or_keeps_the_first_line():
    err = ValueError("  a  b\n c ")
    assert one_line(err) == "a b c"
    assert one_line(err, first_line=True) == "a  b"
    assert one_line(ValueError(" ")) == one_line(ValueError(), first_line=True) == "ValueError"
    assert one_line(" ") == ""


def _npz(tmp_path, members: dict[str, bytes]):
    path = tmp_path / "f.npz"
    with zipfile.ZipFile(path, "w") as zf:
        for name, blob in members.items():
            zf.writestr(name, blob)
    return path


def _npy(arr):
    buf = io.BytesIO()
    np.save(buf, arr)
    return buf.getvalue()


def _declares(shape):
    header = repr({"descr": "<f8", "fortran_order": False, "shape": shape}).encode()
    header += b" " * (63 - (len(header) + 10) % 64) + b"\n"
    return b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little") + header + b"\0" * 8


@pytest.mark.parametrize(("members", "needle"), [
    ({"version.npy": _npy(np.array([1, 2]))}, "'version' must be one integer"),
    ({"version.npy": _npy(np.array("1"))}, "'version' must be one integer"),
    ({"version.npy": _npy(np.array(1)), "x.npy": _declares((10**13,))}, "declares"),
    ({"version.npy": _npy(np.array(9))}, "newer than this aerodock"),
])
def test_npz_header_checks(tmp_path, members, needle):
    path = _npz(tmp_path, {"format.npy": _npy(np.array("fmt")), **members})
    with np.load(path, allow_pickle=False) as data, pytest.raises(ValueError, match=needle):
        check_npz_header(data, path, "fmt", 1, "thing", ValueError)


def test_a_file_output_given_as_a_symlink_is_refused_and_left_alone(tmp_path):
    """Writing replaces the file by renaming, which would replace the link itself: refused in
    one line, the link and the file it points to as they were."""
    from aerodock.fileio import write_json

    target = tmp_path / "real.json"
    target.write_text('{"old": 1}')
    link = tmp_path / "link.json"
    link.symlink_to(target)
    with pytest.raises(OSError, match="is a symbolic link") as info:
        write_json(link, {"new": 2})
    assert "\n" not in str(info.value)
    assert link.is_symlink() and target.read_text() == '{"old": 1}'
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.json", "real.json"]
