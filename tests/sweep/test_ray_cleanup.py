"""``aerodock sweep --backend ray`` leaves no Ray process behind: SIGKILL and SIGTERM of the driver.

The sweep runs in a subprocess with a local Ray instance; once Ray's processes are up (seen as
the driver's descendants), the driver is killed and every Ray process it started must be gone
within a bounded wait (a hang guard, not a timing figure).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytest.importorskip("ray")
if not Path("/proc/self/stat").exists():  # pragma: no cover
    pytest.skip("needs Linux /proc", allow_module_level=True)

from aerodock.sweep.raycleanup import (  # noqa: E402
    SIGTERM_EXIT,
    alive,
    process_table,
    ray_descendants,
)

pytestmark = pytest.mark.slow

SPEC = """
[sweep]
name = "long"
trials = 4
seeds = [0, 1, 2, 3, 4, 5, 6, 7]
[axes]
cable_length_m = [0.36, 0.64, 1.35]
compensation = ["observer", "oracle"]
"""
START_TIMEOUT_S = 120.0
GONE_TIMEOUT_S = 30.0


def _start(tmp_path: Path) -> subprocess.Popen:
    spec = tmp_path / "long.toml"
    spec.write_text(SPEC)
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    return subprocess.Popen(
        [sys.executable, "-c", "from aerodock.cli import main; main()", "sweep", str(spec),
         "--out", str(tmp_path / "out"), "--backend", "ray", "--jobs", "1"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)


def _wait_for_ray(proc: subprocess.Popen) -> set[tuple[int, int]]:
    """The driver's Ray processes once its raylet runs and a worker runs a cell."""
    deadline = time.monotonic() + START_TIMEOUT_S
    while time.monotonic() < deadline:
        assert proc.poll() is None, proc.communicate()[1].decode()[-2000:]
        known = ray_descendants(proc.pid, process_table())
        cmds = [Path(f"/proc/{pid}/cmdline").read_bytes() for pid, _ in known
                if Path(f"/proc/{pid}/cmdline").exists()]
        if any(b"raylet" in c for c in cmds) and any(b"ray::_cell_job" in c for c in cmds):
            time.sleep(1.0)  # let the agents start too
            return known | ray_descendants(proc.pid, process_table())
        time.sleep(0.2)
    proc.kill()
    pytest.fail("the Ray sweep did not start its workers in time")


def _left_after(known: set[tuple[int, int]], timeout_s: float) -> set[int]:
    deadline = time.monotonic() + timeout_s
    while (left := alive(known, process_table())) and time.monotonic() < deadline:
        time.sleep(0.2)
    return left


def _describe(pids: set[int]) -> list[str]:
    out = []
    for pid in pids:
        try:
            out.append(f"{pid}: {Path(f'/proc/{pid}/cmdline').read_bytes()[:120]!r}")
        except OSError:
            pass
    return out


def test_sigkill_of_the_driver_leaves_no_ray_process(tmp_path):
    proc = _start(tmp_path)
    known = _wait_for_ray(proc)
    assert len(known) >= 3  # gcs, raylet, a worker at least: the check below has teeth
    proc.kill()
    proc.wait(timeout=30)
    left = _left_after(known, GONE_TIMEOUT_S)
    if left:  # do not leave them to the next test either
        for pid in left:
            os.kill(pid, signal.SIGKILL)
    assert not left, _describe(left)


def test_sigterm_exits_143_cleanly_and_stops_ray(tmp_path):
    proc = _start(tmp_path)
    known = _wait_for_ray(proc)
    proc.send_signal(signal.SIGTERM)
    _, stderr = proc.communicate(timeout=60)
    text = stderr.decode(errors="replace")
    assert proc.returncode == SIGTERM_EXIT, text[-3000:]
    for sign in ("Traceback", "*** SIGTERM received", "Stack trace", "stack trace"):
        assert sign not in text, text[-3000:]
    assert not (tmp_path / "out").exists()  # stopped, not finished
    left = _left_after(known, GONE_TIMEOUT_S)
    for pid in left:
        os.kill(pid, signal.SIGKILL)
    assert not left, _describe(left)
