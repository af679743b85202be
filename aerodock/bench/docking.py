"""Docking: wall time of one trial and of a 100-trial campaign, and of ``aerodock reproduce
--quick`` end to end (in a subprocess)."""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from aerodock.bench.timing import (
    SUBPROCESS_TIMEOUT_S,
    Progress,
    failure_reason,
    figure,
    measure,
    quiet,
    unavailable,
)


def bench_docking(cfg: Any, quick: bool = False, progress: Progress = quiet) -> dict[str, Any]:
    """Wall time of one docking trial and of a 100-trial campaign (oracle compensation)."""
    from aerodock.mission import MissionSpec, run_campaign

    out: dict[str, Any] = {}
    for key, trials, repeats in (("trial_1", 1, 3 if quick else 5),
                                 ("campaign_100", 100, 2 if quick else 3)):
        progress(f"docking: {trials} trial(s)")
        spec = MissionSpec(trials=trials, compensation="oracle", seed=0)
        flown: list[float] = []

        def fly(spec: Any = spec, flown: list[float] = flown) -> None:
            result = run_campaign(cfg, spec, record="summary")
            flown.append(result.arrival_s)

        times = measure(fly, repeats, warmup=1 if key == "trial_1" else 0)
        out[key] = figure(times, "s", f"{trials} trial(s), {flown[-1]:g} s approach, oracle "
                          "compensation, until every trial is done")
    return out


def _aerodock_argv(*args: str) -> list[str]:
    return [sys.executable, "-c", "from aerodock.cli import main; main()", *args]


def bench_reproduce(progress: Progress = quiet,
                    config_path: Path | None = None) -> dict[str, Any]:
    """Wall time of ``aerodock reproduce --quick`` in a subprocess (one run: it takes minutes)."""
    try:
        probe = subprocess.run(_aerodock_argv("reproduce", "--help"), capture_output=True,
                               text=True, timeout=120)
    except (OSError, subprocess.SubprocessError) as err:
        return unavailable(f"not available ({failure_reason(err)})", "s")
    if probe.returncode != 0:
        return unavailable("not available", "s")
    progress("reproduce --quick (a few minutes)")
    with tempfile.TemporaryDirectory(prefix="aerodock-bench-") as tmp:
        t0 = time.perf_counter()
        try:
            extra = () if config_path is None else ("--config", str(config_path))
            run = subprocess.run(_aerodock_argv("reproduce", "--quick", "--out", tmp, *extra),
                                 capture_output=True, text=True, timeout=SUBPROCESS_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            return unavailable(f"did not finish within {SUBPROCESS_TIMEOUT_S:.0f} s", "s")
        wall = time.perf_counter() - t0
    if run.returncode != 0:
        last = (run.stderr.strip().splitlines() or ["no message"])[-1]
        return unavailable(f"exit code {run.returncode}: {last}", "s")
    return figure([wall], "s", "one run in a subprocess (includes interpreter start-up)")
