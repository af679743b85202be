"""Benchmarks of the hot paths (pytest-benchmark) and checks of ``aerodock bench``'s plumbing.

The benchmarks are light (a few bounded rounds) so that they also pass quickly under plain
``pytest``; they time, they assert nothing about speed. ``aerodock bench`` is the full measurement.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import typer
from short_mission import short_mission_toml
from typer.testing import CliRunner

from aerodock import bench
from aerodock.bench.learning import _numpy_predictor
from aerodock.bench.memory import bench_memory
from aerodock.bench.peer import _peer_steps
from aerodock.cli.bench import bench_command
from aerodock.rng import TrialRNG
from aerodock.world import World, hover_command


@pytest.fixture(scope="module")
def world64(cfg):
    n = 64
    world = World(cfg, n, TrialRNG(0, n))
    lead = np.tile([0.0, 0.0, -2.5], (n, 1))
    world.reset(lead, lead + [0.05, 0.0, 0.6])
    return world, hover_command(world.vehicle, n)


def test_bench_world_step_batch_64(benchmark, world64):
    world, cmd = world64

    def ten_steps():
        for _ in range(10):
            world.step(cmd, cmd)

    benchmark.pedantic(ten_steps, rounds=5, iterations=1, warmup_rounds=1)
    assert np.all(np.isfinite(world.follower.p))


def test_bench_control_period_with_controllers_batch_64(benchmark, cfg):
    loop = bench.SimLoop(cfg, 64)
    benchmark.pedantic(loop.run, args=(2,), rounds=5, iterations=1, warmup_rounds=1)
    assert np.all(np.isfinite(loop.world.follower.p))


def test_bench_numpy_predictor_single_call(benchmark):
    pytest.importorskip("aerodock.learning.runtime")
    pred = _numpy_predictor(None)  # an untrained network: same cost as a trained one
    x, rot = bench.predictor_inputs(1)
    out = benchmark.pedantic(pred.predict_one, args=(x[0], rot[0]), rounds=20, iterations=10,
                             warmup_rounds=1)
    assert out.shape == (3,)


# -- the bench module's plumbing -----------------------------------------------------------------
def test_figure_is_median_with_spread():
    fig = bench.figure([3.0, 1.0, 2.0], "s", "a note")
    assert fig == {"value": 2.0, "min": 1.0, "max": 3.0, "repeats": 3, "unit": "s",
                   "note": "a note"}
    assert bench.unavailable("why", "s") == {"value": None, "unit": "s", "reason": "why"}


def test_sim_loop_counts_vehicle_steps(cfg):
    loop = bench.SimLoop(cfg, 3)
    assert loop.vehicle_steps_per_period == 2 * 3 * loop.world.substeps
    loop.run(2)
    loop.run(1, controllers=False)
    assert loop.world.step_index == 3 * loop.world.substeps


@pytest.mark.parametrize("model", ["rigid-body", "point-mass"])
def test_simulator_and_docking_figures(cfg, model):
    sim = bench.bench_simulator(cfg, batches=(2,), quick=True, model=model)
    for key in ("with_controllers", "physics_only"):
        fig = sim["2"][key]
        assert fig["unit"] == "vehicle-steps/s" and fig["value"] > 0 and fig["repeats"] == 3
        assert fig["min"] <= fig["value"] <= fig["max"]
        assert fig["note"].startswith(model)
        assert fig["per_cpu_s"] > 0


def test_predictor_figures_without_a_trained_model():
    pytest.importorskip("aerodock.learning.runtime")
    out = bench.bench_predictor(None, quick=True)
    assert out["numpy"]["single_call_us"]["value"] > 0
    assert out["numpy"]["batch1024_per_sample_us"]["value"] > 0
    for rt in ("onnx", "torch"):  # nothing to export or run without a trained model
        assert out[rt]["value"] is None and out[rt]["reason"]


def test_memory_figure_from_a_subprocess(tmp_path):
    short = tmp_path / "short.toml"  # the figures' plumbing: the short timing (short_mission.py)
    short.write_text(short_mission_toml())
    out = bench_memory(trials=2, traced=False, config_path=short)
    assert out["peak_rss_mib"]["unit"] == "MiB"
    assert out["peak_rss_mib"]["value"] >= out["rss_after_imports_mib"]["value"] > 10
    assert out["campaign_wall_s"]["value"] > 0 and "traced_peak_mib" not in out


def test_targets_report_met_unmet_and_unmeasured():
    figs = {
        "simulator": {"256": {"physics_only": {"value": 6e5}, "with_controllers": {"value": 4e5}}},
        "simulator_point_mass": {"256": {"with_controllers": {"value": 1.2e6}}},
        "predictor": {"numpy": {"single_call_us": {"value": 20.0}}},
        "peer": {"ratios": {"single_trial": 25.0}},
        "reproduce_quick_s": bench.unavailable("not available", "s"),
        "gym_env_reset": {"block_mean_reset": {"value": 0.08}},
    }
    met = [t["met"] for t in bench.targets(figs)]
    # issue 38's: at 256 (4e5 < 3e6) unmet; the figures not measured, unmeasured
    assert met == [True, False, True, True, True, None, True, None, False, None, None, None, None]
    figs["simulator"].update({"1": {"with_controllers": {"value": 2.5e5}},
                              "1024": {"with_controllers": {"value": 2.0e6}}})
    figs["reproduce_quick_s"] = {"value": 80.0}
    figs["gym_vector_env"] = {"1": {"value": 4000.0}, "128": {"value": 2.1e5}}
    issue_38 = {t["target"]: t["met"] for t in bench.targets(figs)[7:]}
    assert list(issue_38.values()) == [True, False, False, True, False, True], issue_38
    assert all("issue 38" in name for name in issue_38)


def test_peer_reference_is_a_rest_to_rest_minimum_jerk_move():
    dt = 1.0 / bench.PEER_PHYSICS_HZ
    steps = _peer_steps(False)
    ref = bench.peer_reference(steps + 1, dt)
    assert np.allclose(ref["x"][0], 0.0) and np.allclose(ref["x"][-1], bench.PEER_MOVE_NED_M)
    assert np.allclose(ref["x_dot"][[0, -1]], 0.0, atol=1e-12)
    # velocity is the derivative of position, jerk that of acceleration
    assert np.allclose(np.gradient(ref["x"], dt, axis=0)[1:-1], ref["x_dot"][1:-1], atol=1e-4)
    assert np.allclose(np.gradient(ref["x_ddot"], dt, axis=0)[600:2000],
                       ref["x_dddot"][600:2000], atol=1e-3)


def test_peer_aerodock_tracks_the_move(cfg):
    steps = _peer_steps(False)
    ref = bench.peer_reference(steps, 1.0 / bench.PEER_PHYSICS_HZ)
    err, physics_s = bench.peer_aerodock(cfg, 2, steps, ref)
    assert err < 0.05 and physics_s > 0


def test_peer_rotorpy_tracks_the_move_when_installed(cfg):
    pytest.importorskip("rotorpy")
    steps = 100
    ref = bench.peer_reference(steps, 1.0 / bench.PEER_PHYSICS_HZ)
    err, physics_s = bench.peer_rotorpy(cfg, steps, ref)  # aerodock's vehicle in RotorPy
    assert err < 0.01 and physics_s > 0


def test_bench_command_help_and_table_rows():
    app = typer.Typer()
    app.command("bench")(bench_command)
    app.command("other")(lambda: None)  # two commands: `bench` stays a subcommand
    result = CliRunner().invoke(app, ["bench", "--help"])
    assert result.exit_code == 0 and "--json" in result.output and "--quick" in result.output
    doc = {"figures": {
        "simulator": {"1": {"with_controllers": bench.figure([1e4, 2e4, 3e4], "vehicle-steps/s"),
                            "physics_only": bench.unavailable("why", "vehicle-steps/s")}},
        "predictor": {"numpy": bench.unavailable("no runtime", "us")},
        "peer": {"ratios": {"single_trial": 30.0}},
    }}
    rows = bench.table_rows(doc)
    assert ("simulator rigid-body, batch 1, with controllers", "20,000", "10,000 - 30,000 (x3)",
            "vehicle-steps/s", "") in rows
    assert ("simulator rigid-body, batch 1, physics only", "null", "", "vehicle-steps/s",
            "why") in rows
    assert any(r[0] == "predictor numpy" and r[1] == "null" for r in rows)
    assert ("ratio: single trial", "30.0x", "", "", "") in rows
    json.dumps(doc)  # JSON-ready


def test_bench_only_one_part_and_bad_part(cfg, monkeypatch):
    monkeypatch.setattr(bench, "SIM_BATCHES", (1,))
    monkeypatch.setattr(bench, "bench_simulator",
                        lambda cfg, quick, progress, model: {"1": {"model": model}})
    monkeypatch.setattr(bench, "bench_vehicle_step", lambda cfg, quick, progress: {})
    monkeypatch.setattr(bench, "bench_python_field", lambda cfg, quick, progress: {})
    monkeypatch.setattr(bench, "bench_kernels", lambda cold, progress: {"cold": cold})
    doc = bench.run_all(cfg, quick=True, only="simulator")
    assert set(doc["figures"]) == {"simulator", "simulator_point_mass", "vehicle_step",
                                   "simulator_python_field", "kernels"}
    assert doc["figures"]["kernels"] == {"cold": False}  # --quick compiles nothing
    assert doc["figures"]["simulator_point_mass"]["1"]["model"] == "point-mass"
    app = typer.Typer()
    app.command("bench")(bench_command)
    app.command("other")(lambda: None)
    result = CliRunner().invoke(app, ["bench", "--only", "nonsense"])
    assert result.exit_code == 2 and "Invalid value for '--only'" in result.output


def test_vehicle_step_figures(cfg):
    out = bench.bench_vehicle_step(cfg, batches=(2,), quick=True)
    for model in ("rigid-body", "point-mass"):
        fig = out[model]["2"]
        assert fig["unit"] == "vehicle-steps/s" and fig["value"] > 0 and fig["per_cpu_s"] > 0
        assert fig["note"].startswith(model)


def test_bench_json_is_strict_with_a_missing_figure_as_null(monkeypatch):
    doc = {"machine": {}, "figures": {"docking": {"trial_1": bench.figure([1.0], "s")}},
           "targets": [], "ratio": float("nan"), "spread": [float("inf"), 1.0]}
    # (the command reads run_all from aerodock.bench when it runs: the package loads its parts
    # on use, so that the command line starts without them)
    monkeypatch.setattr(bench, "run_all", lambda *args, **kwargs: doc)
    app = typer.Typer()
    app.command("bench")(bench_command)
    app.command("other")(lambda: None)
    result = CliRunner().invoke(app, ["bench", "--quick", "--json"])
    assert result.exit_code == 0, result.output

    def refuse(name):
        raise ValueError(f"not JSON: {name}")

    out = json.loads(result.stdout, parse_constant=refuse)  # no NaN or Infinity in the text
    assert out["ratio"] is None and out["spread"] == [None, 1.0]
    assert out["figures"]["docking"]["trial_1"]["value"] == 1.0


def test_node_figures_pair_each_output_with_its_follower_state():
    """``replay_figures``: end to end from the follower state each output was computed from,
    cut into pieces that sum to it; watchdog outputs counted, not timed (no ROS needed)."""
    from aerodock.bench.node import PATH_SEGMENTS, replay_figures, state_to_prediction_ms
    from aerodock.node.replay import ReplayRecord

    rec = ReplayRecord()
    sends = [100.0 + 0.01 * i for i in range(5)]
    rec.send_times_s = sends
    for i, sent in enumerate(sends):
        rec.published_s[sent] = sent + 0.0005
        # the answer to message i is computed from message i, out 2 ms (+ i * 0.1 ms) later
        stamp = sent + 0.0015 + 1e-4 * i
        received = stamp + 0.0005
        rec.outputs.append((received, stamp, 0.1, 0.2, 0.3))
        rec.output_dds_s[stamp] = (stamp + 1e-4, stamp + 3e-4)
        rec.diagnostics.append((received, stamp, {
            "trigger": "follower", "stale": "false", "latency_ms": "0.2", "queue_ms": "0.3",
            "compute_ms": "0.01", "follower_stamp": repr(sent)}))
    # a watchdog output from the last state: not an answer, not timed
    rec.outputs.append((sends[-1] + 0.012, sends[-1] + 0.011, 0.1, 0.2, 0.3))
    rec.diagnostics.append((sends[-1] + 0.012, sends[-1] + 0.011, {
        "trigger": "watchdog", "stale": "false", "latency_ms": "0.2", "queue_ms": "nan",
        "compute_ms": "0.01", "follower_stamp": repr(sends[-1])}))
    figures = replay_figures(rec, "on-follower")
    assert figures["outputs_by_trigger"] == {"follower": 5, "timer": 0, "watchdog": 0}
    assert figures["follower_messages_answered"] == 5
    assert figures["follower_messages_answered_twice"] == 0
    e2e = figures["end_to_end_ms"]
    assert e2e["n"] == 5 and e2e["median"] == pytest.approx(2.2)
    assert figures["path_ms"]["replay_send"]["median"] == pytest.approx(0.5)
    assert figures["path_ms"]["node_queue"]["median"] == pytest.approx(0.3)
    assert figures["path_ms"]["node_publish"]["median"] == pytest.approx(0.1)
    assert figures["path_ms"]["dds_out"]["median"] == pytest.approx(0.2)
    assert figures["path_ms"]["replay_wait"]["median"] == pytest.approx(0.2)
    # the node's side: publish returned (+0.5 ms) to its DDS write (stamp + 0.1 ms)
    assert figures["node_side_ms"]["median"] == pytest.approx(1.3)
    # the consecutive pieces (node_queue is part of to_trigger) add up to end to end
    pieces = [k for k in PATH_SEGMENTS if k != "node_queue"]
    worst = figures["path_ms_in_the_worst_1pct"]
    assert sum(worst[k] for k in pieces) == pytest.approx(2.4, abs=1e-6)  # the slowest: i = 4
    # each state until an output from it or a newer one: here its own answer
    assert figures["state_to_prediction_ms"]["median"] == pytest.approx(2.2)
    # a state the node skipped counts, until the answer to the next one (2.3 ms after it)
    skipped = ReplayRecord(send_times_s=rec.send_times_s, published_s=rec.published_s,
                           outputs=[o for o in rec.outputs if o[1] != sends[1] + 0.0016],
                           diagnostics=rec.diagnostics, output_dds_s=rec.output_dds_s)
    cover = replay_figures(skipped, "on-follower")
    assert cover["follower_messages_answered"] == 4
    assert cover["end_to_end_ms"]["n"] == 4
    assert cover["state_to_prediction_ms"]["n"] == 5
    by_stamp = {row[1]: row for row in skipped.outputs}
    paired = [(by_stamp[st], v) for _, st, v in skipped.diagnostics if st in by_stamp]
    np.testing.assert_allclose(state_to_prediction_ms(skipped, paired),
                               [2.0, 10 + 2.2, 2.2, 2.3, 2.4], atol=1e-6)
    # the timer mode's own outputs are ticks: these follower answers are not timed there
    assert replay_figures(rec, "timer")["end_to_end_ms"]["n"] == 0
