"""What ``results.json`` records of its run (the resolved config, the version, the commit), and
that ``tools/same_numbers.py`` compares the numbers only, not that record (issue 41)."""

from __future__ import annotations

import importlib.util
import json
import shutil
import subprocess
from pathlib import Path

import pytest

from aerodock.config import load_config
from aerodock.experiments.provenance import KEYS, code_version, git_state, provenance

REPO = Path(__file__).resolve().parents[2]


def _same_numbers():
    path = REPO / "tools" / "same_numbers.py"
    spec = importlib.util.spec_from_file_location("same_numbers", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_provenance_holds_the_resolved_config(tmp_path):
    path = tmp_path / "my.toml"
    path.write_text("[platform]\ncable_length_m = 0.5\n")
    cfg = load_config(path, sets=["vehicle.mass_kg=0.8"])
    record = provenance(cfg)
    assert set(record) == set(KEYS)
    assert record["config"]["platform"]["cable_length_m"] == 0.5
    assert record["config"]["vehicle"]["mass_kg"] == 0.8
    assert record["config_source"] == f"{path} + --set"
    assert record["version"] == code_version() != ""
    json.dumps(record)  # JSON as it is: results.json holds it


def test_the_recorded_config_runs_again(tmp_path):
    """The record is every key's value: written as TOML, it loads into the same config."""
    cfg = load_config(sets=["platform.cable_length_m=0.5", "control.q_diag=[1, 1, 9, 0.01, "
                            "0.01, 0.1, 1]"])
    path = tmp_path / "again.toml"
    path.write_text(cfg.to_toml())
    assert load_config(path).data == provenance(cfg)["config"] == cfg.data


def test_no_commit_outside_a_checkout(tmp_path):
    assert git_state(tmp_path) == (None, None)


@pytest.mark.skipif(shutil.which("git") is None, reason="no git")
def test_commit_and_dirty_in_a_checkout(tmp_path):
    def git(*args):
        subprocess.run(["git", "-C", str(tmp_path), *args], check=True, capture_output=True)

    git("init", "-q")
    (tmp_path / "a.txt").write_text("1")
    git("add", "a.txt")
    git("-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qm", "one")
    commit, dirty = git_state(tmp_path)
    assert commit is not None and len(commit) == 40 and dirty is False
    (tmp_path / "a.txt").write_text("2")
    assert git_state(tmp_path) == (commit, True)


def _results(tmp_path, name, meta_extra, number):
    folder = tmp_path / name / "reproduce"
    folder.mkdir(parents=True)
    doc = {"aerodock_reproduce": {"quick": True, "seed": 0, **meta_extra},
           "learning": {"rmse": number}, "timings_s": {"total_s": 3.0}}
    (folder / "results.json").write_text(json.dumps(doc))
    return tmp_path / name


def test_same_numbers_ignores_the_provenance_not_the_numbers(tmp_path, capsys):
    tool = _same_numbers()
    old = _results(tmp_path, "old", {"config": "defaults"}, 0.25)
    new = _results(tmp_path, "new", {**provenance(load_config()), "git_commit": "abc"}, 0.25)
    changed = _results(tmp_path, "changed", {"config": "defaults"}, 0.26)
    assert tool.compare(old, new)
    assert not tool.compare(old, changed)
    assert "DIFFERS  reproduce/results.json" in capsys.readouterr().out
