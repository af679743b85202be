"""Fault injection: the file format, and campaigns that stay safe when things go wrong."""

from __future__ import annotations

import numpy as np
import pytest

from aerodock.control.compensation import Compensation
from aerodock.experiments.faults import (
    OUTCOME_COLUMNS,
    fault_campaign,
    rows_markdown,
    table_cells,
    table_headers,
)
from aerodock.mission import AbortReason, MissionSpec, run_campaign
from aerodock.mission.faults import Fault, FaultFileError, load_faults, parse_faults


def test_example_fault_file_loads():
    faults = load_faults("examples/faults.toml")
    assert len(faults) == 9
    assert {f.kind for f in faults} >= {"servo_jammed", "rotor_thrust_loss", "latency_spike"}


@pytest.mark.parametrize("doc, match", [
    ({}, "no \\[\\[fault\\]\\]"),
    ({"fault": [{"kind": "gremlins"}]}, "'kind' must be one of"),
    ({"fault": [{"kind": "servo_slow", "magnitude": float("nan")}]}, "finite"),
    ({"fault": [{"kind": "servo_slow", "probability": 2.0}]}, "probability"),
    ({"fault": [{"kind": "servo_slow", "start_s": [3.0, 1.0]}]}, "start_s"),
    ({"fault": [{"kind": "servo_slow", "colour": "red"}]}, "unknown key"),
    ({"faults": []}, "unknown table"),
])
def test_bad_fault_files_are_refused_with_the_entry_named(doc, match):
    with pytest.raises(FaultFileError, match=match):
        parse_faults(doc, "f.toml")


def test_fault_campaign_is_safe_and_counts_what_each_fault_does(docking_cfg):
    cfg = docking_cfg  # the mission's machinery, on a world where it docks (worlds.py)
    faults = [
        Fault("leader state lost", "leader_state_lost", 1.0, (2.0, 3.0)),
        Fault("servo jammed", "servo_jammed"),
        Fault("rotor loses 30 %", "rotor_thrust_loss", 1.0, (2.0, 3.0), magnitude=0.3),
    ]
    rows = fault_campaign(cfg, faults, 6, 4, Compensation.ORACLE, None)
    by = {r["fault"]: r for r in rows}
    assert by["no fault"]["docked"] >= 5
    for r in rows:
        assert r["clearance_violations"] == 0 and r["nan_trials"] == 0
        assert r["docked"] + r["aborts"] <= r["struck"]  # never both docked and aborted
    lost = by["leader state lost"]
    assert lost["safe_aborts"] >= 4 and lost["abort_reasons"]["leader_lost"] >= 4
    # A hobby servo does not report its position: the follower believes the gate shut, acts as
    # docked, falls away from the bar and backs off (a miss, not an abort).
    jam = by["servo jammed"]
    assert jam["docked"] == 0 and jam["abort_reasons"]["gate_fault"] == 0
    assert jam["sensed_misses"] >= 4 and jam["clearance_violations"] == 0
    # ... and the table says so in a column of its own: every struck trial has one outcome
    assert jam["not_held"] >= 4 and jam["missed_or_slipped"] == 0
    for r in rows:
        assert sum(r[key] for key, _ in OUTCOME_COLUMNS) == r["struck"], r
    table = rows_markdown(rows).splitlines()
    assert table[0].count("|") - 1 == len(table_headers()) == 2 + len(OUTCOME_COLUMNS) + 3
    assert "not held (gate never shut)" in table[0]
    jam_line = next(line for line in table if line.startswith("| servo jammed |"))
    cells = [c.strip() for c in jam_line.strip("|").split("|")]
    assert cells == table_cells(jam)
    assert cells[table_headers().index("not held (gate never shut)")] == str(jam["not_held"])


def test_a_servo_that_reports_its_position_tells_a_jammed_gate(cfg):
    """The jammed-servo campaign of fault_campaign's row (its spec; the rows' counting is
    checked above), without the fault-free campaign the table flies first."""
    c = cfg.with_overrides({"gripper": {"servo_feedback": True}})
    jam = run_campaign(c, MissionSpec(trials=6, offset_m=0.36, compensation="oracle", seed=4,
                                      faults=(Fault("servo jammed", "servo_jammed"),)))
    assert jam.fault_hit.all()
    assert not jam.success.any() and jam.summary()["abort_reasons"]["gate_fault"] >= 4
    assert jam.clearance_violation.sum() == 0


def test_a_fault_strikes_only_the_drawn_trials(short_cfg):
    cfg = short_cfg  # the draws and their determinism, whatever the timing (tests/short_mission.py)
    half = Fault("sensor dead, half the trials", "contact_sensor_dead", probability=0.5)
    res = run_campaign(cfg, MissionSpec(trials=12, compensation="oracle", seed=8,
                                        faults=(half,)))
    assert 0 < res.fault_hit.sum() < 12
    again = run_campaign(cfg, MissionSpec(trials=12, compensation="oracle", seed=8,
                                          faults=(half,)))
    assert np.array_equal(res.fault_hit, again.fault_hit)
    assert np.array_equal(res.success, again.success)
    assert not (res.abort_reason == AbortReason.GATE_FAULT).any()


def test_the_docs_fault_table_has_the_commands_columns():
    """docs/research-tools.md quotes `aerodock faults --markdown`: its table has the same
    header, and a row per fault of examples/faults.toml (and the baseline)."""
    from pathlib import Path

    doc = (Path(__file__).parents[2] / "docs" / "research-tools.md").read_text().splitlines()
    header = rows_markdown([]).splitlines()[0]
    start = doc.index(header) + 2  # after the header and its rule
    end = next(i for i in range(start, len(doc)) if not doc[i].startswith("|"))
    rows = doc[start:end]
    names = [r.strip("|").split("|")[0].strip() for r in rows]
    assert names == ["no fault", *(f.name for f in load_faults("examples/faults.toml"))]
    assert all(r.count("|") == header.count("|") for r in rows)
