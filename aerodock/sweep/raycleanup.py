"""Cleaning up the local Ray instance of ``aerodock sweep --backend ray`` however the driver ends.

Ray starts its head processes (GCS, raylet, ...) as children of the driver that fate-share with
it (``PR_SET_PDEATHSIG``), but the raylet's own children, the dashboard and runtime-env agents,
only notice a dead raylet by polling: after a ``kill -9`` of the driver they stay for minutes
(about 85 MB each). Two pieces close that gap:

- :class:`RayReaper`: a small watchdog process started before ``ray.init``, in its own session
  (a terminal's Ctrl-C or a ``kill`` of the driver's process group does not reach it). It keeps
  a list of the driver's Ray descendants (polled every :data:`POLL_S`) and waits on a pipe from
  the driver; when the pipe closes (the driver exited, normally or by ``SIGKILL``), it sends
  ``SIGTERM`` to every listed process still alive and to their descendants, then ``SIGKILL``
  after :data:`GRACE_S`, and exits. Processes are matched by pid *and* start time, so a reused
  pid is never hit; only processes that look like Ray's (:func:`is_ray_process`) are listed.
- :func:`sigterm_exits_cleanly`: while the sweep runs, ``SIGTERM`` raises :class:`Terminated`
  (a ``SystemExit`` with code 143 = 128 + 15) in the main thread instead of Ray's C++ failure
  handler (a stack dump and exit 1); the sweep's ``finally`` calls ``ray.shutdown()``.

Only the Ray instance the sweep starts itself is watched; a cluster given by ``--address`` or a
Ray already initialised by the caller is left alone.
"""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from types import FrameType

POLL_S = 0.3
"""How often the watchdog lists the driver's Ray descendants, s."""
GRACE_S = 2.0
"""From ``SIGTERM`` to ``SIGKILL`` for the Ray processes left when the driver is gone, s."""
SIGTERM_EXIT = 128 + signal.SIGTERM
"""The exit status of a sweep stopped by ``SIGTERM`` (143, the shell's convention)."""

_RAY_MARKERS = ("/ray/", "ray::", "raylet", "gcs_server")

ProcKey = tuple[int, int]
"""A process: ``(pid, start time in clock ticks since boot)``; unique over a boot."""


def _read_stat(pid: int) -> tuple[int, int] | None:
    """``(parent pid, start time)`` of ``pid`` from ``/proc``, or None when it is gone."""
    try:
        raw = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    fields = raw[raw.rindex(")") + 2:].split()  # after "pid (comm) "
    return int(fields[1]), int(fields[19])


def _cmdline(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode(
            errors="replace")
    except OSError:
        return ""


def is_ray_process(pid: int) -> bool:
    """True when ``pid``'s command line is one of Ray's (its binaries, scripts or workers)."""
    cmd = _cmdline(pid)
    return any(marker in cmd for marker in _RAY_MARKERS)


def process_table() -> dict[int, tuple[int, int]]:
    """Every process: pid -> ``(parent pid, start time)`` (Linux ``/proc``)."""
    table = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit() and (stat := _read_stat(int(entry))) is not None:
            table[int(entry)] = stat
    return table


def descendants(roots: set[int], table: dict[int, tuple[int, int]]) -> set[int]:
    """The pids below ``roots`` in ``table`` (not the roots themselves)."""
    children: dict[int, list[int]] = {}
    for pid, (ppid, _) in table.items():
        children.setdefault(ppid, []).append(pid)
    found: set[int] = set()
    todo = list(roots)
    while todo:
        for child in children.get(todo.pop(), []):
            if child not in found:
                found.add(child)
                todo.append(child)
    return found


def ray_descendants(owner: int, table: dict[int, tuple[int, int]]) -> set[ProcKey]:
    """``owner``'s descendants that are Ray processes, as :data:`ProcKey`."""
    me = os.getpid()
    return {(pid, table[pid][1]) for pid in descendants({owner}, table)
            if pid != me and is_ray_process(pid)}


def alive(known: set[ProcKey], table: dict[int, tuple[int, int]]) -> set[int]:
    """The pids of ``known`` still running as the same process (same start time)."""
    return {pid for pid, start in known if pid in table and table[pid][1] == start}


def _signal_all(pids: set[int], sig: int) -> None:
    for pid in pids:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.kill(pid, sig)


def reap(known: set[ProcKey], grace_s: float = GRACE_S) -> set[int]:
    """Stop the processes of ``known`` still running, and their descendants; the pids signalled.

    ``SIGTERM`` first, ``SIGKILL`` to whatever is left after ``grace_s``.
    """
    table = process_table()
    live = alive(known, table)
    keys = {(pid, table[pid][1]) for pid in live | descendants(live, table)}
    _signal_all({pid for pid, _ in keys}, signal.SIGTERM)
    deadline = time.monotonic() + grace_s
    while (left := alive(keys, process_table())) and time.monotonic() < deadline:
        time.sleep(0.05)
    _signal_all(left, signal.SIGKILL)
    return {pid for pid, _ in keys}


def watch(owner: int, poll_s: float = POLL_S) -> None:
    """The watchdog's loop: list ``owner``'s Ray descendants until stdin closes, then reap them."""
    import select

    known: set[ProcKey] = set()
    stdin = sys.stdin.fileno()
    while True:
        known |= ray_descendants(owner, process_table())
        ready, _, _ = select.select([stdin], [], [], poll_s)
        if ready and not os.read(stdin, 4096):  # EOF: the driver is gone or done
            break
    known |= ray_descendants(owner, process_table())  # those still attached to the tree
    reap(known)


class RayReaper:
    """The watchdog of one driver (see the module docstring); a context manager.

    Leaving the context closes the pipe, so the watchdog stops whatever Ray left behind and
    exits; if the driver is killed, the kernel closes the pipe and the same happens.
    """

    def __init__(self) -> None:
        self.proc: subprocess.Popen | None = None

    def __enter__(self) -> RayReaper:
        env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in sys.path if p)}
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "aerodock.sweep.raycleanup", str(os.getpid())],
            stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            start_new_session=True, env=env, close_fds=True)
        return self

    def __exit__(self, *exc: object) -> None:
        if self.proc is not None and self.proc.stdin is not None:
            self.proc.stdin.close()  # the watchdog reaps and exits on its own; not waited for


class Terminated(SystemExit):
    """Raised in the main thread by ``SIGTERM`` during a Ray sweep (exit status 143)."""

    def __init__(self) -> None:
        super().__init__(SIGTERM_EXIT)


_active = False
"""Inside :func:`sigterm_exits_cleanly` (in the main thread)."""
_received = False
"""A ``SIGTERM`` arrived inside :func:`sigterm_exits_cleanly`."""


def _raise_terminated(signum: int, frame: FrameType | None) -> None:
    global _received
    _received = True
    raise Terminated()


@contextlib.contextmanager
def sigterm_exits_cleanly() -> Iterator[None]:
    """``SIGTERM`` raises :class:`Terminated` inside the block (main thread only; else no-op).

    Call :func:`reinstall_sigterm` after ``ray.init``: ``ray.init`` installs its own ``SIGTERM``
    handlers over this one. Ray turns an exception raised by a signal handler inside
    ``ray.wait``/``ray.get`` into ``SystemExit(1)``; leaving the block after a ``SIGTERM`` raises
    :class:`Terminated` instead, as does the ``SystemExit(15)`` of the handler ``ray.init``
    installs while it starts (a ``SIGTERM`` during ``ray.init``).
    """
    import threading

    global _active, _received
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGTERM, _raise_terminated)
    _active, _received = True, False
    try:
        yield
    except Terminated:
        raise
    except SystemExit as exit_:
        if _received or exit_.code == signal.SIGTERM:
            raise Terminated() from None
        raise
    except BaseException:
        if _received:
            raise Terminated() from None
        raise
    finally:
        _active = False
        signal.signal(signal.SIGTERM, previous if previous is not None else signal.SIG_DFL)


def reinstall_sigterm() -> None:
    """Put :func:`sigterm_exits_cleanly`'s handler back (after ``ray.init`` replaced it)."""
    import threading

    if _active and threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGTERM, _raise_terminated)


def main(argv: list[str] | None = None) -> int:
    """``python -m aerodock.sweep.raycleanup OWNER_PID``: the watchdog process."""
    args = sys.argv[1:] if argv is None else argv
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # outlive a Ctrl-C of the driver's terminal
    watch(int(args[0]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
