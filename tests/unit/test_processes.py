"""The side worker (aerodock.processes): jobs in order on one other process, their exceptions
passed on as the driver would have raised them, the worker stopped when its block is left by an
exception or its driver dies, and the jobs run here lazily when asked to (or on one core); and
reproduce's driver lending a core to it and taking it back."""

import os
import signal
import subprocess
import sys
import time

import pytest

import aerodock.processes as processes
from aerodock.fileio.inputs import InputError, check_input_file
from aerodock.processes import SideWorker, side_worker, usable_cores

needs_two_cores = pytest.mark.skipif(usable_cores() < 2, reason="one usable core: jobs run here")


class Unportable(ValueError):
    """An error the driver could not rebuild from its pickle (two arguments, one message)."""

    def __init__(self, where: str, problem: str) -> None:
        super().__init__(f"{where}: {problem}")


def raise_unportable(where: str) -> None:
    raise Unportable(where, "cannot travel")


def _gone(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    return False


@needs_two_cores
def test_jobs_run_in_order_on_one_other_process(tmp_path):
    note = tmp_path / "note.txt"
    with side_worker() as side:
        pids = side.submit(os.getpid), side.submit(os.getpid)
        written = side.submit(note.write_text, "first")
        read = side.submit(note.read_text)  # fails unless the write ran before it
        assert read() == "first" and written() == 5
        assert pids[0]() == pids[1]() != os.getpid()
        assert not side.busy()
    assert _gone(pids[0]())  # the worker exited with the block


@needs_two_cores
def test_a_jobs_error_reaches_the_driver_as_it_would_be_raised_here(tmp_path):
    big = tmp_path / "big.npz"
    big.write_bytes(b"0123456789")
    with pytest.raises(InputError) as here:
        check_input_file(big, "file", 4)
    with side_worker() as side:
        with pytest.raises(InputError) as there:  # two arguments: rebuilt, not a broken pool
            side.submit(check_input_file, big, "file", 4)()
        assert str(there.value) == str(here.value) and there.value.path == str(big)
        with pytest.raises(ValueError, match="^x: cannot travel$") as other:
            side.submit(raise_unportable, "x")()
        assert type(other.value) is ValueError  # its nearest built-in class, same message
        with pytest.raises(ZeroDivisionError):
            side.submit(divmod, 1, 0)()


@needs_two_cores
def test_a_worker_that_dies_is_said_in_one_line():
    with side_worker() as side, pytest.raises(RuntimeError, match="ended without its result"):
        side.submit(os._exit, 3)()


@needs_two_cores
def test_leaving_by_an_exception_stops_a_busy_worker():
    started = time.monotonic()
    with pytest.raises(KeyError), side_worker() as side:
        pid = side.submit(os.getpid)()
        side.submit(time.sleep, 120)
        assert side.busy()
        raise KeyError("the driver failed")
    assert _gone(pid)
    assert time.monotonic() - started < 60  # stopped, not waited for (a hang guard)


DRIVER = """
import os, sys, time
from aerodock.processes import side_worker
with side_worker() as side:
    print(side.submit(os.getpid)(), flush=True)
    side.submit(time.sleep, 120)
    time.sleep(120)
"""


@needs_two_cores
def test_a_worker_ends_when_its_driver_is_killed():
    driver = subprocess.Popen([sys.executable, "-c", DRIVER], stdout=subprocess.PIPE, text=True)
    try:
        worker = int(driver.stdout.readline())
        driver.send_signal(signal.SIGKILL)
        driver.wait(30)
        deadline = time.monotonic() + 30
        while not _gone(worker) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert _gone(worker)  # (reaped by init once it ends)
    finally:
        if driver.poll() is None:
            driver.kill()


def test_run_here_runs_each_job_in_this_process_when_asked():
    seen: list[int] = []
    side = SideWorker(run_here=True)
    result = side.submit(seen.append, 1)
    assert seen == [] and not side.busy()
    result()
    assert seen == [1]
    assert side.submit(os.getpid)() == os.getpid()


def test_one_usable_core_runs_the_jobs_here(monkeypatch):
    monkeypatch.setattr(processes, "usable_cores", lambda: 1)
    with side_worker() as side:
        assert side.run_here and side.submit(os.getpid)() == os.getpid()


class _Side:
    busy_now = True

    def busy(self) -> bool:
        return self.busy_now


def test_reproduce_lends_a_core_to_the_side_worker_and_takes_it_back():
    numba = pytest.importorskip("numba")
    from aerodock.experiments.reproduce import _cores_shared_with

    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("numba has one thread here")
    before = numba.get_num_threads()
    side = _Side()
    with pytest.raises(KeyError), _cores_shared_with(side) as share:
        share()
        assert numba.get_num_threads() == before - 1
        side.busy_now = False
        share()
        assert numba.get_num_threads() == before
        side.busy_now = True
        share()
        raise KeyError("a step failed")
    assert numba.get_num_threads() == before  # restored, though the block failed
