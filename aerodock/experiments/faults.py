"""Fault campaigns: one docking campaign per injected fault, beside a baseline without faults.

Each row counts, over the trials the fault struck: docks, safe aborts (aborted with no clearance
violation, no collision and no numerical failure), clearance violations, collisions (rotor
strikes, ground) and trials with a non-finite state (NaN).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from aerodock.config import Config
from aerodock.control.compensation import AccelPredictor, Compensation
from aerodock.mission import MissionSpec, run_campaign
from aerodock.mission.faults import Fault


def fault_campaign(cfg: Config, faults: list[Fault], trials: int, seed: int,
                   compensation: Compensation, predictor: AccelPredictor | None,
                   progress: Callable[[str], None] | None = None) -> list[dict[str, Any]]:
    """One row per fault (and a first row without faults); see the module docstring."""
    rows = []
    for fault in [None, *faults]:
        name = "no fault" if fault is None else fault.name
        if progress is not None:
            progress(name)
        spec = MissionSpec(trials=trials, offset_m=0.36, compensation=compensation, seed=seed,
                           faults=() if fault is None else (fault,))
        res = run_campaign(cfg, spec, predictor)
        hit = res.fault_hit
        safe = res.aborted & ~res.clearance_violation & ~res.rotor_strike & ~res.ground_contact
        safe &= ~res.nan_state
        rows.append({
            "fault": name, "kind": None if fault is None else fault.kind,
            "trials": trials, "struck": int(hit.sum()),
            "docked": int((res.success & hit).sum()),
            "safe_aborts": int((safe & hit).sum()),
            "aborts": int((res.aborted & hit).sum()),
            "missed_or_slipped": int(((res.missed | res.slipped) & hit & ~res.aborted).sum()),
            "sensed_misses": int((res.sensed_missed & hit).sum()),
            "clearance_violations": int((res.clearance_violation & hit).sum()),
            "collisions": int(((res.rotor_strike | res.ground_contact) & hit).sum()),
            "nan_trials": int((res.nan_state & hit).sum()),
            "abort_reasons": res.summary()["abort_reasons"],
        })
    return rows


def rows_markdown(rows: list[dict[str, Any]]) -> str:
    """The fault table as Markdown (as in the README)."""
    lines = ["| fault | struck | docked | missed (gate closed empty) | safe aborts | "
             "clearance violations | collisions | NaN |", "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['fault']} | {r['struck']}/{r['trials']} | {r['docked']} | "
                     f"{r['missed_or_slipped']} | {r['safe_aborts']} | "
                     f"{r['clearance_violations']} | {r['collisions']} | {r['nan_trials']} |")
    return "\n".join(lines)
