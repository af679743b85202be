"""``--set`` and ``--trust-plugin`` on the command line (issue 41): on every command that reads a
config, and passed on to the child processes of ``bench``."""

from __future__ import annotations

import os

import typer
from typer.testing import CliRunner

from aerodock.cli.app import app
from aerodock.config import load_config
from aerodock.config.plugins import TRUST_ENV


def _commands() -> dict[str, object]:
    group = typer.main.get_command(app)
    out = {}
    for name, command in group.commands.items():
        for sub_name, sub in getattr(command, "commands", {name: command}).items():
            out[name if sub is command else f"{name} {sub_name}"] = sub
    return out


def test_every_command_that_reads_a_config_takes_set_and_trust():
    with_config = 0
    for name, command in _commands().items():
        opts = {o for p in command.params for o in getattr(p, "opts", [])}
        if "--config" in opts:
            with_config += 1
            assert {"--set", "--trust-plugin"} <= opts, name
            flags = {p.name: p for p in command.params}
            assert flags["sets"].multiple and flags["trust"].multiple, name
    assert with_config >= 12
    assert "--trust-plugin" in {o for p in _commands()["sweep"].params for o in p.opts}


def test_bench_children_read_the_resolved_config_and_the_trust(monkeypatch):
    """bench measures some parts in child processes: they get the config as --set made it (a
    file) and the trusted modules (the environment), restored when the command ends."""
    import aerodock.bench as bench  # (the command reads run_all from it when it runs)

    seen = {}

    def fake_run_all(cfg, quick, progress, config_path, only):
        seen["cfg"] = cfg
        seen["file"] = load_config(config_path).data
        seen["trust"] = os.environ.get(TRUST_ENV)
        return {"machine": {}, "figures": {}, "targets": []}

    monkeypatch.setattr(bench, "run_all", fake_run_all)
    monkeypatch.setenv(TRUST_ENV, "theirs")
    result = CliRunner().invoke(app, ["bench", "--quick", "--json", "--set",
                                      "platform.cable_length_m=0.5", "--trust-plugin", "mine"])
    assert result.exit_code == 0, result.output
    assert seen["cfg"].platform.cable_length_m == 0.5
    assert seen["file"] == seen["cfg"].data
    assert seen["trust"] == "mine,theirs"
    assert os.environ[TRUST_ENV] == "theirs"


def test_set_error_is_one_line_through_the_app(capsys):
    from aerodock.cli import run

    rc = run(["field", "probe", "--separation", "0.5", "--radial", "0", "--set",
              "platform.cable_length=0.5"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and err == ["error: --set platform.cable_length: unknown key "
                               "'platform.cable_length'"]
