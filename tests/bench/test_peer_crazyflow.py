"""``aerodock bench --only peer``'s crazyflow part (:mod:`aerodock.bench.peer_batches`): skipped
with one line when crazyflow is absent or its process fails, its commands in crazyflow's z-up
frame, and (slow, with crazyflow installed: ``pip install 'aerodock[peer]'``) a real flight of
all three simulators. Nothing here is timed."""

from __future__ import annotations

import importlib.util
import json
import sys

import numpy as np
import pytest
import typer
from typer.testing import CliRunner

from aerodock import bench
from aerodock.bench import crazyflow_worker, peer_batches
from aerodock.bench.peer import _peer_steps
from aerodock.cli.bench import bench_command

HAVE_CRAZYFLOW = importlib.util.find_spec("crazyflow") is not None


@pytest.fixture
def no_crazyflow(monkeypatch):
    """crazyflow looks absent, and nothing of aerodock may be flown."""
    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if name == "crazyflow" else real(name, *a))

    def refuse(*args, **kwargs):
        raise AssertionError("flown without crazyflow")

    monkeypatch.setattr(peer_batches, "peer_aerodock", refuse)
    monkeypatch.setattr("aerodock.bench.simulator.SimLoop", refuse)


def test_absent_crazyflow_is_one_line_reason_and_nothing_flown(cfg, no_crazyflow):
    out = peer_batches.compare_crazyflow(cfg)
    fig = out["crazyflow"]
    assert fig["value"] is None and fig["unit"] == "vehicle-steps/s"
    assert fig["reason"] == ("crazyflow not installed: pip install 'aerodock[peer]' to fly "
                             "crazyflow")
    assert out["ratios"] is None and "aerodock_world" not in out
    assert out["scenario"]["batches"] == [1, 256, 1024]
    rows = bench.table_rows({"figures": {"peer_crazyflow": out}})
    assert rows == [("peer batches: crazyflow", "null", "", "vehicle-steps/s", fig["reason"])]


def test_bench_only_peer_json_without_crazyflow(cfg, no_crazyflow, monkeypatch):
    monkeypatch.setattr(bench, "compare_rotorpy", lambda cfg, quick, progress: {"ratios": None})
    app = typer.Typer()
    app.command("bench")(bench_command)
    app.command("other")(lambda: None)
    result = CliRunner().invoke(app, ["bench", "--only", "peer", "--json"])
    assert result.exit_code == 0, result.output
    figs = json.loads(result.stdout)["figures"]
    assert set(figs) == {"peer", "peer_crazyflow"}
    assert figs["peer_crazyflow"]["crazyflow"]["reason"].startswith("crazyflow not installed")


@pytest.mark.skipif(HAVE_CRAZYFLOW, reason="crazyflow is installed: its worker would fly")
def test_failing_worker_is_one_line_reason(cfg, monkeypatch):
    """crazyflow found but not importable in its process: the worker's own error, one line."""
    monkeypatch.setattr(peer_batches, "crazyflow_missing", lambda: None)
    monkeypatch.setattr("aerodock.bench.simulator.SimLoop", None)  # never reached
    out = peer_batches.compare_crazyflow(cfg, quick=True, batches=(1,))
    assert out["crazyflow"]["value"] is None and out["ratios"] is None
    assert out["crazyflow"]["reason"] == ("crazyflow failed at 1 worlds: ModuleNotFoundError: "
                                          "No module named 'crazyflow'")


def test_worker_that_dies_is_a_reason_with_its_last_words(tmp_path, monkeypatch):
    script = tmp_path / "dies.py"
    script.write_text("import sys\nprint('noise')\nsys.stderr.write('boom\\n')\nsys.exit(3)\n")
    monkeypatch.setattr(crazyflow_worker, "__file__", str(script))
    with pytest.raises(peer_batches.CrazyflowUnavailable,
                       match=r"^its process ended \(exit code 3\): boom$"):
        peer_batches.CrazyflowWorker(1, np.zeros((2, 16)), np.zeros(3))


def test_worker_protocol_skips_noise(tmp_path, monkeypatch):
    """The worker's answers are the prefixed lines; other output is ignored; closing ends it."""
    script = tmp_path / "fake.py"
    script.write_text(
        "import json, sys\n"
        "print('a note from JAX')\n"
        f"print({crazyflow_worker.PREFIX!r} + json.dumps({{'ready': True, 'version': '9'}}),"
        " flush=True)\n"
        "for line in sys.stdin:\n"
        f"    print({crazyflow_worker.PREFIX!r} + json.dumps({{'wall_s': 2.0, 'cpu_s': 1.5,"
        " 'error_m': float(len(line))}), flush=True)\n")
    monkeypatch.setattr(crazyflow_worker, "__file__", str(script))
    with peer_batches.CrazyflowWorker(3, np.zeros((2, 16)), np.zeros(3)) as worker:
        assert worker.version == "9"
        assert worker.fly() == (2.0, 1.5, 4.0)  # "fly\n"
        proc = worker._proc
    assert proc.poll() == 0


def test_commands_are_the_reference_in_crazyflows_z_up_frame():
    every = 5
    steps = _peer_steps(False)
    ref = bench.peer_reference(steps, 1.0 / bench.PEER_PHYSICS_HZ)
    cmds = peer_batches.crazyflow_commands(ref, every)
    assert cmds.shape == (steps // every, 16) and cmds.dtype == np.float32
    start = np.array(peer_batches.CRAZYFLOW_START_ZUP_M)
    assert np.allclose(cmds[0, 0:3], start)
    north, east, down = bench.PEER_MOVE_NED_M
    assert np.allclose(cmds[-1, 0:3], start + [north, -east, -down], atol=1e-4)
    k = 250  # mid-move: moving north, west (east negated) and up
    assert cmds[k, 3] > 0 and cmds[k, 4] < 0 and cmds[k, 5] > 0
    assert np.allclose(cmds[k, 3:6], ref["x_dot"][k * every] * [1, -1, -1], atol=1e-6)
    assert np.all(cmds[:, 12] == 1.0) and np.all(cmds[:, [9, 10, 11, 13, 14, 15]] == 0.0)


@pytest.mark.slow
@pytest.mark.skipif(not HAVE_CRAZYFLOW, reason="crazyflow not installed (aerodock[peer])")
def test_all_three_fly_the_scenario(cfg):
    """crazyflow (in its process), aerodock's rigid body and its full world fly a batch of 2;
    both movers end near the move's end (which is 1.2 m from the start)."""
    out = peer_batches.compare_crazyflow(cfg, quick=False, batches=(2,))
    steps = out["scenario"]["steps"]
    assert out["scenario"]["crazyflow_version"]
    for key, vehicles in (("crazyflow", 2), ("aerodock_rigid_body", 2), ("aerodock_world", 4)):
        fig = out[key]["2"]
        assert fig["vehicle_steps"] == vehicles * steps and fig["repeats"] == 3
        assert fig["value"] > 0 and fig["per_cpu_s"] > 0
    assert out["crazyflow"]["2"]["final_error_m"] < 0.15
    assert out["aerodock_rigid_body"]["2"]["final_error_m"] < 0.05
    assert set(out["ratios"]["2"]) == {"rigid_body_vs_crazyflow", "world_vs_crazyflow"}
    assert all(r > 0 for r in out["ratios"]["2"].values())
    assert sys.modules.get("crazyflow") is None  # flown in its own process only
