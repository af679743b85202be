"""The side worker (aerodock.processes): jobs in order on one other process, their exceptions
passed on, the worker stopped when its block is left by an exception, and the jobs run here
lazily when asked to."""

import operator
import os
import time

import pytest

from aerodock.processes import SideWorker, side_worker, usable_cores

needs_two_cores = pytest.mark.skipif(usable_cores() < 2, reason="one usable core: jobs run here")


def _gone(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    return False


@needs_two_cores
def test_jobs_run_in_order_on_one_other_process():
    with side_worker() as side:
        first, second = side.submit(os.getpid), side.submit(os.getpid)
        assert first() == second() != os.getpid()
        assert not side.busy()
    assert _gone(first())  # the worker exited with the block


@needs_two_cores
def test_a_jobs_exception_reaches_the_caller():
    with side_worker() as side:
        result = side.submit(operator.truediv, 1, 0)
        with pytest.raises(ZeroDivisionError):
            result()


@needs_two_cores
def test_leaving_by_an_exception_stops_a_busy_worker():
    with pytest.raises(KeyError), side_worker() as side:
        pid = side.submit(os.getpid)()
        side.submit(time.sleep, 600)
        assert side.busy()
        raise KeyError("the caller failed")
    assert _gone(pid)  # terminated, not left sleeping (the block would have waited 600 s)


def test_run_here_runs_each_job_in_this_process_when_asked():
    seen: list[int] = []
    side = SideWorker(run_here=True)
    result = side.submit(seen.append, 1)
    assert seen == [] and not side.busy()
    result()
    assert seen == [1]
    assert side.submit(os.getpid)() == os.getpid()
