"""Fixtures of the fuzz suite: files written by aerodock itself, and a tiny trained model."""

from __future__ import annotations

from pathlib import Path

import pytest


@pytest.fixture(autouse=True)
def _isolated(monkeypatch, tmp_path):
    """No traceback mode, and a scratch working folder: a fuzzed ``--out -inf`` writes there."""
    monkeypatch.delenv("AERODOCK_DEBUG", raising=False)
    monkeypatch.chdir(tmp_path)


@pytest.fixture(scope="session")
def fuzz_dir(tmp_path_factory) -> Path:
    """A scratch folder for the whole fuzz session."""
    return tmp_path_factory.mktemp("fuzz")


@pytest.fixture(scope="session")
def flightlog_file(fuzz_dir, short_cfg) -> Path:
    """A FlightLog file written by aerodock: two simulated docking trials (3 s of each, so that
    a thousand damaged copies stay quick to write and read), flown on the short mission (the
    file is what is damaged, not what it flew)."""
    from aerodock.flightlog import save_flightlogs
    from aerodock.mission import MissionSpec, run_campaign

    result = run_campaign(short_cfg, MissionSpec(trials=2, seed=3), record="full")
    return save_flightlogs(fuzz_dir / "base.npz", [log.slice(0, 300) for log in result.logs])


@pytest.fixture(scope="session")
def model_dir(fuzz_dir, flightlog_file) -> Path:
    """A small so2 model trained by ``aerodock train`` on that file."""
    from fuzz_helpers import run_cli

    out = fuzz_dir / "model"
    res = run_cli(["train", "--data", flightlog_file, "--out", out, "--max-epochs", "3",
                   "--json"], family="setup")
    assert res.rc == 0, res.err
    return out
