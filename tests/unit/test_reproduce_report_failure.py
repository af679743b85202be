"""A reproduction whose report fails after the experiments ran keeps what it computed: the
folder is swapped in with its ``results.json``, and the failure is one line (exit 1)."""

from __future__ import annotations

import json

import pytest

from aerodock.config import load_config
from aerodock.experiments import reproduce


def _fake_run(cfg, work, named, quick, seed, say, shared_data, bar, smoke):
    """The experiments' part done (a results.json written), the report failed."""
    (work / "figures").mkdir()
    (work / "results.json").write_text(json.dumps({"flown": True}))
    return {"flown": True}, "ValueError: 'yerr' must not contain negative values"


def test_the_numbers_are_kept_when_the_report_fails(tmp_path, monkeypatch):
    monkeypatch.setattr(reproduce, "_reproduce_into", _fake_run)
    out = tmp_path / "run"
    with pytest.raises(reproduce.ReportError, match="results.json holds their numbers.*yerr"):
        reproduce.run_reproduce(load_config(), out, smoke=True, say=lambda _: None)
    assert json.loads((out / "results.json").read_text()) == {"flown": True}
    assert not [p for p in tmp_path.iterdir() if p.name != "run"]  # no building folder left


def test_the_command_says_it_in_one_line(tmp_path, monkeypatch):
    from click.testing import CliRunner

    from aerodock.cli.app import command

    monkeypatch.setattr(reproduce, "_reproduce_into", _fake_run)
    out = tmp_path / "run"
    result = CliRunner().invoke(command(), ["reproduce", "--smoke", "--no-real-data", "--out",
                                      str(out)])
    assert result.exit_code == 1
    errors = [line for line in result.output.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and "yerr" in errors[0]
    assert "Traceback" not in result.output
    assert (out / "results.json").exists()
