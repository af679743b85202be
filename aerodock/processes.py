"""Work on other local processes: fresh interpreters (``spawn``) with one BLAS/OpenMP thread
each, that leave Ctrl-C to the process that started them and are stopped with it.

A terminal's Ctrl-C reaches the whole process group: the workers ignore ``SIGINT`` and the
driver alone reacts, stopping them (:func:`stop_pool`) before the interrupt propagates, so no
worker prints a traceback and none outlives the command. ``aerodock sweep`` runs its cells this
way (:mod:`aerodock.sweep.run`); ``aerodock reproduce`` its real-data study beside the
simulations (:func:`side_worker`).
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import signal
import threading
from collections.abc import Callable, Iterator
from concurrent.futures import Future, ProcessPoolExecutor
from typing import Any, TypeVar

T = TypeVar("T")

_THREAD_VARS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def usable_cores() -> int:
    """The cores this process may run on (its affinity mask where the system has one)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


@contextlib.contextmanager
def single_threaded_children() -> Iterator[None]:
    """Child processes started inside see one thread per BLAS/OpenMP pool (restored after):
    N processes on N cores, where inherited thread pools would oversubscribe them."""
    saved = {k: os.environ.get(k) for k in _THREAD_VARS}
    os.environ.update({k: "1" for k in _THREAD_VARS})
    try:
        yield
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


@contextlib.contextmanager
def sigint_ignored() -> Iterator[None]:
    """``SIGINT`` ignored inside (main thread only): processes started here inherit it through
    ``exec``, so a Ctrl-C while a worker interpreter starts (before its initializer) does not
    print a traceback from it. The driver's handler is restored on leaving."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def ignore_sigint() -> None:
    """A worker's initializer: Ctrl-C is the driver's to handle (it stops the workers)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def worker_pool(workers: int) -> ProcessPoolExecutor:
    """A pool of ``workers`` fresh interpreters, each with one BLAS/OpenMP thread and ``SIGINT``
    ignored. Its workers start with the first :meth:`~ProcessPoolExecutor.submit`: submit inside
    :func:`single_threaded_children` and :func:`sigint_ignored`."""
    return ProcessPoolExecutor(max_workers=workers, initializer=ignore_sigint,
                               mp_context=multiprocessing.get_context("spawn"))


def stop_pool(pool: ProcessPoolExecutor, futures: list[Future]) -> None:
    """Stop every worker now (a running job is abandoned) and wait for them to exit."""
    for fut in futures:
        fut.cancel()
    procs = list((getattr(pool, "_processes", None) or {}).values())
    for proc in procs:
        with contextlib.suppress(Exception):
            proc.terminate()
    pool.shutdown(wait=True, cancel_futures=True)
    for proc in procs:
        with contextlib.suppress(Exception):
            proc.join(5.0)
            if proc.is_alive():
                proc.kill()
                proc.join(5.0)


class SideWorker:
    """Jobs on one worker process beside this one, run in the order they are submitted
    (:func:`side_worker`); with ``run_here``, each job runs in this process when its result is
    asked for."""

    def __init__(self, run_here: bool) -> None:
        self.run_here = run_here
        self._pool: ProcessPoolExecutor | None = None
        self._futures: list[Future] = []

    def submit(self, job: Callable[..., T], *args: Any) -> Callable[[], T]:
        """Start ``job(*args)`` (a module-level function; it and its arguments are pickled) after
        the jobs submitted before it; returns a function that waits for it and returns its
        result, or raises its exception."""
        if self.run_here:
            return lambda: job(*args)
        with single_threaded_children(), sigint_ignored():
            if self._pool is None:
                self._pool = worker_pool(1)
            self._futures.append(self._pool.submit(job, *args))  # the first starts the worker
        return self._futures[-1].result

    def busy(self) -> bool:
        """A submitted job has not finished (never, with ``run_here``)."""
        return any(not fut.done() for fut in self._futures)

    def stop(self) -> None:
        """Let the worker exit; stopped now if a job is running or waiting (it is abandoned)."""
        if self._pool is None:
            return
        if self.busy():
            stop_pool(self._pool, self._futures)
        else:
            self._pool.shutdown(wait=True)


@contextlib.contextmanager
def side_worker(run_here: bool = False) -> Iterator[SideWorker]:
    """A :class:`SideWorker` for the block: leaving it (by an exception too) stops the worker,
    abandoning the jobs whose results were not asked for. On a machine with one usable core,
    where a second process would only take turns with this one, the jobs run here."""
    side = SideWorker(run_here or usable_cores() < 2)
    try:
        yield side
    finally:
        side.stop()
