"""tools/audit.py, the outside audit (issue 25): it runs, its summary adds up, and it reports
what it exists to find (a fake CLI that exits 1, prints a traceback, hangs, grows, writes NaN
JSON, or accepts any model.json)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
TOOL = REPO / "tools" / "audit.py"

FAKE_CLI = '''
import sys, time
cmd = sys.argv[1] if len(sys.argv) > 1 else ""
if cmd == "dock":
    print("Traceback (most recent call last):\\nZeroDivisionError", file=sys.stderr)
    sys.exit(1)
if cmd == "train":
    time.sleep(60)
if cmd == "export":
    blob = bytearray(300 * 1024 * 1024)
    blob[::4096] = b"x" * len(blob[::4096])
    sys.exit(0)
if cmd == "field":  # accepts any model, prints NaN where JSON is asked for
    print('{"mean_mps2": NaN}' if sys.argv[2] != "probe" else '{"mean_mps2": [0, 0, 1]}')
    sys.exit(0)
if cmd == "view":
    print("error: one\\nerror: two", file=sys.stderr)
    sys.exit(2)
print("error: refused", file=sys.stderr)
sys.exit(2)
'''


@pytest.fixture(scope="module")
def work(tmp_path_factory) -> Path:
    """One scratch folder: the setup files (a config, a FlightLog, a model...) made once."""
    return tmp_path_factory.mktemp("audit")


def audit(out: Path, work: Path, *extra: str) -> tuple[subprocess.CompletedProcess, dict]:
    res = subprocess.run([sys.executable, str(TOOL), "--out", str(out), "--work", str(work),
                          *extra], capture_output=True, text=True, timeout=1200)
    assert out.exists(), res.stderr[-2000:]
    return res, json.loads(out.read_text())


def test_every_command_once_through_the_real_cli_adds_up(work, tmp_path):
    """17 runs, round-robin: every command and field's three once (each a real process)."""
    res, s = audit(tmp_path / "a.json", work, "--runs", "17", "--seed", "5",
                   "--model-changes", "2")
    assert s["runs"] == 17 and not s["partial"]
    assert sum(s["exit_codes"].values()) == 17
    assert sum(c["runs"] for c in s["per_command"].values()) == 17
    assert len(s["per_command"]) == 17  # round-robin: every command and field's three
    assert {c["runs"] for c in s["per_command"].values()} == {1}
    assert 0 < s["max_rss_mb"] < 2048 and s["max_rss_command"]
    m = s["model_json"]
    assert m["reference_probe_ok"] and m["plain"]["tried"] == 2
    assert sum(m["plain"]["results"].values()) == 2
    # the package keeps the invariants: exit status 0, and the text says the same
    assert s["failures"] == 0, json.dumps(s, indent=1)[:3000]
    assert m["plain"]["accepted_altering"] == []
    assert res.returncode == 0
    assert "audit: 17 runs" in res.stdout and "hangs: 0" in res.stdout


def test_a_broken_cli_is_reported(work, tmp_path):
    """Every command once (17 runs), through a fake CLI; setup used the real one."""
    fake = tmp_path / "fake_cli.py"
    fake.write_text(FAKE_CLI)
    res, s = audit(tmp_path / "b.json", work, "--runs", "17", "--seed", "1", "--timeout", "3",
                   "--max-rss-mb", "200", "--model-changes", "3",
                   "--cli", f"{sys.executable} {fake}")
    assert res.returncode == 1
    assert [h["command"].split()[0] for h in s["hangs"]] == ["train"]
    assert s["exit_codes"]["hang"] == 1
    assert s["hangs_blocked"] == 1  # it slept: waiting, not computing
    assert [r["command"].split()[0] for r in s["other_exit_codes"]] == ["dock"]
    assert [r["command"].split()[0] for r in s["tracebacks"]] == ["dock"]
    assert s["max_rss_command"].startswith("export") and s["max_rss_mb"] > 250
    assert [r["command"].split()[0] for r in s["over_rss_limit"]] == ["export"]
    # dock's exit 1 had no error: line either
    assert sorted(r["command"].split()[0] for r in s["multi_line_errors"]) == ["dock", "view"]
    bad_json = [r["command"] for r in s["invalid_json"]]
    assert {c.split()[0] for c in bad_json} <= {"export", "field"}  # empty or NaN output
    m = s["model_json"]["plain"]
    assert m["tried"] == 3 and len(m["accepted_altering"]) == 3  # anything loads: caught
    assert "hangs: 1" in res.stdout
