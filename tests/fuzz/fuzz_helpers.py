"""Fuzzing helpers: the CLI in-process, the invariants every run must keep, nasty values.

Invariants (issue 12): exit code 0 or 2, no traceback, exactly one ``error:`` line on a refusal,
strict JSON (no NaN/Infinity) on ``--json`` success, and no NaN anywhere in that JSON.
"""

from __future__ import annotations

import io
import json
import math
import os
import random
import zipfile
from contextlib import redirect_stderr, redirect_stdout
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

# Quick mode by default; AERODOCK_FUZZ_SCALE=10 runs ten times as many cases.
SCALE = float(os.environ.get("AERODOCK_FUZZ_SCALE", "1"))
TALLY: dict[str, int] = {}


def n_cases(quick: int) -> int:
    """Number of cases for a family: ``quick`` in quick mode, scaled otherwise."""
    return max(1, int(quick * SCALE))


def count(family: str, n: int = 1) -> None:
    """Record ``n`` cases of a family (printed in the terminal summary)."""
    TALLY[family] = TALLY.get(family, 0) + n


@dataclass
class Result:
    """One CLI run."""

    args: list[str]
    rc: int
    out: str
    err: str
    problems: list[str] = field(default_factory=list)


def _reject_constant(name: str) -> Any:
    raise ValueError(f"invalid JSON constant {name}")


def has_nan(obj: Any) -> bool:
    """True if a parsed JSON value holds a non-finite number anywhere."""
    if isinstance(obj, float):
        return not math.isfinite(obj)
    if isinstance(obj, dict):
        return any(has_nan(v) for v in obj.values())
    if isinstance(obj, list):
        return any(has_nan(v) for v in obj)
    return False


def run_cli(args: list[Any], family: str = "cli") -> Result:
    """Run ``aerodock ARGS`` in-process (``aerodock.cli.run``) and check the invariants."""
    from aerodock.cli import run

    args = [str(a) for a in args]
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        try:
            rc = run(args)
        except SystemExit as exc:  # nothing may escape run(); record it as a problem
            rc = exc.code if isinstance(exc.code, int) else 1
            err.write(f"\nSystemExit escaped run(): {exc.code!r}")
    res = Result(args, rc, out.getvalue(), err.getvalue())
    count(family)
    if rc not in (0, 2):
        res.problems.append(f"exit code {rc}")
    if "Traceback" in res.out + res.err or "escaped" in res.err:
        res.problems.append("traceback")
    if "AERODOCK_DEBUG" in res.err:
        res.problems.append("unexpected error (asks for AERODOCK_DEBUG)")
    if rc == 2:
        errors = [line for line in res.err.splitlines() if line.startswith("error:")]
        if len(errors) != 1:
            res.problems.append(f"{len(errors)} 'error:' lines")
    if rc == 0 and "--json" in args and "--help" not in args:
        try:
            doc = json.loads(res.out, parse_constant=_reject_constant)
        except ValueError as exc:
            res.problems.append(f"invalid JSON ({exc})")
        else:
            if has_nan(doc):
                res.problems.append("NaN in JSON")
    return res


def assert_clean(results: list[Result]) -> None:
    """Fail with the first few offending runs (command line, exit code, stderr)."""
    bad = [r for r in results if r.problems]
    if bad:
        lines = [f"{len(bad)} of {len(results)} runs broke the invariants:"]
        for r in bad[:8]:
            lines.append(f"  aerodock {' '.join(r.args)} -> {r.rc} {r.problems}: "
                         f"{(r.err.strip().splitlines() or [''])[-1][:300]}")
        raise AssertionError("\n".join(lines))


NASTY_NUMBERS: list[Any] = [
    float("nan"), float("inf"), -float("inf"), 1e308, -1e308, 1e-300, -1.0, 0.0, 0, -0.0, 4.5,
    10**30, -(10**30), 2**63, 1e6, 0.5, 3,
]
NASTY_VALUES: list[Any] = [
    *NASTY_NUMBERS, True, False, "", "0.2", "nan", "x" * 300, [], [1, 2], [float("nan")],
    [True] * 7, {}, {"a": 1}, None,
]
NASTY_CLI: list[str] = [
    "nan", "inf", "-inf", "1e308", "-1e308", "1e-300", "-1", "0", "4.5", "1e8", "100000000",
    "99999999999999999999", "abc", "", "--json", "-", "0x10", "1_000",
]


def mutate_bytes(blob: bytes, rng: random.Random) -> bytes:
    """One random byte-level damage: flips, truncation, a zeroed or duplicated range, garbage."""
    data = bytearray(blob)
    kind = rng.randrange(5)
    if kind == 0 and data:
        for _ in range(rng.randint(1, 8)):
            i = rng.randrange(len(data))
            data[i] ^= 1 << rng.randrange(8)
    elif kind == 1:
        data = data[: rng.randrange(len(data) + 1)]
    elif kind == 2 and data:
        i = rng.randrange(len(data))
        j = min(len(data), i + rng.randint(1, 64))
        data[i:j] = bytes(j - i)
    elif kind == 3 and data:
        i = rng.randrange(len(data))
        data[i:i] = data[i:i + rng.randint(1, 200)]
    else:
        i = rng.randrange(len(data) + 1)
        data[i:i] = bytes(rng.randrange(256) for _ in range(rng.randint(1, 32)))
    return bytes(data)


def npy_bytes(arr: np.ndarray) -> bytes:
    """An array as ``.npy`` bytes."""
    buf = io.BytesIO()
    np.save(buf, arr, allow_pickle=False)
    return buf.getvalue()


def npy_header_only(shape: tuple[int, ...], descr: str = "<f8") -> bytes:
    """An ``.npy`` member that declares ``shape`` but holds almost no data."""
    header = repr({"descr": descr, "fortran_order": False, "shape": shape}).encode()
    header += b" " * (63 - (len(header) + 10) % 64) + b"\n"
    return b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little") + header + b"\0" * 16


def rewrite_npz(src: Path, dst: Path, replace: dict[str, bytes],
                drop: tuple[str, ...] = ()) -> None:
    """Copy an ``.npz``, replacing members (``name.npy`` -> bytes) and dropping others."""
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w", zipfile.ZIP_STORED) as zout:
        for info in zin.infolist():
            if info.filename in drop:
                continue
            blob = replace.pop(info.filename, None)
            zout.writestr(info.filename, blob if blob is not None else zin.read(info))
        for name, blob in replace.items():
            zout.writestr(name, blob)


def toml_value(value: Any) -> str:
    """A Python value as TOML text (NaN and infinities in TOML's spelling)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, int):
        return str(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k} = {toml_value(v)}" for k, v in value.items()) + "}"
    return '"None"'
