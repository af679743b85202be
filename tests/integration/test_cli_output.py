"""What a person reads: every --help as written (no markup eaten, choices listed), --version,
the dock table without raw dicts, and JSON keys whose unit suffix is the unit."""

from __future__ import annotations

import io
import json
import re
import tomllib
from contextlib import redirect_stderr, redirect_stdout
from enum import Enum
from pathlib import Path

import pytest
import typer
from short_mission import short_mission_toml

import aerodock
from aerodock.cli import run
from aerodock.cli.app import app
from aerodock.cli.dock import Controller, aborts_text
from aerodock.control.profiles import PROFILES
from aerodock.mission.outcome import DEPRECATED_KEYS


def _run(*args: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        rc = run([str(a) for a in args])
    return rc, out.getvalue(), err.getvalue()


def _commands(cmd, path=()):
    """(path, click command) of every command and group, the raw help texts as written."""
    yield path, cmd
    for name, sub in getattr(cmd, "commands", {}).items():
        yield from _commands(sub, (*path, name))


def _flat(text: str) -> str:
    """The text without colours, the help's frame and line breaks: one space between words."""
    text = re.sub(r"\x1b\[[0-9;]*m", "", text)
    return " ".join(re.sub(r"[│╭╮╰╯─]", " ", text).split())


@pytest.fixture
def wide(monkeypatch):
    """Help drawn 4000 columns wide: one line per option, nothing wraps."""
    import typer.rich_utils

    monkeypatch.setenv("COLUMNS", "4000")
    monkeypatch.setattr(typer.rich_utils, "MAX_WIDTH", 4000)


def _as_read(text: str) -> str:
    """A help text as the reader should see it: code quotes as '...', spaces collapsed."""
    text = re.sub(r"``([^`]+)``", r"'\1'", text)
    return " ".join(re.sub(r"`([^`]+)`", r"'\1'", text).split())


RAW = list(_commands(typer.main.get_command(app)))


@pytest.mark.parametrize("path, cmd", RAW, ids=[" ".join(p) or "aerodock" for p, _ in RAW])
def test_every_help_renders_as_written(path, cmd, wide):
    rc, out, err = _run(*path, "--help")
    assert rc == 0, err
    seen = _flat(out)
    texts = [cmd.help or ""] + [getattr(p, "help", None) or "" for p in cmd.params]
    for text in texts:
        for bracket in re.findall(r"\[[^\]]*\]+", text):  # [[fault]], aerodock[viz], [default]
            assert bracket in seen, (bracket, text)
        paragraphs = text.split("\f")[0].split("\n\n")
        for para in paragraphs:
            assert _as_read(para) in seen, para
    assert "`" not in seen and "[]" not in seen
    for p in cmd.params:  # a fixed set of values (an Enum) is listed, not <str>
        kind = getattr(getattr(p, "type_descriptor", None), "annotation", None)
        if isinstance(kind, type) and issubclass(kind, Enum):
            assert "<" + "|".join(str(c.value) for c in kind) + ">" in seen, p.name


def test_the_dock_controller_lists_its_choices(wide):
    assert {c.value for c in Controller} == set(PROFILES)
    seen = _flat(_run("dock", "--help")[1])
    assert "<paper|tuned|ours>" in seen and "[[fault]]" in seen and "<str>" not in seen
    assert "not 'ours without model'" in seen  # --compensation none with ours, explained


def test_version_is_the_packages():
    rc, out, err = _run("--version")
    assert rc == 0 and out.strip() == f"aerodock {aerodock.__version__}"
    pyproject = Path(aerodock.__file__).resolve().parents[1] / "pyproject.toml"
    version = tomllib.loads(pyproject.read_text())["project"]["version"]
    assert aerodock.__version__ == version


def test_version_falls_back_to_pyproject(monkeypatch):
    import importlib.metadata as md

    def missing(name):
        raise md.PackageNotFoundError(name)

    monkeypatch.setattr(md, "version", missing)
    pyproject = Path(aerodock.__file__).resolve().parents[1] / "pyproject.toml"
    assert aerodock._version() == tomllib.loads(pyproject.read_text())["project"]["version"]


def test_aborts_read_as_words():
    summary = {"aborts": 3, "abort_reasons": {"timeout": 2, "leader_lost": 0,
                                              "unsafe_tracking": 1, "gate_fault": 0}}
    assert aborts_text(summary) == "3 (timeout 2, unsafe tracking 1)"
    assert aborts_text({"aborts": 0, "abort_reasons": {"timeout": 0}}) == "0"


@pytest.fixture(scope="module")
def short_toml(tmp_path_factory):
    path = tmp_path_factory.mktemp("short") / "short.toml"
    path.write_text(short_mission_toml())
    return str(path)


def test_dock_json_keys_carry_their_units_and_name_the_old_ones(short_toml):
    rc, out, err = _run("dock", "--trials", "2", "--controller", "ours", "--compensation",
                        "none", "--json", "--config", short_toml)
    assert rc == 0, err
    doc = json.loads(out)
    assert doc["controller"] == "ours"
    assert doc["deprecated_keys"] == DEPRECATED_KEYS
    for old, new in DEPRECATED_KEYS.items():
        assert new.endswith("_m_s") and doc[old] == doc[new]
    assert "warning: --compensation none turns off every observer" in err


def test_dock_table_has_no_raw_dicts(short_toml, monkeypatch):
    monkeypatch.setenv("COLUMNS", "200")
    rc, out, err = _run("dock", "--trials", "2", "--config", short_toml)
    assert rc == 0, err
    assert "docked" in out and "aborts" in out
    assert not re.search(r"[{}]|'\w+':", out), out
