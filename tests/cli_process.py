"""The CLI in a subprocess, as a user runs it: one helper for the tests that need a real process
(exit codes, stdout and stderr as printed, files written by a separate interpreter)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ENTRY = "from aerodock.cli import main; main()"


def aerodock(*args: object, check: bool = False, cwd: Path | str | None = None,
             timeout_s: float = 600) -> subprocess.CompletedProcess:
    """Run ``aerodock ARGS`` with this interpreter; ``check``: a non-zero exit fails the test
    with the command's stderr."""
    proc = subprocess.run([sys.executable, "-c", ENTRY, *map(str, args)], capture_output=True,
                          text=True, timeout=timeout_s, cwd=cwd)
    if check and proc.returncode != 0:
        raise AssertionError(proc.stderr)
    return proc
