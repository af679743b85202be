"""Helpers of the plug-in protocol suite (issue 15): configs for three fields that look nothing
like the default jet, and the ``aerodock`` command line run in-process or as a subprocess."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

from short_mission import short_mission_toml

HERE = Path(__file__).resolve().parent
TRUST = {"AERODOCK_TRUST_PLUGINS": "protocol_fields"}
"""The user's word that the config's plug-in module may run (a config names code only so)."""
FIELDS = ("MinimalField", "OutwardThrustAxisField", "NoWakeField")
# Only these have no mean_acceleration(): their mean is estimated or reported unavailable.
WITHOUT_MEAN = ("MinimalField", "NoWakeField")

# The smallest honest curriculum: one stage (0.5-0.8 m below the leader) of three flights
# (0.6 min, so the sample-efficiency study still trains at 0.5 min) and one deep stage (0.3-0.5 m)
# of three; the mission's waiting times cut (tests/short_mission.py: what is checked here is that
# the field goes through, not what the mission achieves). Everything else is what
# `reproduce --smoke` and the other commands do by default.
_CONFIG = """[downwash]
field = "protocol_fields:{name}"
[downwash.params]
[curriculum]
stage0_depth_m = [0.5, 0.8]
flights_per_stage = 3
deep_depths_m = [0.3]
deep_flights_per_stage = 3
""" + short_mission_toml()


def write_config(folder: Path, name: str, deep: bool = True) -> Path:
    """A user config that plugs in ``protocol_fields:NAME``; without ``deep``, its curriculum
    is the one paper stage alone (``collect``'s test: the deep stage flies the same world with
    the stage model fed forward, which ``reproduce --smoke`` covers with a plug-in field)."""
    path = folder / f"{name}{'' if deep else '-paper-stage'}.toml"
    text = _CONFIG.format(name=name)
    if not deep:
        text = text.replace("deep_depths_m = [0.3]", "deep_depths_m = []")
    path.write_text(text)
    return path


def subprocess_env() -> dict[str, str]:
    """The environment of a user whose plug-in module is on PYTHONPATH and trusted."""
    env = {**os.environ, **TRUST}
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(HERE), env.get("PYTHONPATH")) if p)
    return env


def aerodock_process(args: list[str], cwd: Path) -> subprocess.Popen:
    """Start ``aerodock ARGS`` as a user would (its exit code and stderr as they would see)."""
    return subprocess.Popen([sys.executable, "-c", "from aerodock.cli import main; main()", *args],
                            cwd=cwd, env=subprocess_env(), stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


def run_cli(*args: str) -> Any:
    """``aerodock ARGS`` in this process (no interpreter start-up), the plug-in module trusted
    for the call; asserts exit code 0."""
    from typer.testing import CliRunner

    from aerodock.cli.app import app

    if str(HERE) not in sys.path:
        sys.path.insert(0, str(HERE))
    result = CliRunner().invoke(app, list(args), env=TRUST)
    assert result.exit_code == 0, (args, result.output, result.exception)
    return result


def finite_numbers(obj: Any, path: str = "") -> list[str]:
    """Paths of every number in a JSON-like object that is not finite (empty: all finite)."""
    bad: list[str] = []
    if isinstance(obj, dict):
        for key, value in obj.items():
            bad += finite_numbers(value, f"{path}.{key}")
    elif isinstance(obj, list | tuple):
        for i, value in enumerate(obj):
            bad += finite_numbers(value, f"{path}[{i}]")
    elif isinstance(obj, float) and not math.isfinite(obj):
        bad.append(path)
    return bad


def load_json(text: str) -> Any:
    """Parse ``--json`` output (NaN and Infinity parse, so :func:`finite_numbers` sees them)."""
    return json.loads(text)
