"""The command line as a user runs it: numbers, JSON, and one-line errors."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

CALIBRATION = {0.36: (4.5, 1.0), 0.64: (3.0, 0.8), 1.35: (1.5, 0.5)}


def aerodock(*args, check=True):
    proc = subprocess.run([sys.executable, "-c", "from aerodock.cli import main; main()", *args],
                          capture_output=True, text=True, timeout=300)
    if check and proc.returncode != 0:
        raise AssertionError(proc.stderr)
    return proc


@pytest.mark.parametrize("sep", sorted(CALIBRATION))
def test_field_probe_json_matches_design_table(sep):
    out = json.loads(aerodock("field", "probe", "--separation", str(sep), "--radial", "0",
                              "--json").stdout)
    target, tol = CALIBRATION[sep]
    assert abs(out["mean_mps2"][2] - target) <= tol
    assert out["frame"] == "NED"
    assert 0.15 * out["mean_mps2"][2] < out["sd_mps2"][2] < 0.3 * out["mean_mps2"][2]


def test_field_plot_writes_png(tmp_path):
    path = tmp_path / "f.png"
    aerodock("field", "plot", "--out", str(path))
    assert path.read_bytes()[:4] == b"\x89PNG"


def test_bad_config_is_one_line_error(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[vehicle]\nmass_kg = -1\n")
    proc = aerodock("field", "probe", "--separation", "0.36", "--radial", "0", "--config",
                    str(bad), check=False)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error:")
    assert "vehicle.mass_kg" in lines[0] and str(bad) in lines[0]
    assert "Traceback" not in proc.stderr


def test_dock_json_and_bad_trials():
    out = json.loads(aerodock("dock", "--trials", "4", "--compensation", "oracle", "--json")
                     .stdout)
    assert out["trials"] == 4 and 0 <= out["success_rate"] <= 1
    assert len(out["success_wilson95"]) == 2
    proc = aerodock("dock", "--trials", "0", check=False)
    assert proc.returncode == 2 and "trials" in proc.stderr
    proc = aerodock("dock", "--trials", "2", "--compensation", "model", check=False)
    assert proc.returncode == 2 and "--model" in proc.stderr


def test_dock_saves_flightlogs(tmp_path):
    from aerodock.flightlog import load_flightlogs

    out = json.loads(aerodock("dock", "--trials", "2", "--compensation", "oracle", "--save-logs",
                              str(tmp_path), "--json").stdout)
    logs = load_flightlogs(out["logs"])
    assert len(logs) == 2
    assert "true_field_mean_mps2" in logs[0].extra
