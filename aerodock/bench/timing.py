"""Timing: a figure is the median of timed repetitions after an untimed warm-up, with its spread
(the fastest and slowest repetition) and the repetition count; a part that cannot be measured
gives an unavailable figure (``value`` null) with a one-line reason."""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable
from typing import Any

SUBPROCESS_TIMEOUT_S = 1800.0  # for a part measured in a subprocess

Progress = Callable[[str], None]


def quiet(_: str) -> None:
    """A progress callback that says nothing."""


def measure(fn: Callable[[], Any], repeats: int, warmup: int = 1,
            setup: Callable[[], Any] | None = None,
            cpu_times: list[float] | None = None) -> list[float]:
    """Wall times (s) of ``repeats`` calls of ``fn`` after ``warmup`` untimed ones.

    ``setup``, if given, runs (untimed) before every call, the warm-up ones included; the
    process CPU time of each timed call is appended to ``cpu_times`` if given.
    """
    times = []
    for i in range(warmup + repeats):
        if setup is not None:
            setup()
        c0 = time.process_time()
        t0 = time.perf_counter()
        fn()
        if i >= warmup:
            times.append(time.perf_counter() - t0)
            if cpu_times is not None:
                cpu_times.append(time.process_time() - c0)
    return times


def figure(samples: list[float], unit: str, note: str | None = None) -> dict[str, Any]:
    """A figure: median of ``samples`` with its spread (min and max) and repetition count."""
    out: dict[str, Any] = {
        "value": float(statistics.median(samples)),
        "min": float(min(samples)),
        "max": float(max(samples)),
        "repeats": len(samples),
        "unit": unit,
    }
    if note:
        out["note"] = note
    return out


def unavailable(reason: str, unit: str = "") -> dict[str, Any]:
    """A figure that could not be measured, and why."""
    return {"value": None, "unit": unit, "reason": reason}


def failure_reason(err: BaseException) -> str:
    """``Type: first line of the message`` (the type alone if there is no message)."""
    text = str(err).splitlines()[0] if str(err) else ""
    return f"{type(err).__name__}: {text}" if text else type(err).__name__

