"""Work on other local processes: fresh interpreters (``spawn``) with one BLAS/OpenMP/numba
thread each, that leave Ctrl-C to the process that started them and are stopped with it.

A terminal's Ctrl-C reaches the whole process group: the workers ignore ``SIGINT`` and the
driver alone reacts, stopping them (:func:`stop_pool`) before the interrupt propagates, so no
worker prints a traceback and none outlives the command. A worker whose driver dies without
stopping it (``SIGKILL``) ends too (Linux: the parent-death signal; elsewhere a thread that
watches its parent). ``aerodock sweep`` runs its cells this way (:mod:`aerodock.sweep.run`);
``aerodock reproduce`` its real-data study and the levers' costs beside the simulations
(:func:`side_worker`).

Workers are spawned, so they import the driver's ``__main__`` again when it is a script: a
script that starts such work runs it under ``if __name__ == "__main__":``.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import pickle
import signal
import threading
import time
from collections.abc import Callable, Iterator
from concurrent.futures import Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from typing import Any, TypeVar

T = TypeVar("T")

_THREAD_VARS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS")


def usable_cores() -> int:
    """The cores this process may run on (its affinity mask where the system has one)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


@contextlib.contextmanager
def single_threaded_children() -> Iterator[None]:
    """Child processes started inside see one thread per BLAS/OpenMP/numba pool (restored
    after): N processes on N cores, where inherited thread pools would oversubscribe them."""
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


def _worker_init(driver_pid: int) -> None:
    """A worker's initializer: ``SIGINT`` ignored (Ctrl-C is the driver's to handle: it stops
    the workers), and the worker ends when its driver dies."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        if libc.prctl(1, signal.SIGKILL) != 0:  # PR_SET_PDEATHSIG
            raise OSError(ctypes.get_errno(), "prctl")
    except (OSError, AttributeError):  # not Linux: watch the parent instead
        def watch() -> None:
            while os.getppid() == driver_pid:
                time.sleep(1.0)
            os._exit(1)

        threading.Thread(target=watch, daemon=True, name="aerodock-driver-watch").start()
    if os.getppid() != driver_pid:  # died before the signal was asked for
        os._exit(1)


def worker_pool(workers: int) -> ProcessPoolExecutor:
    """A pool of ``workers`` fresh interpreters, each with one BLAS/OpenMP/numba thread,
    ``SIGINT`` ignored, ending with this process. Its workers start with the first
    :meth:`~ProcessPoolExecutor.submit`: submit inside :func:`single_threaded_children` and
    :func:`sigint_ignored`."""
    return ProcessPoolExecutor(max_workers=workers, initializer=_worker_init,
                               initargs=(os.getpid(),),
                               mp_context=multiprocessing.get_context("spawn"))


def portable_call(job: Callable[..., T], *args: Any) -> T:
    """``job(*args)`` on a worker, its exception made fit to travel back to the driver: one
    that cannot be rebuilt there (pickled, then unpickled) is raised as its nearest built-in
    class with the same message, so the driver reports it as it would have here."""
    try:
        return job(*args)
    except Exception as err:
        try:
            pickle.loads(pickle.dumps(err))
        except Exception:  # noqa: BLE001 - any failure to travel
            base = next(c for c in type(err).__mro__ if c.__module__ == "builtins")
            raise base(str(err)) from None
        raise


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
            future = self._pool.submit(portable_call, job, *args)  # the first starts the worker
        self._futures.append(future)

        def result() -> T:
            try:
                return future.result()
            except BrokenProcessPool:
                raise RuntimeError(
                    "the worker process beside this one ended without its result (killed, or "
                    "out of memory; or a script ran this without "
                    "'if __name__ == \"__main__\":', which spawned workers need)") from None

        return result

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
