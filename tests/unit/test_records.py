"""Typed results write exactly the JSON the files held before them.

Each expected object below is built by the statements the code ran before the records existed
(the dicts ``reproduce`` and ``targets`` assembled, copied here), from the same
fabricated inputs, and compared with the record's ``to_json()`` as JSON text: the same keys, in
the same order, the same values, so ``results.json`` and ``targets.json`` keep their bytes
(``model.json``'s training record: tests/learning/test_training_record.py).
"""

from __future__ import annotations

import json
from dataclasses import FrozenInstanceError, replace
from pathlib import Path

import numpy as np
import pytest

from aerodock.experiments.docking_runs import _window_mean
from aerodock.experiments.records import (
    UNITS,
    AltitudeWindow,
    ControllersRecord,
    DockingRecord,
    HoverDocking,
    LearningRecord,
    LearntMean,
    MovingLeader,
    MovingMode,
    OursController,
    PaperController,
    ReproduceResults,
    RunHeader,
    ScenarioSpec,
    TargetRow,
    TargetsProvenance,
    TargetsResult,
    TunedController,
)
from aerodock.experiments.reproduce import _renamed
from aerodock.experiments.targets import _KEYS, SCENARIOS, scenario_outcome
from aerodock.mission import Phase


def _text(obj: object) -> str:
    return json.dumps(obj, indent=2)


def _summary(rng: np.random.Generator, trials: int = 4) -> dict:
    """A campaign summary's shape (more keys than a scenario keeps), with arrival_s."""
    docked = int(rng.integers(0, trials + 1))
    return {"trials": trials, "docked": docked, "success_rate": docked / trials,
            "success_wilson95": [float(rng.random()) / 2, 0.5 + float(rng.random()) / 2],
            "slip_throughs": 1, "missed": 0, "sensed_misses": 0, "aborts": 1,
            "abort_reasons": {"none": 3}, "clearance_violations": 0, "rotor_strikes": 0,
            "post_dock_sink_median_m": None, "terminal_err_down_median_m": float(rng.random()),
            "terminal_err_3d_median_m": float(rng.random()),
            "terminal_tilt_rms_deg_median": float(rng.random()),
            "arrival_s": 4.0}


def _old_scenario(s: dict, offset: float, speed: float, target: float) -> dict:
    rec = {key: s[key] for key in _KEYS}
    rec.update({"offset_m": offset, "leader_speed_mps": speed, "target_success": target,
                "met": s["success_rate"] >= target})
    return rec


def _learnt(where: str, rel: float | None) -> tuple[LearntMean, dict]:
    old = {"where": where, "depth_m": 0.36, "field_mean_down_mps2": 4.5,
           "learnt_down_mps2": 4.4, "relative_error": rel,
           "met": rel is not None and abs(rel) <= 0.1}
    return LearntMean(**old), old


def _targets(rng: np.random.Generator, rows: list[str]) -> tuple[TargetsResult, dict]:
    """The same targets as a record and as the old dict (targets() before the records)."""
    out: dict = {"trials": 4, "scenarios": [
        {"name": n, "offset_m": o, "leader_speed_mps": s, "target_success": t}
        for n, o, s, t in SCENARIOS], "err_down_target_m": 0.015,
        "mean_rel_target": 0.1, "rows": {}}
    typed_rows = {}
    for name in rows:
        summaries = {n: _summary(rng) for n, *_ in SCENARIOS}
        recs = {n: _old_scenario(summaries[n], o, s, t) for n, o, s, t in SCENARIOS}
        err = recs["hover_0.36"]["terminal_err_down_median_m"]
        out["rows"][name] = {"scenarios": recs, "err_down_met": err <= 0.015}
        typed_rows[name] = TargetRow(
            scenarios={n: scenario_outcome(summaries[n], o, s, t) for n, o, s, t in SCENARIOS},
            err_down_met=err <= 0.015)
    learnt, out["learnt_mean"] = zip(*[_learnt("0.36 m", 0.02), _learnt("docking depth", None)],
                                     strict=True)
    out["learnt_mean"] = list(out["learnt_mean"])
    record = TargetsResult(trials=4, scenarios=[ScenarioSpec(*s) for s in SCENARIOS],
                           err_down_target_m=0.015, mean_rel_target=0.1, rows=typed_rows,
                           learnt_mean=list(learnt))
    return record, out


def test_a_scenario_outcome_keeps_the_old_keys_in_order():
    s = _summary(np.random.default_rng(0))
    assert _text(scenario_outcome(s, 0.36, 0.25, 0.9).to_json()) == _text(
        _old_scenario(s, 0.36, 0.25, 0.9))
    assert scenario_outcome(s, 0.36, 0.25, 0.0).met  # every rate reaches a target of 0


def test_targets_json_is_the_old_targets_json_with_the_cli_fields():
    record, old = _targets(np.random.default_rng(1), ["paper's controller + model",
                                                      "ours + model"])
    assert _text(record.to_json()) == _text(old)
    # aerodock targets adds where its numbers came from (res.update before the records)
    old.update({"model": "out/data/models/final", "config": None, "field": "jet"})
    cli = replace(record, provenance=TargetsProvenance("out/data/models/final", None, "jet"))
    assert _text(cli.to_json()) == _text(old)
    assert [label for label, _ in cli.learnt_means()] == ["deep curriculum"]


def test_the_altitude_window_is_the_old_one():
    rng = np.random.default_rng(2)
    t = np.arange(0.0, 8.0, 0.5)
    trace = {"t_s": t, "follower_p": rng.normal(size=(t.size, 3, 3)),
             "ref_p": rng.normal(size=(t.size, 3, 3)),
             "phase": np.where(rng.random((t.size, 3)) < 0.7, Phase.TERMINAL, Phase.CAPTURED)}
    trace["phase"][:, 2] = Phase.CAPTURED  # one trial never approaching: left out
    sel = (t >= 2.0) & (t < 6.0)
    err = np.abs(trace["follower_p"][sel, :, 2] - trace["ref_p"][sel, :, 2])
    ok = trace["phase"][sel] <= Phase.TERMINAL
    per_trial = np.array([np.mean(err[ok[:, i], i]) if ok[:, i].any() else np.nan
                          for i in range(3)])
    good = per_trial[np.isfinite(per_trial)]
    old = {"window_s": [2.0, 6.0], "mean_abs_err_down_m": float(np.mean(good)),
           "sd_m": float(np.std(good)), "trials": int(good.size)}
    assert good.size == 2
    assert _text(_window_mean(trace, 2.0, 6.0).to_json()) == _text(old)


def _docking(rng: np.random.Generator) -> tuple[DockingRecord, dict]:
    """A controller's docking experiments as a record and as _docking_experiments's dict."""
    cable = {"repetitions": 1, "with_model": [{"offset_m": 0.36, "result": "dock"}],
             "without_model": [{"offset_m": 0.36, "result": "miss"}]}
    hover: dict = {"offset_m": 0.36, "aperture_m": 0.1, "trials": 4}
    modes = {k: _summary(rng) for k in ("without_model", "with_model", "oracle")}
    hover.update(modes)
    w, m = hover["without_model"], hover["with_model"]
    err_w, err_m = w["terminal_err_down_median_m"], m["terminal_err_down_median_m"]
    hover["terminal_error_reduction_x"] = err_w / max(err_m, 1e-9)
    hover["oracle_mean_source"] = "the field's own mean_acceleration()"
    moving: dict = {"leader_speed_mps": 0.25, "meet_s": 6.0, "hold_s": 5.0, "trials": 2}
    typed_modes = {}
    for key in ("without_model", "with_model"):
        summary = _summary(rng, 2)
        windows = [{"window_s": [4.0, 6.0], "mean_abs_err_down_m": float(rng.random()),
                    "sd_m": None, "trials": 2} for _ in range(2)]
        rec = dict(summary)
        rec["altitude_error_approach"], rec["altitude_error_hold"] = windows
        moving[key] = rec
        typed_modes[key] = MovingMode(summary, *(AltitudeWindow(**w) for w in windows))
    old = {"cable_study": cable, "hover_docking": hover, "moving_leader": moving}
    record = DockingRecord(
        cable, HoverDocking(offset_m=0.36, aperture_m=0.1, trials=4, **modes,
                            terminal_error_reduction_x=hover["terminal_error_reduction_x"],
                            oracle_mean_source=hover["oracle_mean_source"]),
        MovingLeader(leader_speed_mps=0.25, meet_s=6.0, hold_s=5.0, trials=2, **typed_modes))
    return record, old


@pytest.mark.parametrize("full", [False, True], ids=["smoke", "full"])
def test_results_json_is_the_old_results_json(full):
    """The results assembled as _reproduce_into assembled them before the records, against the
    record: a smoke run (no tuned controller, no learnt wrench, no real data) and a full one."""
    rng = np.random.default_rng(3)
    given = {"config": {"sim": {"physics_hz": 500}}, "config_source": "defaults",
             "version": "0.1", "git_commit": None, "git_dirty": None}
    overrides = {} if full else {"planner": {"hold_s": 2.0}}
    machine = "x86_64, 2 cores, Python 3.11.7"
    floor = {"rmse_ratio_to_floor": {"all": 1.2, "interaction": None},
             "error_floor_source": "the field's own mean_acceleration()"}
    curriculum, heldout = {"flights": 6, "stages": []}, {"all": {"n": 10}}
    docking, docking_old = _docking(rng)
    tuned_docking, tuned_old = _docking(rng)
    ours_docking, ours_old = _docking(rng)
    rows = ["paper's controller + paper's model", "ours + deep model"]
    targets, targets_old = _targets(rng, rows + (["tuned + deep model"] if full else []))
    real = {"models": {}} if full else None

    # -- what the old code built (its statements, in its order) --
    results: dict = {
        "aerodock_reproduce": {"quick": not full, "smoke": not full, "seed": 0,
                               **given, "size_overrides": overrides, "machine": machine},
        "units": {"errors": "m", "integrals_over_0.5s": "m*s (errors), m/s (force)",
                  "accelerations": "m/s^2, NED (down positive)", "rates": "fraction"},
    }
    results["learning"] = {"curriculum": curriculum, "heldout": heldout,
                           "heldout_paper_model": heldout, **floor}
    results["sample_efficiency"] = {"minutes": [0.5]}
    results.update(docking_old)
    results["paper_counts"] = {"hover_with_model": {"probability": 0.2}}
    paper = {"source": "Freyja", "q_diag": [1.0, 8.0], "terminal_q_diag": [1.0, 8.0],
             "bias_estimator": "freyja", "command_rate_hz": 50.0, "reference_ff_factor": 0.0,
             "observer_rise_63_s": 0.5}
    results["controllers"] = {"paper": dict(paper)}
    if full:
        results["controllers"]["tuned"] = {"source": "tuned", "q_diag": [2.0],
                                           "terminal_q_diag": [200.0],
                                           "observer_bias_tau_s": 0.2, **tuned_old}
    results["controllers"]["ours"] = {"source": "ours", "accel_observer_tau_s": 0.05,
                                      "terminal_q_diag": [300.0], **ours_old}
    wrench_curriculum = {"flights": 6, "kind": "so2-wrench"} if full else None
    if full:
        results["learning"]["wrench_curriculum"] = wrench_curriculum
    results["targets"] = targets_old
    paper_mean = [_learnt("0.36 m", 0.3)]
    results["targets"]["learnt_mean_paper_model"] = [paper_mean[0][1]]
    wrench_mean = [_learnt("0.36 m", -0.05)] if full else None
    if full:
        results["targets"]["learnt_mean_wrench_model"] = [wrench_mean[0][1]]
    results["controller_costs"] = {"trials": 2}
    results["real_data"] = real
    results["compensation"] = None
    results["timings_s"] = {"curriculum_s": 1.0, "total_s": 9.0}
    results["figures"] = ["figures/cable_trajectories.png"]

    # -- the record --
    record = ReproduceResults(
        aerodock_reproduce=RunHeader(quick=not full, smoke=not full, seed=0, provenance=given,
                                     size_overrides=overrides, machine=machine),
        units=UNITS,
        learning=LearningRecord(curriculum=curriculum, heldout=heldout,
                                heldout_paper_model=heldout, **floor,
                                wrench_curriculum=wrench_curriculum),
        sample_efficiency={"minutes": [0.5]}, docking=docking,
        paper_counts={"hover_with_model": {"probability": 0.2}},
        controllers=ControllersRecord(
            paper=PaperController(**paper),
            tuned=TunedController("tuned", [2.0], [200.0], 0.2, tuned_docking) if full
            else None,
            ours=OursController("ours", 0.05, [300.0], ours_docking)),
        targets=replace(targets, learnt_mean_paper_model=[paper_mean[0][0]],
                        learnt_mean_wrench_model=None if wrench_mean is None
                        else [wrench_mean[0][0]]),
        controller_costs={"trials": 2}, real_data=real, compensation=None,
        timings_s={"curriculum_s": 1.0, "total_s": 9.0},
        figures=["figures/cable_trajectories.png"])
    assert _text(record.to_json()) == _text(results)
    assert record.total_s == 9.0
    assert record.aerodock_reproduce.config_source == "defaults"
    with pytest.raises(FrozenInstanceError):
        record.figures = []  # type: ignore[misc]


def test_paths_are_renamed_inside_records_as_in_the_json(tmp_path):
    built, named = tmp_path / ".building", tmp_path / "out"
    record, _ = _targets(np.random.default_rng(4), ["a row"])
    record = replace(record, provenance=TargetsProvenance(str(built / "data" / "models"),
                                                          str(built), "jet"))
    renamed = _renamed(record, built, named)
    assert _text(renamed.to_json()) == _text(_renamed(record.to_json(), built, named))
    assert renamed.provenance.model == str(Path(named) / "data" / "models")
    assert renamed.provenance.config == str(named)
