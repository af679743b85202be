"""``aerodock ingest`` command: summaries, JSON, progress, and one-line errors (exit 2)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import typer
from ingest_helpers import NS_HEADER, write_ns_file
from typer.testing import CliRunner

from aerodock.cli.ingest import ingest_command
from aerodock.flightlog import load_flightlogs
from aerodock.ingest import read_logs
from aerodock.ingest.errors import IngestError

app = typer.Typer()
app.command("ingest")(ingest_command)


@app.command("other")
def _other() -> None:  # a second command, so "ingest" is a sub-command as in aerodock's CLI
    """Placeholder."""


runner = CliRunner()


def _flights(folder: Path, n_flights: int = 2) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    t_us = 9842.0 + 9874.0 * np.arange(200)
    for k in range(n_flights):
        write_ns_file(folder / f"cf1_{k:02d}.csv", t_us=t_us)
        write_ns_file(folder / f"cf2_{k:02d}.csv", t_us=t_us,
                      pos_zup=np.tile([0.0, 0.2, 0.8], (200, 1)))
    return folder


def test_ingest_writes_flights_and_prints_a_line_each(tmp_path: Path) -> None:
    folder = _flights(tmp_path / "data")
    out = tmp_path / "flights.npz"
    result = runner.invoke(app, ["ingest", "--format", "neural-swarm", str(folder),
                                 "--out", str(out), "--vehicle", "large"])
    assert result.exit_code == 0, result.output
    lines = result.stdout.strip().splitlines()
    assert lines[0] == "data_00_cf1: 2.0 s, 200 samples (neural-swarm, label basis thrust)"
    assert len(lines) == 5 and lines[-1] == f"wrote 4 flights to {out}"
    logs = load_flightlogs(out)
    assert [log.name for log in logs] == ["data_00_cf1", "data_00_cf2", "data_01_cf1",
                                         "data_01_cf2"]
    assert logs[0].meta["follower_mass_kg"] == 0.067


def test_ingest_json(tmp_path: Path) -> None:
    folder = _flights(tmp_path / "data", 1)
    out = tmp_path / "flights.npz"
    result = runner.invoke(app, ["ingest", "-f", "neural-swarm", str(folder / "cf1_00.csv"),
                                 str(folder / "cf2_00.csv"), "-o", str(out), "--json"])
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout)
    assert summary["out"] == str(out)
    assert [f["n_samples"] for f in summary["flights"]] == [200, 200]


def test_progress_is_reported_per_file(tmp_path: Path) -> None:
    folder = _flights(tmp_path / "data", 3)
    calls: list[tuple[int, int]] = []
    read_logs("neural-swarm", [folder], progress=lambda d, n: calls.append((d, n)))
    assert calls[-1] == (6, 6)
    assert [d for d, _ in calls] == sorted(d for d, _ in calls)


def test_error_is_one_line_exit_2_and_keeps_old_output(tmp_path: Path) -> None:
    folder = _flights(tmp_path / "data", 1)
    write_ns_file(folder / "cf2_00.csv", t_us=9842.0 + 9874.0 * np.arange(200),
                  header=NS_HEADER.replace("vy[m/s]", "speed"))
    out = tmp_path / "flights.npz"
    out.write_bytes(b"previous results")
    result = runner.invoke(app, ["ingest", "--format", "neural-swarm", str(folder),
                                 "--out", str(out)])
    assert result.exit_code == 2
    assert result.stderr == f"error: {folder / 'cf2_00.csv'}: missing columns: vy\n"
    assert "Traceback" not in result.output
    assert out.read_bytes() == b"previous results"


@pytest.mark.parametrize("args, phrase", [
    (["--format", "csv", "--single"], "option --single does not apply to this format"),
    (["--format", "ulog"], "give pairs (LEADER.ulg FOLLOWER.ulg), or --single"),
])
def test_option_errors(tmp_path: Path, args: list[str], phrase: str) -> None:
    path = tmp_path / ("x.csv" if "csv" in args else "x.ulg")
    path.write_text("")
    result = runner.invoke(app, ["ingest", *args, str(path), "--out", str(tmp_path / "o.npz")])
    assert result.exit_code == 2
    assert phrase in result.stderr
    assert result.stderr.count("\n") == 1 and result.stderr.startswith("error: ")


def test_missing_path(tmp_path: Path) -> None:
    result = runner.invoke(app, ["ingest", "-f", "csv", str(tmp_path / "nope.csv"), "-o",
                                 str(tmp_path / "o.npz")])
    assert result.exit_code == 2
    assert result.stderr == f"error: {tmp_path / 'nope.csv'}: no such file or folder\n"


def test_real_ulog_sample_single(tmp_path: Path, ulog_sample: Path) -> None:
    pytest.importorskip("pyulog")
    out = tmp_path / "px4.npz"
    result = runner.invoke(app, ["ingest", "--format", "ulog", "--single", str(ulog_sample),
                                 "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert "warning: " in result.stderr and "assuming 1 kg" in result.stderr
    assert result.stdout.startswith("sample_log_small: 6.3 s, 634 samples (ulog")
    assert load_flightlogs(out)[0].meta["leader"] == "virtual"


def test_unknown_format_is_rejected_by_read_logs(tmp_path: Path) -> None:
    with pytest.raises(IngestError, match="unknown format"):
        read_logs("bag", [tmp_path])
