"""Memory: the peak of a large campaign, measured in a fresh process.

:func:`bench_memory` (the parent) runs this module as a script, once plainly and once under
``tracemalloc``; :func:`probe` (the child) flies the campaign and reports, as one JSON line::

    python -m aerodock.bench.memory --trials 1024 [--traced] [--config FILE]

The campaign's modules are imported when this module is, before ``tracemalloc`` starts and
before the resident set is read: ``rss_after_imports_mib`` is the process ready to fly, and
``traced_peak_mib`` counts the campaign's own allocations only.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

from aerodock.bench.timing import (
    SUBPROCESS_TIMEOUT_S,
    Progress,
    failure_reason,
    figure,
    quiet,
    unavailable,
)
from aerodock.config import load_config
from aerodock.mission import MissionSpec, run_campaign


def status_mib(key: str) -> float:
    """This process's ``/proc/self/status`` entry ``key`` (``VmRSS``, ``VmHWM``) in MiB.

    VmHWM is the peak resident set of this process image; unlike ``ru_maxrss`` it does not
    start from the parent's size (``ru_maxrss`` is inherited through fork and exec on Linux),
    which is the fallback where there is no ``/proc``.
    """
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith(key + ":"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    import resource

    scale = 1.0 / 2**20 if sys.platform == "darwin" else 1.0 / 1024.0
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * scale


def probe(trials: int, traced: bool, config_path: str | None) -> dict[str, float]:
    """Fly one ``trials``-trial campaign (oracle compensation, summary only) in this process:
    its resident set before, its peak, its wall time and (``traced``) its traced peak."""
    if traced:
        import tracemalloc

        tracemalloc.start()
    cfg = load_config(config_path)
    spec = MissionSpec(trials=trials, compensation="oracle", seed=0)
    base = status_mib("VmRSS")
    t0 = time.perf_counter()
    run_campaign(cfg, spec, record="summary")
    wall = time.perf_counter() - t0
    out = {"rss_after_imports_mib": base, "peak_rss_mib": status_mib("VmHWM"), "wall_s": wall}
    if traced:
        out["traced_peak_mib"] = tracemalloc.get_traced_memory()[1] / 2**20
    return out


def _memory_run(trials: int, traced: bool, config_path: Path | None) -> dict[str, float]:
    argv = [sys.executable, "-m", "aerodock.bench.memory", "--trials", str(trials)]
    argv += ["--traced"] if traced else []
    argv += [] if config_path is None else ["--config", str(config_path)]
    run = subprocess.run(argv, capture_output=True, text=True, timeout=SUBPROCESS_TIMEOUT_S)
    if run.returncode != 0:
        last = (run.stderr.strip().splitlines() or ["no message"])[-1]
        raise RuntimeError(f"campaign failed: {last}")
    return json.loads(run.stdout.strip().splitlines()[-1])


def bench_memory(trials: int = 1024, traced: bool = True, progress: Progress = quiet,
                 config_path: Path | None = None) -> dict[str, Any]:
    """Peak memory (MiB) of a ``trials``-trial campaign, each in a fresh subprocess.

    ``peak_rss_mib``: the process's peak resident set (interpreter, imports and campaign);
    ``rss_after_imports_mib``: its resident set before the campaign; ``traced_peak_mib`` (if
    ``traced``): the peak of the campaign's own allocations (``tracemalloc``, a second run).
    """
    progress(f"memory: {trials}-trial campaign in a subprocess")
    try:
        plain = _memory_run(trials, False, config_path)
        if traced:
            progress(f"memory: {trials}-trial campaign under tracemalloc")
            allocs = _memory_run(trials, True, config_path)
    except (OSError, subprocess.SubprocessError, RuntimeError, ValueError, IndexError) as err:
        return {"peak_rss_mib": unavailable(f"could not run ({failure_reason(err)})", "MiB")}
    what = f"{trials}-trial campaign, oracle compensation, record='summary', one run"
    out = {
        "peak_rss_mib": figure([plain["peak_rss_mib"]], "MiB",
                               f"{what}: peak resident set of the whole process"),
        "rss_after_imports_mib": figure([plain["rss_after_imports_mib"]], "MiB",
                                        "the same process before the campaign"),
        "campaign_wall_s": figure([plain["wall_s"]], "s", what),
    }
    if traced:
        out["traced_peak_mib"] = figure([allocs["traced_peak_mib"]], "MiB",
                                        f"{what}: peak of the campaign's own allocations "
                                        "(tracemalloc)")
    return out




def main(argv: list[str] | None = None) -> None:
    """The child process: :func:`probe`, printed as one JSON line."""
    parser = argparse.ArgumentParser(prog="python -m aerodock.bench.memory",
                                     description="Peak memory of one docking campaign.")
    parser.add_argument("--trials", type=int, default=1024, help="trials in the campaign")
    parser.add_argument("--traced", action="store_true", help="also trace allocations")
    parser.add_argument("--config", default=None, help="aerodock TOML file")
    args = parser.parse_args(argv)
    print(json.dumps(probe(args.trials, args.traced, args.config)))


if __name__ == "__main__":
    main()
