"""The outside audit of issue 25, as a user would run it: many ``aerodock`` command lines with
damaged and odd inputs, each in its own process, watched from outside.

::

    nice -n 15 python tools/audit.py --runs 2000 --seed 0 --out audit.json

1. **Setup**: files made by aerodock itself, in a scratch folder (never the repository): a
   config (the package's defaults, and a small point-mass one), a FlightLog from ``dock
   --save-logs``, a generic CSV of it, a model from ``train``, a sweep spec, a fault file, a
   topic mapping; also a FIFO, a folder, an empty and a binary file, a sparse 4 GiB file, a
   non-UTF-8 name, the shared ULog and Neural-Swarm CSV (read in place).
2. **Runs**: ``--runs`` command lines from seeded random draws, round-robin over every command
   (``aerodock --help``'s, and ``field``'s three): each input option gets a good file, a copy
   with damaged bytes, a TOML file with one value made odd (NaN, huge, negative, wrong type),
   ``/dev/zero``, the FIFO, a folder, a missing path, a non-UTF-8 name...; numbers and words
   come from valid choices or from odd ones (``NASTY_CLI``); sweeps get huge sizes and configs
   long simulated times. Every run is a subprocess of its own, in its own folder, with a
   timeout (a timeout is a hang: its process group is killed), at most ``--jobs`` at a time.
   Recorded: exit code, peak RSS (``os.wait4``'s ``ru_maxrss``, KiB), a ``Traceback`` on
   stderr, the number of ``error:`` lines of a failing run, strict JSON (no NaN) on ``--json``
   success.
3. **model.json**: every key path of a trained model's ``model.json`` changed alone (numbers
   perturbed, strings changed, booleans flipped, lists shortened, keys dropped, the kind
   swapped), loaded through ``aerodock field probe --model``. A change the CLI accepts is
   compared with the original model: a probe through the CLI and, in this process, the
   predictions of both on 2,000 random states; accepted and altering is a failure. The same
   changes are also tried *re-sealed* (the checksum recomputed, as a deliberate edit would),
   which leaves only the plausibility checks between the edit and the prediction: reported,
   not counted against the target.

The JSON summary goes to ``--out``; a one-screen text summary to stdout. The exit status is 0
when no run broke an invariant (exit code 0 or 2, no traceback, one ``error:`` line, strict
JSON, no hang, RSS under ``--max-rss-mb``) and no plain model.json change was accepted and
altering, else 1.
"""

from __future__ import annotations

import argparse
import copy
import hashlib
import json
import math
import os
import random
import shlex
import shutil
import signal
import sys
import tempfile
import threading
import time
import tomllib
from collections import Counter
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tests" / "fuzz"))
from fuzz_helpers import NASTY_CLI, NASTY_VALUES, has_nan, mutate_bytes, toml_value  # noqa: E402

ENTRY = "from aerodock.cli import main; main()"
SHARED = Path(os.environ.get("AERODOCK_SHARED_DATA", "/work/shared/data"))
NON_UTF8 = b"\xff\xfe-odd"  # a file name that is not UTF-8

# Every command line the audit draws from, round-robin (aerodock --help, and field's three).
COMMANDS = ["dock", "faults", "bench", "ingest", "train", "evaluate", "evaluate-compensation",
            "export", "node", "view", "sweep", "collect", "reproduce", "targets",
            "field probe", "field plot", "field fit"]


# Options that take no value: a "--json" after any other option is that option's value.
FLAGS = {"--json", "--quick", "--smoke", "--no-real-data", "--single", "--spectral-norm", "--bar",
         "--leader-fixed", "--no-leader-fixed", "--markdown", "--no-markdown", "--help"}
BLOCKED_CPU_FRACTION = 0.1  # a timed-out run below this CPU share was waiting, not computing


def _reject_constant(name: str) -> Any:
    raise ValueError(f"invalid JSON constant {name}")


# --------------------------------------------------------------------------------------------
# Running one command line from outside

@dataclass
class Run:
    """One audited process."""

    index: int
    command: str
    argv: list[str]
    rc: int | None = None
    hang: bool = False
    seconds: float = 0.0
    maxrss_kib: int = 0
    cpu_s: float = 0.0
    traceback: bool = False
    error_lines: int = 0
    json_checked: bool = False
    json_ok: bool = True
    json_problem: str = ""
    stderr_tail: str = ""
    problems: list[str] = field(default_factory=list)


def spawn(cli: list[str], args: list[Any], cwd: Path, timeout_s: float,
          env: dict[str, str] | None = None
          ) -> tuple[int | None, bool, float, int, bytes, bytes, float]:
    """Run ``cli + args`` in ``cwd`` in a new process group; ``(rc, hang, seconds, maxrss_kib,
    stdout, stderr, cpu_s)`` (CPU: user + system, with the children it waited for; for a run
    killed at the timeout, its whole group's, :func:`group_cpu_seconds`). A run past
    ``timeout_s`` is killed (its whole group) and flagged a hang;
    ``rc`` is negative for a signal, as :func:`os.waitstatus_to_exitcode` gives it."""
    import subprocess

    argv = [os.fsencode(a) if isinstance(a, (str, Path)) else a for a in cli + list(args)]
    out_path, err_path = cwd / ".audit.stdout", cwd / ".audit.stderr"
    with open(out_path, "wb") as out, open(err_path, "wb") as err:
        t0 = time.monotonic()
        proc = subprocess.Popen(argv, cwd=cwd, stdin=subprocess.DEVNULL, stdout=out, stderr=err,
                                start_new_session=True, env=env)
        hang = False
        while True:
            pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
            if pid:
                break
            if time.monotonic() - t0 > timeout_s:
                hang = True
                group_cpu_s = group_cpu_seconds(proc.pid)  # before the kill: a pool's workers
                try:
                    os.killpg(proc.pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
                pid, status, usage = os.wait4(proc.pid, 0)
                break
            time.sleep(0.02)
        seconds = time.monotonic() - t0
        proc.returncode = os.waitstatus_to_exitcode(status)  # reaped here: keep Popen quiet
    if not hang:  # workers the run left behind (a pool, Ray) go with their group
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
    cpu_s = usage.ru_utime + usage.ru_stime
    if hang:  # the killed group's CPU: the processes alive at the kill, plus what was reaped
        cpu_s = max(cpu_s, group_cpu_s)
    return (None if hang else proc.returncode, hang, seconds, usage.ru_maxrss,
            out_path.read_bytes(), err_path.read_bytes(), cpu_s)


def group_cpu_seconds(pgid: int) -> float:
    """CPU seconds (user + system, children they reaped included) of every live process in
    process group ``pgid``, from ``/proc``: a run whose work is in pool workers it has not
    reaped computes in them, which ``wait4`` on the leader alone does not see (0 off Linux)."""
    ticks = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100
    total = 0
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except (OSError, IndexError):
            continue  # gone meanwhile
        # after the command name: state ppid pgrp ... utime(12) stime(13) cutime(14) cstime(15)
        if int(fields[2]) == pgid:
            total += sum(int(v) for v in fields[11:15])
    return total / ticks


def judge(run: Run, args: list[Any], stdout: bytes, stderr: bytes, max_rss_kib: int) -> None:
    """Fill in a run's verdicts (the invariants of tests/fuzz/fuzz_helpers.py, from outside)."""
    err = stderr.decode("utf-8", "replace")
    out = stdout.decode("utf-8", "replace")
    run.traceback = "Traceback" in err or "Traceback" in out
    run.error_lines = sum(1 for line in err.splitlines() if line.startswith("error:"))
    run.stderr_tail = "\n".join(err.strip().splitlines()[-3:])[-600:]
    if run.hang:
        run.problems.append("hang")
    elif run.rc not in (0, 2):
        run.problems.append(f"exit code {run.rc}")
    if run.traceback:
        run.problems.append("traceback")
    if run.rc not in (0, None) and run.error_lines != 1:
        run.problems.append(f"{run.error_lines} 'error:' lines")
    if run.maxrss_kib > max_rss_kib:
        run.problems.append(f"RSS {run.maxrss_kib / 1024:.0f} MB")
    strs = [a if isinstance(a, str) else "" for a in args]
    json_flag = any(a == "--json" and (i == 0 or not strs[i - 1].startswith("-")
                                       or strs[i - 1] in FLAGS) for i, a in enumerate(strs))
    if run.rc == 0 and json_flag and "--help" not in strs:
        run.json_checked = True
        try:
            doc = json.loads(out, parse_constant=_reject_constant)
        except ValueError as exc:
            run.json_ok, run.json_problem = False, str(exc)[:200]
        else:
            if has_nan(doc):
                run.json_ok, run.json_problem = False, "NaN in JSON"
        if not run.json_ok:
            run.problems.append(f"invalid JSON ({run.json_problem})")


def show(args: list[Any]) -> str:
    """A command line as text (a non-UTF-8 name shown with its escapes)."""
    return " ".join(shlex.quote(os.fsdecode(a) if isinstance(a, bytes) else str(a))
                    for a in args)


# --------------------------------------------------------------------------------------------
# Setup: real files, made by aerodock

def dump_toml(doc: dict[str, Any]) -> str:
    """A TOML document (tables, arrays of tables and values; odd values in TOML's spelling)."""
    lines = [f"{k} = {toml_value(v)}" for k, v in doc.items()
             if not isinstance(v, dict) and not (isinstance(v, list) and v
                                                 and all(isinstance(x, dict) for x in v))]

    def table(prefix: str, tab: dict[str, Any]) -> None:
        lines.append(f"[{prefix}]")
        subs = []
        for k, v in tab.items():
            if isinstance(v, dict):
                subs.append((k, v))
            else:
                lines.append(f"{k} = {toml_value(v)}")
        for k, v in subs:
            table(f"{prefix}.{k}", v)

    for k, v in doc.items():
        if isinstance(v, dict):
            table(k, v)
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            for item in v:
                lines.append(f"[[{k}]]")
                lines += [f"{kk} = {toml_value(vv)}" for kk, vv in item.items()]
    return "\n".join(lines) + "\n"


def leaf_paths(doc: Any, prefix: tuple = ()) -> list[tuple]:
    """Every key path to a value that is not a dict (list items of dicts are walked too)."""
    if isinstance(doc, dict):
        if not doc and prefix:
            return [prefix]
        return [p for k, v in doc.items() for p in leaf_paths(v, prefix + (k,))]
    if isinstance(doc, list) and doc and all(isinstance(x, dict) for x in doc):
        return [p for i, v in enumerate(doc) for p in leaf_paths(v, prefix + (i,))]
    return [prefix]


def get_path(doc: Any, path: tuple) -> Any:
    for k in path:
        doc = doc[k]
    return doc


def set_path(doc: Any, path: tuple, value: Any) -> None:
    for k in path[:-1]:
        doc = doc[k]
    doc[path[-1]] = value


SMALL_CONFIG = """[vehicle]
model = "point-mass"
[curriculum]
stage0_depth_m = [0.5, 0.6]
min_depth_m = 0.5
deep_depths_m = []
flights_per_stage = 1
"""

SWEEP_SPEC = """[sweep]
name = "audit"
kind = "grid"
trials = 1
seeds = [0]
config = "small.toml"

[axes]
cable_length_m = [0.36]
leader_speed_mps = [0.0]
"""

MAPPING = """frame = "enu"
time = "header"
max_gap_s = 0.25
[leader]
state = "/alpha/current_state"
[follower]
state = "/bravo/current_state"
command = ["/bravo/controller_debug", "/bravo/rpyt_command"]
"""


def setup(base: Path, cli: list[str], timeout_s: float) -> dict[str, Path]:
    """The good inputs, made once per scratch folder (reused when ``base/ready`` exists)."""
    files = {
        "config": base / "config.toml", "small": base / "small.toml",
        "log": base / "logs" / "dock-observer-seed1.npz", "csv": base / "flight.csv",
        "model": base / "model", "sweep": base / "sweep.toml", "faults": base / "faults.toml",
        "mapping": base / "mapping.toml", "onnx": base / "model.onnx",
        "ulog": SHARED / "px4-ulog" / "sample_log_small.ulg",
        "nscsv": SHARED / "neural-swarm" / "swap_ss" / "cf50_00.csv",
        "fifo": base / "fifo", "folder": base / "folder", "empty": base / "empty.toml",
        "binary": base / "binary.bin", "sparse": base / "sparse.toml",
        "nonutf8": Path(os.fsdecode(bytes(base) + b"/" + NON_UTF8 + b".toml")),
    }
    if (base / "ready").exists():
        return files
    base.mkdir(parents=True, exist_ok=True)
    shutil.copy(REPO / "aerodock" / "config" / "defaults.toml", files["config"])
    files["small"].write_text(SMALL_CONFIG)
    for args in (["dock", "--trials", "2", "--seed", "1", "--config", files["small"],
                  "--save-logs", base / "logs"],
                 ["train", "--data", files["log"], "--out", files["model"], "--max-epochs", "3"]):
        rc, hang, _, _, _, err, _ = spawn(cli, args, base, max(600.0, timeout_s * 5))
        if rc != 0:
            raise SystemExit(f"audit setup failed: aerodock {show(args)} -> {rc}: "
                             f"{err.decode(errors='replace')[-500:]}")
    from aerodock.flightlog import load_flightlogs
    from aerodock.ingest.csv_generic import write_csv

    write_csv(load_flightlogs(files["log"])[0], files["csv"])
    files["sweep"].write_text(SWEEP_SPEC)
    faults = tomllib.loads((REPO / "examples" / "faults.toml").read_text())
    files["faults"].write_text(dump_toml({"fault": faults["fault"][:2]}))
    files["mapping"].write_text(MAPPING)
    if not files["fifo"].exists():
        os.mkfifo(files["fifo"])
    files["folder"].mkdir(exist_ok=True)
    files["empty"].write_bytes(b"")
    files["binary"].write_bytes(bytes(random.Random(1).randrange(256) for _ in range(4096)))
    with open(files["sparse"], "wb") as f:  # 4 GiB of holes: costs no disk
        f.truncate(4 << 30)
    shutil.copy(files["small"], files["nonutf8"])  # a valid small config with an odd name
    (base / "ready").write_text("ok\n")
    return files


# --------------------------------------------------------------------------------------------
# Drawing command lines

class Draw:
    """Seeded draws of inputs and values for one run (files land in the run's folder)."""

    def __init__(self, rng: random.Random, files: dict[str, Path], run_dir: Path) -> None:
        self.rng, self.files, self.dir, self.n = rng, files, run_dir, 0

    def p(self, prob: float) -> bool:
        return self.rng.random() < prob

    def odd(self) -> str:
        return self.rng.choice(NASTY_CLI)

    def value(self, *good: Any, odd: float = 0.3) -> str:
        """A valid choice, or (with probability ``odd``) an odd one."""
        return self.odd() if self.p(odd) else str(self.rng.choice(good))

    def _new(self, suffix: str) -> Path:
        self.n += 1
        return self.dir / f"in{self.n}{suffix}"

    def special(self, small_only: bool = False) -> Any:
        """Something that is not the file asked for (``small_only``: never an empty file, a
        config of the defaults for commands that run long with them)."""
        f = self.files
        return self.rng.choice([
            "/dev/zero", "/dev/null", f["fifo"], f["folder"], f["binary"],
            *([] if small_only else [f["empty"]]),
            f["sparse"], self.dir / "missing.toml", "", "-", os.fsencode(f["nonutf8"]),
            "/proc/self/mem", "/etc/shadow"])

    def damaged(self, src: Path, suffix: str) -> Path:
        """A copy of ``src`` with byte damage (big files: their first 64 KiB only)."""
        with open(src, "rb") as fh:
            blob = fh.read(1 << 16)
        for _ in range(self.rng.randint(1, 3)):
            blob = mutate_bytes(blob, self.rng)
        out = self._new(suffix)
        out.write_bytes(blob)
        return out

    def odd_toml(self, src: Path) -> Path:
        """A TOML file with one value (or a new key) made odd."""
        doc = tomllib.loads(src.read_text())
        paths = leaf_paths(doc)
        if paths and self.p(0.9):
            path = self.rng.choice(paths)
            if self.p(0.5) and isinstance(get_path(doc, path), (int, float)) \
                    and not isinstance(get_path(doc, path), bool):
                v = get_path(doc, path)
                value = self.rng.choice([v * 1e6, -v, v * 1e300, 1e308, -1, 0, 2**63,
                                         float("nan"), float("inf"), str(v), [v]])
            else:
                value = self.rng.choice(NASTY_VALUES)
            if value is None:  # a dropped key
                parent = get_path(doc, path[:-1])
                del parent[path[-1]]
            else:
                set_path(doc, path, value)
        else:
            doc.setdefault("extra", {})["banana"] = 1
        out = self._new(".toml")
        out.write_text(dump_toml(doc))
        return out

    def long_config(self) -> Path:
        """A config whose simulated time (or physics rate) is far longer than usual."""
        key = self.rng.choice([("mission", "settle_s", 600), ("mission", "dock_window_s", 900),
                               ("mission", "backoff_s", 600), ("sim", "physics_rate_hz", 20000),
                               ("mission", "post_dock_s", 1e5), ("mission", "leader_ramp_s", 1e4),
                               ("planner", "hold_s", 3600), ("planner", "horizon_hover_s", 1e4),
                               ("sim", "control_rate_hz", 1e6),
                               ("curriculum", "flights_per_stage", 100000),
                               ("curriculum", "deep_flights_per_stage", 10**9)])
        doc = tomllib.loads(self.files["small"].read_text())
        doc.setdefault(key[0], {})[key[1]] = key[2]
        out = self._new(".toml")
        out.write_text(dump_toml(doc))
        return out

    def input(self, kind: str, small_only: bool = False) -> Any:
        """An input of ``kind`` (a key of the setup files): good, damaged, odd or not a file."""
        src = self.files[kind]
        r = self.rng.random()
        if r < 0.3:
            return src
        if r < 0.55 or src.is_dir():
            if src.is_dir():  # a model folder: damage one of its files in a copy
                out = self._new("")
                shutil.copytree(src, out)
                name = self.rng.choice(sorted(p.name for p in out.iterdir()))
                blob = mutate_bytes((out / name).read_bytes(), self.rng)
                (out / name).write_bytes(blob)
                return out
            return self.damaged(src, src.suffix)
        if r < 0.75 and src.suffix == ".toml":
            return self.odd_toml(src)
        return self.special(small_only)

    def config(self, small_only: bool = False) -> Any:
        """A config: the small one, one with long simulated times, or either one damaged;
        ``small_only``: the package's defaults never (a command that flies a curriculum or a
        whole study with them runs for minutes, legitimately)."""
        r = self.rng.random()
        if r < 0.35:
            return self.files["small"]
        if r < 0.5:
            return self.long_config()
        if small_only:
            return self.input("small", small_only=True)
        return self.input(self.rng.choice(["config", "small"]))

    def out_path(self, suffix: str) -> Any:
        """Where to write: usually fresh, sometimes odd."""
        if self.p(0.8):
            return self.dir / f"out{suffix}"
        return self.rng.choice(["/dev/null", self.files["fifo"], self.files["folder"],
                                self.dir / "no" / "such" / f"dir{suffix}",
                                os.fsencode(self.dir) + b"/" + NON_UTF8 + suffix.encode(),
                                "", "/proc/version", self.odd()])

    def sweep_spec(self) -> Any:
        r = self.rng.random()
        if r < 0.45:
            return self.input("sweep")
        doc = tomllib.loads(self.files["sweep"].read_text())
        doc["sweep"]["config"] = str(self.files["small"])
        big = self.rng.choice([
            ("sweep", "trials", 100_000_000), ("sweep", "trials", 10**6),
            ("sweep", "seeds", list(range(5000))), ("sweep", "kind", "random"),
            ("sweep", "samples", 100_000_000), ("sweep", "samples", 1e8),
            ("axes", "cable_length_m", [0.3 + i * 1e-5 for i in range(3000)]),
            ("axes", "leader_speed_mps", [0.0, 1e6]), ("axes", "compensation", ["banana"]),
            ("sweep", "config", "/dev/zero"), ("sweep", "config", str(self.files["fifo"])),
            ("sweep", "config", str(self.long_config())),
            ("axes", "mocap_noise_scale", [1.0, 1e5]), ("axes", "leader_dropout_s", [[3.0, 1e9]])])
        if big == ("sweep", "kind", "random"):
            doc["sweep"]["samples"] = self.rng.choice([1, 2, 10**7, -1])
        doc[big[0]][big[1]] = big[2]
        out = self._new(".toml")
        out.write_text(dump_toml(doc))
        return out

    def trials(self) -> list[str]:
        return ["--trials", self.rng.choice(["1", "1", "1", "2", "100000", "10000000",
                                             self.odd()])]


def _opt(d: Draw, args: list[Any], prob: float, *opt: Any) -> None:
    if d.p(prob):
        args.extend(opt)


def gen(command: str, d: Draw) -> list[Any]:
    """One command line for ``command`` (a list of str, Path or bytes)."""
    f, r = d.files, d.rng
    model = lambda: d.input("model")  # noqa: E731
    if command == "dock":
        a: list[Any] = ["dock", *d.trials()]
        comp = d.value("none", "observer", "model", "oracle", "banana", odd=0.1)
        a += ["--compensation", comp]
        if comp == "model" or d.p(0.2):
            a += ["--model", model()]
        _opt(d, a, 0.3, "--offset", d.value(0.27, 0.36, 0.64, 1.2))
        _opt(d, a, 0.3, "--leader-speed", d.value(0.0, 0.25, 0.5))
        _opt(d, a, 0.2, r.choice(["--leader-fixed", "--no-leader-fixed"]))
        _opt(d, a, 0.3, "--controller", d.value("paper", "tuned", "ours"))
        _opt(d, a, 0.3, "--faults", d.input("faults"))
        _opt(d, a, 0.3, "--seed", d.value(0, 1, 7))
        _opt(d, a, 0.2, "--save-logs", d.out_path(""))
        a += ["--config", d.config()]
        _opt(d, a, 0.7, "--json")
    elif command == "faults":
        a = ["faults", d.input("faults"), *d.trials()]
        comp = d.value("none", "observer", "model", "oracle", odd=0.1)
        a += ["--compensation", comp]
        if comp == "model" or d.p(0.1):
            a += ["--model", model()]
        _opt(d, a, 0.3, "--seed", d.value(0, 3))
        a += ["--config", d.config(small_only=True)]
        _opt(d, a, 0.3, r.choice(["--markdown", "--no-markdown"]))
        _opt(d, a, 0.6, "--json")
    elif command == "bench":
        # predictor only: every other part measures for minutes by design
        a = ["bench", "--quick", "--only", d.value("predictor", "banana", odd=0.2)]
        _opt(d, a, 0.6, "--config", d.config())
        _opt(d, a, 0.6, "--json")
    elif command == "ingest":
        fmt = d.value("neural-swarm", "csv", "rosbag", "ulog", odd=0.1)
        src = {"neural-swarm": "nscsv", "csv": "csv", "ulog": "ulog"}.get(fmt, "log")
        a = ["ingest", "--format", fmt, d.input(src)]
        if fmt == "ulog" and d.p(0.3):
            a.append(d.input("ulog"))
        a += ["--out", d.out_path(".npz")]
        _opt(d, a, 0.2, "--mass-kg", d.value(0.032, 0.7))
        _opt(d, a, 0.2, "--vehicle", d.value("small", "large", "cf50=small,cf51=large"))
        _opt(d, a, 0.3 if fmt == "rosbag" else 0.1, "--mapping", d.input("mapping"))
        _opt(d, a, 0.3 if fmt == "ulog" else 0.05, "--single")
        _opt(d, a, 0.2, "--hover-thrust", d.value(0.3, 0.5))
        _opt(d, a, 0.6, "--json")
    elif command == "train":
        a = ["train", "--data", d.input(r.choice(["log", "log", "csv"]))]
        _opt(d, a, 0.2, d.input("log"))
        a += ["--out", d.out_path(""), "--max-epochs", d.value(1, 2, 3, odd=0.15)]
        _opt(d, a, 0.4, "--model", d.value("so2", "so2-ext", "so2-wrench", "so2-leader", "mlp",
                                           "zero"))
        _opt(d, a, 0.2, "--minutes", d.value(0.05, 0.1))
        _opt(d, a, 0.2, "--seed", d.value(0, 1))
        _opt(d, a, 0.1, "--spectral-norm")
        _opt(d, a, 0.3, "--split", d.value("auto", "flight", "time-blocks"))
        _opt(d, a, 0.2, "--curve", d.out_path(".png"))
        _opt(d, a, 0.6, "--json")
    elif command == "evaluate":
        a = ["evaluate", "--model", model(), "--data", d.input("log")]
        _opt(d, a, 0.3, "--lateral-radius", d.value(0.1, 0.2, 0.5))
        _opt(d, a, 0.7, "--json")
    elif command == "evaluate-compensation":
        a = ["evaluate-compensation", "--model", model()]
        _opt(d, a, 0.3, "--data", r.choice([d.special(), f["folder"], SHARED / "neural-swarm"]))
        _opt(d, a, 0.2, "--kind", d.value("so2", "mlp"))
        _opt(d, a, 0.5, "--quick")
        _opt(d, a, 0.3, "--warmup", d.value(0.5, 2.0))
        _opt(d, a, 0.3, "--lateral-radius", d.value(0.1, 0.2))
        _opt(d, a, 0.2, "--figure", d.out_path(".png"))
        _opt(d, a, 0.5, "--config", d.config())
        _opt(d, a, 0.2, "--seed", d.value(0, 1))
        _opt(d, a, 0.6, "--json")
    elif command == "export":
        a = ["export", "--model", model(), "--out", d.out_path(".onnx")]
        _opt(d, a, 0.4, "--dtype", d.value("float32", "float64"))
        _opt(d, a, 0.6, "--json")
    elif command == "node":
        a = ["node", "--model", model(), "--duration", d.value(0.5, 1.0, odd=0.1)]
        _opt(d, a, 0.3, "--mapping", d.input("mapping"))
        _opt(d, a, 0.3, "--rate", d.value(50, 100))
        _opt(d, a, 0.2, "--publish", d.value("on-follower", "timer"))
        _opt(d, a, 0.2, "--max-age", d.value(0.05, 0.1))
        _opt(d, a, 0.3, "--output-topic", d.value("/aerodock/f_ext", "/a//b", "", "bad topic"))
        _opt(d, a, 0.3, "--diagnostics-topic", d.value("/aerodock/diag", "", "1abc", "/x/"))
        _opt(d, a, 0.2, "--output-frame", d.value("auto", "ned", "enu"))
        _opt(d, a, 0.2, "--state-type", d.value("/bravo/odom=nav_msgs/msg/Odometry", "=", "x"))
        _opt(d, a, 0.3, "--config", d.config())
    elif command == "view":
        a = ["view", d.input("log"), "--out", d.out_path(r.choice([".gif", ".gif", ".mp4"])),
             "--max-frames", d.value(2, 5, odd=0.15)]
        _opt(d, a, 0.2, "--flight", d.value(0, 1, 5))
        _opt(d, a, 0.2, "--fps", d.value(5, 15))
        _opt(d, a, 0.2, "--speed", d.value(0.5, 1, 4))
        _opt(d, a, 0.2, "--start", d.value(0, 1.5))
        _opt(d, a, 0.2, "--duration", d.value(1, 2))
        _opt(d, a, 0.15, "--rerun", d.out_path(".rrd"))
        _opt(d, a, 0.3, "--config", d.config())
    elif command == "sweep":
        a = ["sweep", d.sweep_spec(), "--out", d.out_path("")]
        _opt(d, a, 0.1, "--backend", d.value("local", "ray"))
        _opt(d, a, 0.05, "--address", d.value("ray://127.0.0.1:1", "banana"))
        a += ["--jobs", d.value(1, 2, odd=0.2)]
        _opt(d, a, 0.6, "--json")
    elif command == "collect":
        a = ["collect", "--out", d.out_path(""), "--config", d.config(small_only=True)]
        _opt(d, a, 0.3, "--model", d.value("so2", "mlp", "so2-ext"))
        _opt(d, a, 0.3, "--seed", d.value(0, 1))
        _opt(d, a, 0.6, "--json")
    elif command == "reproduce":
        # Even --smoke with the small config takes over 60 s here: only odd configs (a damaged
        # one that is still valid runs long, legitimately; such a hang says so in its tail).
        cfg = d.input("small", True) if d.p(0.6) else d.long_config()
        while cfg in (d.files["small"], os.fsencode(d.files["nonutf8"])):
            cfg = d.input("small", True)
        a = ["reproduce", "--smoke", "--no-real-data", "--out", d.out_path(""), "--config", cfg]
        _opt(d, a, 0.2, "--seed", d.value(0, 1))
    elif command == "targets":
        # one trial: it flies four scenarios for two controllers (about 30 s here)
        a = ["targets", "--model", model(), "--trials", d.value(1, odd=0.3), "--out",
             d.out_path(""),
             "--config", d.config(small_only=True)]
        _opt(d, a, 0.2, "--seed", d.value(0, 1))
        _opt(d, a, 0.6, "--json")
    elif command == "field probe":
        a = ["field", "probe", "--separation", d.value(0.27, 0.36, 1.0),
             "--radial", d.value(0.0, 0.1), "--samples",
             r.choice(["10", "100", "1000", "100000000", "1e8", d.odd()])]
        _opt(d, a, 0.3, "--leader-speed", d.value(0.0, 0.5))
        _opt(d, a, 0.4, "--model", model())
        _opt(d, a, 0.2, "--bar")
        _opt(d, a, 0.6, "--config", d.config())
        _opt(d, a, 0.2, "--seed", d.value(0, 1))
        _opt(d, a, 0.7, "--json")
    elif command == "field plot":
        a = ["field", "plot", "--out", d.out_path(".png")]
        _opt(d, a, 0.3, "--leader-speed", d.value(0.0, 0.5))
        _opt(d, a, 0.4, "--model", model())
        _opt(d, a, 0.6, "--config", d.config())
    elif command == "field fit":
        a = ["field", "fit", d.input("log")]
        _opt(d, a, 0.3, d.input("log"))
        a += ["--bootstrap", d.value(0, 1, 2, odd=0.15), "--out", d.out_path("")]
        _opt(d, a, 0.2, "--holdout", d.value("dock*", "[", "x"))
        _opt(d, a, 0.1, "--estimate-rotor", d.value("leader", "follower", "nobody"))
        _opt(d, a, 0.2, "--config-out", d.out_path(".toml"))
        _opt(d, a, 0.4, "--config", d.config())
        _opt(d, a, 0.2, "--seed", d.value(0, 1))
        _opt(d, a, 0.5, "--json")
    else:
        raise ValueError(command)
    if d.p(0.02):  # an unknown option, or --help
        a.insert(r.randrange(1, len(a) + 1), r.choice(["--banana", "--help", "--json=3"]))
    return a


# --------------------------------------------------------------------------------------------
# model.json: every field changed alone

def model_changes(doc: dict[str, Any]) -> list[tuple[str, dict[str, Any]]]:
    """``(description, changed document)`` for every single-field change of ``doc``."""
    out: list[tuple[str, dict[str, Any]]] = []

    def add(desc: str, path: tuple, value: Any, drop: bool = False) -> None:
        new = copy.deepcopy(doc)
        if drop:
            del get_path(new, path[:-1])[path[-1]]
        else:
            set_path(new, path, value)
        out.append((desc, new))

    def walk(node: Any, path: tuple) -> None:
        name = ".".join(map(str, path))
        if isinstance(node, dict):
            for k, v in node.items():
                walk(v, path + (k,))
            if path:
                add(f"{name}: an extra key", path + ("audit_extra",), 1)
        elif isinstance(node, list):
            if node:
                add(f"{name}: shortened", path, node[:-1])
                add(f"{name}: one item more", path, node + [node[-1]])
            if node and all(isinstance(x, (int, float)) and not isinstance(x, bool)
                            for x in node):
                for i, x in enumerate(node[:8]):  # each number of short lists, e.g. norms
                    add(f"{name}[{i}]: perturbed", path + (i,), _perturb(x))
                    add(f"{name}[{i}]: sign flipped", path + (i,), -x if x else 1.0)
            elif node and all(isinstance(x, str) for x in node):
                add(f"{name}[0]: changed", path + (0,), node[0] + "x")
                if len(node) > 1:
                    add(f"{name}: reordered", path, node[::-1])
        elif isinstance(node, bool):
            add(f"{name}: flipped", path, not node)
        elif isinstance(node, (int, float)):
            add(f"{name}: perturbed", path, _perturb(node))
            add(f"{name}: string", path, str(node))
        elif isinstance(node, str):
            add(f"{name}: changed", path, node + "x" if len(node) != 64 else node[::-1])
        elif node is None:
            add(f"{name}: 0 instead of null", path, 0)
        if path and not (isinstance(path[-1], int)):
            add(f"{name}: dropped", path, None, drop=True)

    walk(doc, ())
    for kind in ("zero", "so2", "so2-ext", "so2-wrench", "so2-leader", "mlp"):
        if kind != doc.get("kind"):
            add(f"kind: {kind}", ("kind",), kind)
    return out


def _perturb(x: Any) -> Any:
    if isinstance(x, int):
        return x + 1
    return x * 1.01 + 1e-3 if math.isfinite(x) else 0.0


def reseal(doc: dict[str, Any]) -> dict[str, Any]:
    """The document with its checksum recomputed (as aerodock computes it)."""
    from aerodock.learning.modelfile import CHECKSUM_KEY

    body = {k: v for k, v in doc.items() if k != CHECKSUM_KEY}
    text = json.dumps(body, sort_keys=True, separators=(",", ":"), ensure_ascii=True)
    return {**doc, CHECKSUM_KEY: hashlib.sha256(text.encode("ascii")).hexdigest()}


PROBES = [["--separation", "0.36", "--radial", "0.05", "--leader-speed", "0.25"]]


def _numbers(outs: list[str] | None) -> Any:
    """The probes' JSON without ``source`` (the model's path, which differs by design)."""
    if outs is None:
        return None
    docs = [json.loads(o) for o in outs]
    for doc in docs:
        doc.pop("source", None)
    return docs


def predictions(model: Path) -> Any:
    """The model's predictions (force, and torque when it has one) on 2,000 fixed random states,
    loaded by aerodock's own loader; None if it does not load."""
    import numpy as np

    from aerodock.learning.runtime import Predictor

    try:
        pred = Predictor.load(model)
    except Exception:  # noqa: BLE001 - refused here too: nothing to compare
        return None
    rng = np.random.default_rng(0)
    n = 2000
    x = np.concatenate([rng.uniform([-0.5, -0.5, 0.1], [0.5, 0.5, 1.8], (n, 3)),
                        rng.normal(0, 0.3, (n, 6))], axis=1)
    ang = rng.normal(0, 0.1, n)
    rot = np.tile(np.eye(3), (n, 1, 1))
    rot[:, 0, 0] = rot[:, 1, 1] = np.cos(ang)
    rot[:, 0, 1], rot[:, 1, 0] = -np.sin(ang), np.sin(ang)
    try:
        with np.errstate(all="ignore"):
            out = [np.asarray(pred.predict(x, rot))]
            if pred.has_torque:
                out.append(np.asarray(pred.predict_torque(x, rot)))
    except Exception as exc:  # noqa: BLE001 - loads, then cannot predict: altered
        return [np.asarray(f"raises {type(exc).__name__}: {exc}")]
    return out


def same(a: Any, b: Any) -> bool:
    import numpy as np

    if a is None or b is None:
        return a is b
    return len(a) == len(b) and all(x.shape == y.shape and np.array_equal(x, y, equal_nan=True)
                                    for x, y in zip(a, b))


def model_check(cli: list[str], files: dict[str, Path], work: Path, limit: int | None,
                timeout_s: float, pool: ThreadPoolExecutor, max_rss_kib: int,
                passes: tuple[bool, ...] = (False, True)) -> tuple[dict[str, Any], list[Run]]:
    """Each single-field change of model.json, plain (``False`` in ``passes``) and re-sealed
    (``True``), through ``field probe``."""
    src = files["model"]
    doc = json.loads((src / "model.json").read_text())

    def probe(model: Path, cwd: Path, i: int) -> tuple[list[str] | None, Run]:
        outs: list[str] = []
        first = None
        for args in PROBES[:1]:
            argv = ["field", "probe", *args, "--samples", "2", "--model", model, "--json"]
            run = Run(-1, "model.json", [show(argv)])
            rc, run.hang, run.seconds, run.maxrss_kib, so, se, run.cpu_s = spawn(
                cli, argv, cwd, timeout_s)
            run.rc = rc
            judge(run, argv, so, se, max_rss_kib)
            first = first or run
            if rc != 0:
                return None, run
            outs.append(so.decode("utf-8", "replace"))
        return outs, first  # type: ignore[return-value]

    base_dir = work / "model_check"
    base_dir.mkdir(parents=True, exist_ok=True)
    (base_dir / "ref").mkdir(exist_ok=True)
    ref_out, ref_run = probe(src, base_dir / "ref", -1)
    ref_pred = predictions(src)
    changes = model_changes(doc)[:limit]
    # Re-sealed: every change but the training record's (metadata no prediction reads; the
    # plain pass tries those too).
    jobs = [(desc, new, sealed) for desc, new in changes for sealed in passes
            if not (sealed and desc.startswith("training."))]

    def one(i: int, desc: str, new: dict[str, Any], sealed: bool) -> dict[str, Any]:
        d = base_dir / f"m{i}" / "model"  # each run in a folder of its own
        shutil.copytree(src, d)
        (d / "model.json").write_text(json.dumps(reseal(new) if sealed else new, indent=2))
        outs, run = probe(d, d.parent, i)
        verdict = {"change": desc, "resealed": sealed, "rc": run.rc,
                   "problems": run.problems, "error": run.stderr_tail.splitlines()[-1:]}
        if outs is None:
            verdict["result"] = "refused" if run.rc == 2 and not run.problems else "broken"
        else:
            altered_cli = _numbers(outs) != _numbers(ref_out)
            altered_py = not same(predictions(d), ref_pred)
            verdict["result"] = ("accepted-altering" if altered_cli or altered_py
                                 else "accepted-same")
            verdict["altered_by"] = [w for w, x in (("cli probe", altered_cli),
                                                    ("2,000 states", altered_py)) if x]
        shutil.rmtree(d.parent, ignore_errors=True)
        print(f"[model.json {i + 1}/{len(jobs)}] {verdict['result']}: {desc}"
              f"{' (re-sealed)' if sealed else ''}", file=sys.stderr, flush=True)
        return verdict, run

    results = list(pool.map(lambda a: one(*a), [(i, *j) for i, j in enumerate(jobs)]))
    verdicts = [v for v, _ in results]
    runs = [r for _, r in results] + [ref_run]
    summary: dict[str, Any] = {"reference_probe_ok": ref_out is not None, "changes": len(changes)}
    for sealed, key in ((False, "plain"), (True, "resealed")):
        if sealed not in passes:
            continue
        vs = [v for v in verdicts if v["resealed"] == sealed]
        summary[key] = {
            "tried": len(vs),
            "results": dict(Counter(v["result"] for v in vs)),
            "accepted_same": [v["change"] for v in vs if v["result"] == "accepted-same"],
            "accepted_altering": [{"change": v["change"], "by": v["altered_by"]}
                                  for v in vs if v["result"] == "accepted-altering"],
            "broken": [{"change": v["change"], "rc": v["rc"], "problems": v["problems"],
                        "error": v["error"]} for v in vs if v["result"] == "broken"],
        }
    return summary, runs


# --------------------------------------------------------------------------------------------

def summarise(runs: list[Run], model: dict[str, Any] | None, args: argparse.Namespace,
              wall_s: float) -> dict[str, Any]:
    bad = [r for r in runs if r.problems]
    top = max(runs, key=lambda r: r.maxrss_kib) if runs else None
    per: dict[str, dict[str, int]] = {}
    for r in runs:
        c = per.setdefault(r.command, {"runs": 0, "exit_0": 0, "exit_2": 0, "other": 0})
        c["runs"] += 1
        key = {0: "exit_0", 2: "exit_2"}.get(r.rc, "other")  # type: ignore[arg-type]
        c[key] += 1
    lite = lambda r: {"command": r.argv[0], "rc": r.rc, "seconds": round(r.seconds, 1),  # noqa
                      "maxrss_mb": round(r.maxrss_kib / 1024, 1), "problems": r.problems,
                      "cpu_s": round(r.cpu_s, 1),
                      "stderr_tail": r.stderr_tail}
    return {
        "tool": "tools/audit.py", "seed": args.seed, "runs": len(runs), "jobs": args.jobs,
        "timeout_s": args.timeout, "max_rss_limit_mb": args.max_rss_mb,
        "wall_s": round(wall_s, 1),
        "exit_codes": dict(sorted(Counter("hang" if r.hang else str(r.rc)
                                          for r in runs).items())),
        "per_command": dict(sorted(per.items())),
        "hangs": [lite(r) for r in runs if r.hang],
        # A hang that used little CPU was waiting (a FIFO, a lock): blocked for ever. One that
        # computed was a valid long run the CLI's size limits let through.
        "hangs_blocked": sum(r.hang and r.cpu_s < BLOCKED_CPU_FRACTION * r.seconds
                             for r in runs),
        "max_rss_mb": round(top.maxrss_kib / 1024, 1) if top else 0.0,
        "max_rss_command": top.argv[0] if top else "",
        "over_rss_limit": [lite(r) for r in runs if r.maxrss_kib > args.max_rss_mb * 1024],
        "tracebacks": [lite(r) for r in runs if r.traceback],
        "other_exit_codes": [lite(r) for r in runs if not r.hang and r.rc not in (0, 2)],
        "multi_line_errors": [lite(r) for r in runs
                              if r.rc not in (0, None) and r.error_lines != 1],
        "json_checked": sum(r.json_checked for r in runs),
        "invalid_json": [lite(r) | {"json": r.json_problem} for r in runs if not r.json_ok],
        "slowest": [lite(r) for r in sorted(runs, key=lambda r: -r.seconds)[:5]],
        "failures": len(bad),
        "model_json": model,
    }


def text_summary(s: dict[str, Any]) -> str:
    lines = [f"audit: {s['runs']} runs (seed {s['seed']}, {s['jobs']} at a time, "
             f"{s['timeout_s']:g} s timeout), {s['wall_s'] / 60:.1f} min",
             "exit codes: " + ", ".join(f"{k}: {v}" for k, v in s["exit_codes"].items()),
             "per command: " + ", ".join(f"{k} {v['runs']}" for k, v in s["per_command"].items()),
             f"hangs: {len(s['hangs'])} ({s['hangs_blocked']} blocked, the rest computing); "
             f"max RSS {s['max_rss_mb']:.0f} MB "
             f"({s['max_rss_command'][:120]}); over {s['max_rss_limit_mb']} MB: "
             f"{len(s['over_rss_limit'])}",
             f"tracebacks: {len(s['tracebacks'])}; exits other than 0/2: "
             f"{len(s['other_exit_codes'])}; not one 'error:' line: "
             f"{len(s['multi_line_errors'])}; invalid JSON: {len(s['invalid_json'])} of "
             f"{s['json_checked']} checked"]
    m = s.get("model_json")
    if m:
        for key in [k for k in ("plain", "resealed") if k in m]:
            k = m[key]
            lines.append(f"model.json {key}: {k['tried']} single-field changes: {k['results']}; "
                         f"accepted and altering: {len(k['accepted_altering'])}")
    lines.append(f"runs breaking an invariant: {s['failures']}")
    bad = (s["hangs"] + s["other_exit_codes"] + s["tracebacks"] + s["multi_line_errors"]
           + s["invalid_json"] + s["over_rss_limit"])
    for r in bad[:8]:
        lines.append(f"  {r['problems']}: aerodock {r['command'][:160]}")
        if r["stderr_tail"]:
            lines.append(f"      {r['stderr_tail'].splitlines()[-1][:160]}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, required=True, help="JSON summary to write")
    ap.add_argument("--jobs", type=int, default=2, help="processes at a time (at most 2)")
    ap.add_argument("--timeout", type=float, default=60.0, help="seconds before a run is a hang")
    ap.add_argument("--max-rss-mb", type=int, default=2048)
    ap.add_argument("--work", type=Path, help="scratch folder (default: a new temporary one; "
                    "its setup files are reused when present)")
    ap.add_argument("--cli", help="the command audited (default: this Python with "
                    "aerodock.cli.main); shell words")
    ap.add_argument("--model-changes", type=int, default=None,
                    help="at most this many model.json changes (default: all; 0: none)")
    ap.add_argument("--keep", action="store_true", help="keep every run's folder")
    args = ap.parse_args(argv)
    args.jobs = max(1, min(args.jobs, 2))
    real = [sys.executable, "-c", ENTRY]
    cli = shlex.split(args.cli) if args.cli else real
    work = args.work or Path(tempfile.mkdtemp(prefix="aerodock-audit-"))
    work = work.resolve()
    if REPO in (work, *work.parents):
        raise SystemExit("the scratch folder must be outside the repository")
    t0 = time.monotonic()
    files = setup(work / "base", real, args.timeout)
    rng = random.Random(args.seed)
    order = COMMANDS[:]
    rng.shuffle(order)
    plans = []
    for i in range(args.runs):
        run_dir = work / "runs" / f"{i:05d}"
        if run_dir.exists():
            shutil.rmtree(run_dir)
        run_dir.mkdir(parents=True)
        d = Draw(random.Random(f"{args.seed}:{i}"), files, run_dir)
        command = order[i % len(order)]
        plans.append((i, command, gen(command, d), run_dir))
    max_rss_kib = args.max_rss_mb * 1024
    lock = threading.Lock()
    done = [0]

    def execute(plan: tuple[int, str, list[Any], Path]) -> Run:
        i, command, a, run_dir = plan
        run = Run(i, command, [show(a)])
        run.rc, run.hang, run.seconds, run.maxrss_kib, so, se, run.cpu_s = spawn(
            cli, a, run_dir, args.timeout)
        judge(run, a, so, se, max_rss_kib)
        if not run.problems and not args.keep:
            shutil.rmtree(run_dir, ignore_errors=True)
        with lock:
            done[0] += 1
            if run.problems or done[0] % 50 == 0:
                print(f"[{done[0]}/{args.runs}] {time.monotonic() - t0:.0f}s "
                      f"{run.problems or ''} {run.argv[0][:150]}", file=sys.stderr, flush=True)
        return run

    def write(runs: list[Run], model: dict[str, Any] | None, partial: bool) -> dict[str, Any]:
        summary = summarise(runs, model, args, time.monotonic() - t0)
        summary["partial"] = partial
        args.out.parent.mkdir(parents=True, exist_ok=True)
        tmp = args.out.with_name(args.out.name + ".tmp")
        tmp.write_text(json.dumps(summary, indent=1, allow_nan=False) + "\n")
        os.replace(tmp, args.out)
        return summary

    with ThreadPoolExecutor(args.jobs) as pool:
        model = None
        if args.model_changes != 0:  # the plain changes first: the target's own check
            model, _ = model_check(cli, files, work, args.model_changes, args.timeout,
                                   pool, max_rss_kib, passes=(False,))
        runs = []
        for start in range(0, len(plans), 100):  # a partial summary every 100 runs
            runs += list(pool.map(execute, plans[start:start + 100]))
            write(runs, model, partial=True)
        if model is not None:  # then re-sealed (informational)
            sealed, _ = model_check(cli, files, work, args.model_changes, args.timeout,
                                    pool, max_rss_kib, passes=(True,))
            model["resealed"] = sealed["resealed"]
    summary = write(runs, model, partial=False)
    print(text_summary(summary))
    if not args.work and not args.keep and summary["failures"] == 0:
        shutil.rmtree(work, ignore_errors=True)
    ok = summary["failures"] == 0 and not (model and (model["plain"]["accepted_altering"]
                                                      or model["plain"]["broken"]))
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
