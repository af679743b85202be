"""The example ROS 2 launch file (examples/launch/aerodock_node.launch.py).

ros2launch (``launch``) is not installed here, so the file is read, not launched: it parses as
Python, names the real command (``aerodock``, the console script of pyproject.toml) and only
options ``aerodock node`` has; then the command it builds, with its launch arguments filled in,
is run for real (rclpy, a localhost domain of this run): it starts, its node is in the
namespace the launch file gives it, publishes ``f_ext`` there, and takes ``use_sim_time``.
"""

from __future__ import annotations

import ast
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import pytest
import typer
from node_helpers import random_model

from aerodock.cli.app import app

ROOT = Path(__file__).resolve().parents[2]
LAUNCH = ROOT / "examples" / "launch" / "aerodock_node.launch.py"


def _launch_call(tree: ast.Module, name: str) -> list[ast.Call]:
    return [n for n in ast.walk(tree) if isinstance(n, ast.Call)
            and isinstance(n.func, ast.Name) and n.func.id == name]


def _declared(tree: ast.Module) -> dict[str, ast.expr | None]:
    """Launch argument name -> its ``default_value`` expression (None: required)."""
    out = {}
    for call in _launch_call(tree, "DeclareLaunchArgument"):
        default = next((k.value for k in call.keywords if k.arg == "default_value"), None)
        out[ast.literal_eval(call.args[0])] = default
    return out


def _command(tree: ast.Module, values: dict[str, str]) -> list[str]:
    """The ``ExecuteProcess`` command with the launch arguments ``values`` substituted (a list
    element is the concatenation of its parts, as ``launch`` makes it)."""

    def word(node: ast.expr) -> str:
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            return node.value
        if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
                and node.func.id == "LaunchConfiguration"):
            return values[ast.literal_eval(node.args[0])]
        if isinstance(node, ast.List):
            return "".join(word(e) for e in node.elts)
        raise AssertionError(f"unexpected command element {ast.dump(node)}")

    (call,) = _launch_call(tree, "ExecuteProcess")
    cmd = next(k.value for k in call.keywords if k.arg == "cmd")
    assert isinstance(cmd, ast.List)
    return [word(e) for e in cmd.elts]


def test_the_launch_file_names_the_real_command_and_its_options():
    source = LAUNCH.read_text()
    tree = ast.parse(source, filename=str(LAUNCH))
    compile(tree, str(LAUNCH), "exec")
    assert [f.name for f in tree.body if isinstance(f, ast.FunctionDef)] == [
        "generate_launch_description"]  # what ros2 launch calls
    declared = _declared(tree)
    assert declared["model"] is None  # required: model:=DIR
    assert "odometry_mapping.toml" in ast.unparse(declared["mapping"])
    cmd = _command(tree, {name: f"<{name}>" for name in declared})
    scripts = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
    assert cmd[:2] == ["aerodock", "node"] and scripts["aerodock"] == "aerodock.cli:main"
    node = typer.main.get_command(app).commands["node"]
    options = {opt for p in node.params for opt in p.opts}
    ours = cmd[2:cmd.index("--ros-args")]
    assert {w for w in ours if w.startswith("--")} <= options
    assert "--model" in ours and "<model>" in ours
    assert cmd[cmd.index("--ros-args") + 1:] == ["-r", "__ns:=/<namespace>",
                                                 "-p", "use_sim_time:=<use_sim_time>"]
    mapping = ROOT / "examples" / "launch" / "odometry_mapping.toml"
    from aerodock.ingest.rosbag import load_mapping

    merged, explicit = load_mapping(mapping)
    assert merged["frame"] == "enu" and "frame" not in explicit  # ENU as Odometry is


def test_the_launched_command_runs_in_its_namespace_with_sim_time(tmp_path, monkeypatch):
    pytest.importorskip("rclpy")
    pytest.importorskip("rcl_interfaces.srv")
    import rclpy
    from rcl_interfaces.srv import GetParameters

    from aerodock.node.replay import LOCALHOST_ENV, free_domain_id, ros_env

    tree = ast.parse(LAUNCH.read_text())
    values = {"model": str(random_model(tmp_path / "model")), "namespace": "bravo",
              "mapping": str(ROOT / "examples" / "launch" / "odometry_mapping.toml"),
              "use_sim_time": "true"}
    cmd = _command(tree, values)
    at = cmd.index("--ros-args")
    args = [*cmd[2:at], "--duration", "60", *cmd[at:]]
    domain = free_domain_id()
    proc = subprocess.Popen([sys.executable, "-c", "from aerodock.cli import main; main()",
                             "node", *args], env=ros_env(domain), stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    for key, value in LOCALHOST_ENV.items():
        monkeypatch.setenv(key, value)
    monkeypatch.setenv("ROS_DOMAIN_ID", str(domain))
    rclpy.init()
    client = rclpy.create_node("aerodock_launch_check")
    try:
        deadline = time.monotonic() + 60.0
        while not (("aerodock_f_ext", "/bravo") in client.get_node_names_and_namespaces()
                   and "/bravo/f_ext" in dict(client.get_topic_names_and_types())):
            assert proc.poll() is None, proc.communicate()[1]
            assert time.monotonic() < deadline, "the node did not show up in /bravo"
            rclpy.spin_once(client, timeout_sec=0.05)
        params = client.create_client(GetParameters, "/bravo/aerodock_f_ext/get_parameters")
        assert params.wait_for_service(timeout_sec=60.0)
        future = params.call_async(GetParameters.Request(names=["use_sim_time"]))
        rclpy.spin_until_future_complete(client, future, timeout_sec=60.0)
        assert future.result().values[0].bool_value is True
    finally:
        client.destroy_node()
        rclpy.shutdown()
        proc.kill()
        _, stderr = proc.communicate(timeout=30)
    assert "error" not in stderr.lower() and "Traceback" not in stderr
