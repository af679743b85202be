"""Sweeps: the specification, the tidy table, the figures, and Ray = local for the same seeds."""

from __future__ import annotations

import csv
import json

import pytest
from cli_process import aerodock
from short_mission import short_mission_toml

from aerodock.sweep import SweepSpecError, load_spec, parse_spec, run_sweep, write_table

TINY = """
[sweep]
name = "tiny"
trials = 2
seeds = [0]
[axes]
cable_length_m = [0.36, 0.64]
compensation = ["observer", "oracle"]
"""


def test_grid_expands_every_combination_times_seeds():
    spec = parse_spec({"sweep": {"trials": 3, "seeds": [0, 7]},
                       "axes": {"cable_length_m": [0.36, 0.64], "leader_speed_mps": [0.0, 0.25],
                                "leader_dropout_s": ["none", [3.0, 1.0]]}})
    assert len(spec.cells) == 2 * 2 * 2 * 2
    combos = {(c.cable_length_m, c.leader_speed_mps, c.leader_dropout_s, c.seed)
              for c in spec.cells}
    assert len(combos) == 16
    assert [c.index for c in spec.cells] == list(range(16))
    assert {c.compensation for c in spec.cells} == {"observer"}


def test_random_study_draws_inside_the_ranges_reproducibly():
    doc = {"sweep": {"kind": "random", "samples": 30, "sampling_seed": 4},
           "axes": {"cable_length_m": {"min": 0.3, "max": 1.4},
                    "compensation": ["observer", "oracle"]}}
    a, b = parse_spec(doc), parse_spec(doc)
    lengths = [c.cable_length_m for c in a.cells]
    assert all(0.3 <= x <= 1.4 for x in lengths) and len(set(lengths)) == 30
    assert {c.compensation for c in a.cells} == {"observer", "oracle"}
    assert a.cells == b.cells


@pytest.mark.parametrize("doc, message", [
    ({"axes": {"wind_mps": [1.0]}}, "unknown axis 'axes.wind_mps'"),
    ({"axes": {"cable_length_m": [-0.3]}}, "must be > 0"),
    ({"axes": {"compensation": ["magic"]}}, "not one of"),
    ({"axes": {"leader_dropout_s": [[1.0]]}}, "leader_dropout_s"),
    ({"axes": {"compensation": ["model"]}}, "needs sweep.model"),
    ({"sweep": {"trials": 0}}, "sweep.trials"),
    ({"axes": {"cable_length_m": {"min": 0.3, "max": 1.0}}}, "needs a random study"),
])
def test_bad_specifications_name_the_key(doc, message):
    with pytest.raises(SweepSpecError, match=message):
        parse_spec(doc, "s.toml")


def test_leader_dropout_fault_shows_in_the_table(short_cfg):
    # (the table's columns, whatever the mission's timing: the short one, tests/short_mission.py)
    spec = parse_spec({"sweep": {"trials": 2}, "axes": {"leader_dropout_s": [[1.0, 2.0]]}})
    rows = run_sweep(spec, short_cfg, backend="local", jobs=1)
    assert [r["abort_reason"] for r in rows] == ["leader_lost", "leader_lost"]
    assert all(r["fault"] == "leader_dropout" and r["dropout_start_s"] == 1.0 for r in rows)


def test_cells_that_share_a_world_fly_as_one_batch_with_their_own_numbers(short_cfg):
    """Seeds of one point fly as one batch, each trial as in its own cell's campaign: the same
    rows as flying every cell alone; the batches split while workers would idle."""
    from aerodock.sweep.run import batches, run_cell

    spec = parse_spec({"sweep": {"trials": 2, "seeds": [0, 5]},
                       "axes": {"compensation": ["observer", "oracle"]}})
    groups = batches(list(spec.cells), workers=1)
    assert [[c.seed for c in g] for g in groups] == [[0, 5], [0, 5]]
    assert {len({c.compensation for c in g}) for g in groups} == {1}
    assert [len(g) for g in batches(list(spec.cells), workers=3)] == [1, 1, 2]
    assert len(batches(list(spec.cells[:1]), workers=4)) == 1
    batched = run_sweep(spec, short_cfg, backend="local", jobs=1)
    alone = [row for cell in spec.cells for row in run_cell(short_cfg, cell, 2, None)]
    assert batched == alone  # same rows, same floats
    # the seeds differ in their outcomes' numbers: each row drew its own cell's stream
    assert len({r["min_clearance_m"] for r in batched}) == len(batched)


def test_ray_backend_table_equals_local_backend(tmp_path, short_cfg):
    # Ray = local whatever the mission's timing: the short one (tests/short_mission.py)
    cfg = short_cfg
    ray = pytest.importorskip("ray")
    spec_path = tmp_path / "tiny.toml"
    spec_path.write_text(TINY)
    spec = load_spec(spec_path)
    local = run_sweep(spec, cfg, backend="local", jobs=2)
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        remote = run_sweep(spec, cfg, backend="ray")
    finally:
        ray.shutdown()
    assert len(local) == 4 * 2
    assert remote == local  # same rows, same order, same floats
    write_table(local, tmp_path / "a")
    write_table(remote, tmp_path / "b")
    assert (tmp_path / "a/results.csv").read_bytes() == (tmp_path / "b/results.csv").read_bytes()
    # Real outcomes, not constants: the oracle docks where the slow observer does not.
    oracle = [r["docked"] for r in local if r["compensation"] == "oracle"]
    observer = [r["docked"] for r in local if r["compensation"] == "observer"]
    assert sum(oracle) > sum(observer)


def test_sweep_command_writes_table_parquet_summary_and_figures(tmp_path):
    spec_path = tmp_path / "tiny.toml"
    # the command's files, whatever the mission's timing: the short one (tests/short_mission.py)
    (tmp_path / "short.toml").write_text(short_mission_toml())
    spec_path.write_text(TINY.replace('["observer", "oracle"]', '["oracle"]')
                         .replace("[0.36, 0.64]", "[0.36]")
                         .replace("[sweep]\n", '[sweep]\nconfig = "short.toml"\n'))
    out = tmp_path / "out"
    proc = aerodock("sweep", str(spec_path), "--out", str(out), "--jobs", "1", "--json")
    assert proc.returncode == 0, proc.stderr
    summary = json.loads(proc.stdout)
    with open(out / "results.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == summary["trials"] == 2
    assert summary["docked"] == sum(r["docked"] == "True" for r in rows)
    for name in ("sweep_success.png", "sweep_error.png"):
        assert (out / "figures" / name).read_bytes()[:4] == b"\x89PNG"
    pq = pytest.importorskip("pyarrow.parquet")
    table = pq.read_table(out / "results.parquet").to_pylist()
    assert [r["min_clearance_m"] for r in table] == [float(r["min_clearance_m"]) for r in rows]


def test_sweep_command_bad_spec_is_one_line_error(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[axes]\nwind_mps = [1.0]\n")
    proc = aerodock("sweep", str(bad), "--out", str(tmp_path / "o"))
    assert proc.returncode == 2
    assert proc.stderr.strip().count("\n") == 0 and "unknown axis" in proc.stderr
    assert "Traceback" not in proc.stderr
    assert not (tmp_path / "o").exists()
