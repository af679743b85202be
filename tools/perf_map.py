"""Where the compiled world's time goes, by function: Linux perf with numba's functions named.

::

    AERODOCK_CACHE_DIR=$(mktemp -d) python tools/perf_map.py record --trials 1 --out perf.data
    perf report -i perf.data --no-children --sort sym     # or --sort dso: by library

    AERODOCK_CACHE_DIR=$(mktemp -d) python tools/perf_map.py census

numba's machine code carries no symbols, so perf shows its samples as bare addresses. ``record``
flies bench's ``SimLoop`` (``--trials`` trials, ``--controllers`` or the physics alone), writes
``/tmp/perf-PID.map`` (perf's map for code made at run time) naming every function of the
libraries numba compiled in this process and numba's reference counts (``NRT_incref``,
``NRT_decref``), then samples itself with ``perf record`` for ``--seconds``. ``census`` prints,
for the serial period kernel's optimized code, how many reference-count calls each function
holds (at a batch of one each runs about once a physics step).

Functions loaded from the disk cache have no compiled library to read names from: run with an
empty cache (``AERODOCK_CACHE_DIR`` a new folder), which compiles the kernels in the process
first (a few minutes). ``NUMBA_NUM_THREADS=1`` keeps the period on the serial kernel.
"""

from __future__ import annotations

import argparse
import gc
import os
import re
import signal
import subprocess
import sys
import time


def _short(name: str) -> str:
    """A numba function's name from its mangled one (the last identifier of ``_ZN...``)."""
    rest, ids = (name[3:] if name.startswith("_ZN") else name), []
    i = 0
    while i < len(rest) and rest[i].isdigit():
        j = i
        while j < len(rest) and rest[j].isdigit():
            j += 1
        size = int(rest[i:j])
        ids.append(rest[j:j + size])
        i = j + size
    return ids[-1] if ids else name


def write_perf_map() -> int:
    """``/tmp/perf-PID.map`` for this process: every function numba compiled here and its
    runtime's reference counts. Returns how many were named."""
    from numba.core.registry import CPUDispatcher
    from numba.core.runtime import nrt

    libraries = [cres.library for obj in gc.get_objects() if isinstance(obj, CPUDispatcher)
                 for cres in obj.overloads.values()]
    libraries.append(nrt.rtsys._library)
    named: dict[int, str] = {}
    for library in libraries:
        try:
            names = [f.name for f in library._final_module.functions if not f.is_declaration]
        except Exception:  # loaded from the disk cache: no module to read
            continue
        for name in names:
            address = library.get_pointer_to_function(name)
            if address:
                named[address] = _short(name)
    starts = sorted(named)
    with open(f"/tmp/perf-{os.getpid()}.map", "w") as out:
        for k, start in enumerate(starts):
            gap = starts[k + 1] - start if k + 1 < len(starts) else 1 << 16
            out.write(f"{start:x} {min(gap, 1 << 20):x} {named[start]}\n")
    return len(starts)


def census() -> list[tuple[int, int, str]]:
    """(increments, decrements, function) of the serial period kernel's optimized code, most
    first."""
    from aerodock.bench.simulator import SimLoop
    from aerodock.config import load_config
    from aerodock.world import period_kernel

    SimLoop(load_config(None), 1).run(2)
    code = next(iter(period_kernel.period_kernel.overloads.values())).library.get_llvm_str()
    rows = []
    for body in code.split("\ndefine ")[1:]:
        name = re.search(r'@"?([^"(]+)', body).group(1)
        rows.append((body.count("call void @NRT_incref"), body.count("call void @NRT_decref"),
                     _short(name)))
    return sorted(rows, key=lambda r: -(r[0] + r[1]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="what", required=True)
    rec = sub.add_parser("record", help="fly SimLoop under perf with numba's functions named")
    rec.add_argument("--trials", type=int, default=1)
    rec.add_argument("--controllers", action="store_true")
    rec.add_argument("--seconds", type=float, default=20.0)
    rec.add_argument("--out", default="perf.data")
    rec.add_argument("--warm", type=int, default=2,
                     help="rounds of 100 periods flown before recording (after the first "
                          "compile: what a later period compiles, or collects, stays out)")
    sub.add_parser("census", help="reference-count calls per function of the period kernel")
    args = parser.parse_args()
    if args.what == "census":
        rows = census()
        print(f"{sum(r[0] for r in rows)} increments, {sum(r[1] for r in rows)} decrements")
        for inc, dec, name in rows[:25]:
            print(f"{inc + dec:6d} {inc:6d} {dec:6d}  {name}")
        return
    from aerodock.bench.simulator import SimLoop
    from aerodock.config import load_config

    loop = SimLoop(load_config(None), args.trials)
    loop.run(3, args.controllers)  # compiles (an empty cache: minutes)
    for _ in range(args.warm):
        loop.reset()
        loop.run(100, args.controllers)
    print(f"named {write_perf_map()} functions; recording {args.seconds:g} s", file=sys.stderr)
    perf = subprocess.Popen(["perf", "record", "-q", "-p", str(os.getpid()), "-o", args.out])
    start = time.time()
    while time.time() - start < args.seconds:
        loop.reset()
        loop.run(100, args.controllers)
    perf.send_signal(signal.SIGINT)  # perf writes its file and stops
    perf.wait()
    print(f"perf report -i {args.out} --no-children --sort sym", file=sys.stderr)


if __name__ == "__main__":
    main()
