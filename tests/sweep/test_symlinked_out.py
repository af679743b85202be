"""An output folder given as a symbolic link is refused in one line and leaves nothing behind;
the hidden link an earlier version left (``.NAME.PID.XXXX.tmp``) is removed like a folder."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from cli_process import aerodock

from aerodock.fileio import (
    InputError,
    building_dir,
    remove_stale_build_dirs,
    write_dir_atomic,
)


def _dead_pid() -> int:
    proc = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    return int(proc.stdout)


def _listing(folder: Path) -> dict[str, str]:
    """Every entry under ``folder`` (links not followed): name -> kind or bytes."""
    out = {}
    for root, dirs, files in os.walk(folder):
        for name in dirs + files:
            path = Path(root, name)
            rel = str(path.relative_to(folder))
            if path.is_symlink():
                out[rel] = f"-> {os.readlink(path)}"
            elif path.is_dir():
                out[rel] = "dir"
            else:
                out[rel] = path.read_bytes().decode(errors="replace")
    return out


@pytest.fixture
def linked(tmp_path) -> tuple[Path, Path]:
    """``out`` -> ``real/`` (a folder holding a file of the user's)."""
    real = tmp_path / "real"
    real.mkdir()
    (real / "notes.txt").write_text("mine")
    out = tmp_path / "out"
    out.symlink_to(real)
    return out, real


def test_sweep_refuses_a_symlinked_out_in_one_line(tmp_path, linked):
    out, real = linked
    spec = tmp_path / "spec.toml"
    spec.write_text('[sweep]\ntrials = 1\n[axes]\ncompensation = ["oracle"]\n')
    before = _listing(tmp_path)
    proc = aerodock("sweep", spec, "--out", out, "--jobs", "1")
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1 and "Traceback" not in proc.stderr
    assert proc.stderr.startswith(f"error: {out}: is a symbolic link")
    assert str(real) in proc.stderr  # says where it points
    assert _listing(tmp_path) == before  # nothing behind: no hidden folder, link and target kept


def test_train_refuses_a_symlinked_out_before_training(tmp_path, linked):
    out, _ = linked
    before = _listing(tmp_path)
    proc = aerodock("train", "--data", tmp_path / "missing.npz", "--out", out)
    assert proc.returncode == 2 and "is a symbolic link" in proc.stderr  # not the data error
    assert proc.stderr.count("\n") == 1
    assert _listing(tmp_path) == before


def test_folder_writers_refuse_links_and_leave_nothing(tmp_path, linked):
    out, _ = linked
    before = _listing(tmp_path)
    with pytest.raises(InputError, match="is a symbolic link"):
        write_dir_atomic(out, {"model.json": b"{}"})
    with pytest.raises(InputError, match="is a symbolic link"), building_dir(out) as work:
        (work / "x").write_text("never")
    assert _listing(tmp_path) == before
    # a link in a parent folder is followed: the output is a real folder inside its target
    write_dir_atomic(out / "model", {"model.json": b"{}"})
    with building_dir(out / "study") as work:
        (work / "a.csv").write_text("x")
    assert (tmp_path / "real" / "model" / "model.json").read_bytes() == b"{}"
    assert (tmp_path / "real" / "study" / "a.csv").read_text() == "x"


def test_a_leftover_temporary_link_is_removed_like_a_folder(tmp_path, linked):
    """What an earlier version left after ``--out LINK``: the link, moved to a temporary name
    by the swap; the next build of the same folder removes it (never what it points to)."""
    _, real = linked
    dead = _dead_pid()
    left = tmp_path / f".study.{dead}.abcd1234.tmp"
    left.symlink_to(real)
    folder = tmp_path / f".study.{dead}.abcd1235.tmp"
    folder.mkdir()
    (folder / "results.csv").write_text("half")
    alive = tmp_path / f".study.{os.getpid()}.abcd1236.tmp"
    alive.symlink_to(real)
    assert sorted(remove_stale_build_dirs(tmp_path / "study")) == sorted([left, folder])
    assert not os.path.lexists(left) and not folder.exists()
    assert os.path.lexists(alive)  # its process is running
    assert (real / "notes.txt").read_text() == "mine"
